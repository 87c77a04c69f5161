"""When `diagnose` must not name its best candidate (issue 16 item 4, issue 14 item 4): the
answer is then "inconclusive", with the reason.

- **A nominal that cannot be this axis.** Jm, K, JL (or the rigid J) not positive: the fit
  describes no physical axis, so no effect measured against it means anything
  (identification.sanity.mislabel_reason names the likely mislabelling: q and q_m swapped, the
  torque's sign). With q, the nominal's first mode sqrt(K (1/Jm + 1/JL)) / 2 pi must also
  agree with the one measured on the log (identification.first_mode, +-5 % typically) within
  a factor F1_FACTOR = 3, i.e. K within about 10 times: beyond, K is off by an order of
  magnitude or more and the model is not this axis.
- **An extended model that is worse.** The named effect must improve both views: the
  inverse view's error of its equation (after < before), and, when the log replays, the
  forward view's torque error (gain above 1). An extended model that does not replay while
  the nominal does is worse too.
"""

from __future__ import annotations

import math

from jointbench.bench.analysis.diagnose.types import Diagnosis
from jointbench.identification.first_mode import FirstMode
from jointbench.identification.sanity import mislabel_reason

F1_FACTOR = 3.0


def nominal_reason(d: Diagnosis, mode: FirstMode | None) -> str:
    """Why the nominal model is not a physical model of this axis ("" when it is)."""
    p = d.nominal_parameters
    why = mislabel_reason(p)
    bad = [k for k in ("Jm", "K", "JL", "J") if k in p and not p[k] > 0]
    if not why and bad:
        why = ", ".join(f"{k} = {p[k]:.4g}" for k in bad) + " must be positive"
    if not why and "K" in p and mode is not None and mode.found:
        f1 = math.sqrt(p["K"] * (1 / p["Jm"] + 1 / p["JL"])) / (2 * math.pi)
        ratio = f1 / mode.f1_hz
        if not 1 / F1_FACTOR <= ratio <= F1_FACTOR:
            why = (f"the nominal's first mode sqrt(K (1/Jm + 1/JL)) / 2 pi = {f1:.4g} Hz is "
                   f"{ratio:.3g} times the {mode.f1_hz:.4g} Hz measured on the log (over "
                   f"{F1_FACTOR:g} times off: K = {p['K']:.4g} is off by an order of magnitude "
                   "or more)")
    if not why:
        return ""
    return f"the nominal model is not a physical model of this axis: {why}; no effect is named"


def gain_reason(d: Diagnosis) -> str:
    """Why the named effect's extended model is worse than the nominal ("" when it is not)."""
    c = d.inverse.named
    if c is None:
        return ""
    if not c.after_pct < c.before_pct:
        return (f"{c.effect} does not improve the inverse view ({c.before_pct:.3g} % -> "
                f"{c.after_pct:.3g} %)")
    a, b = d.forward_nominal, d.forward_extended
    if a is not None and b is None:
        return (f"{c.effect}'s extended model does not replay while the nominal does "
                f"({d.forward_note})")
    if a is not None and b is not None and not b.tau_rel_pct < a.tau_rel_pct:
        return (f"{c.effect}'s extended model is worse in the forward view: torque error "
                f"{a.tau_rel_pct:.3g} % -> {b.tau_rel_pct:.3g} % (gain "
                f"{a.tau_rel_pct / b.tau_rel_pct:.2f}x, under 1), though the inverse view "
                f"improves ({c.before_pct:.3g} % -> {c.after_pct:.3g} %): the fit does not "
                "describe the experiment")
    return ""
