"""When `diagnose` must not name its best candidate (issue 16 item 4, issue 14 item 4): the
answer is then "inconclusive", with the reason.

- **A nominal that cannot be this axis.** Jm, K, JL (or the rigid J) not positive: the fit
  describes no physical axis, so no effect measured against it means anything
  (identification.sanity.mislabel_reason names the likely mislabelling: q and q_m swapped, the
  torque's sign). Positions that look like degrees (identification.log.unit_warnings):
  every parameter but the Coulomb frictions is then 180 / pi times off. (A check of the nominal's first mode sqrt(K (1/Jm + 1/JL)) / 2 pi against
  the one measured on the log was tried and left out: with heavy spring damping the
  measurement finds 23.9 Hz where the axis has 3.75 Hz, and a right nominal was overruled.)
- **An extended model that is worse.** The named effect must improve both views: the
  inverse view's error of its equation (after < before), and, when the log replays, the
  forward view's torque error (gain above 1). An extended model that does not replay while
  the nominal does is worse too.
"""

from __future__ import annotations

from jointbench.bench.analysis.diagnose.types import Diagnosis
from jointbench.identification.sanity import mislabel_reason

DEGREES = "look like degrees"   # identification.log.unit_warnings' words for that warning


def nominal_reason(d: Diagnosis) -> str:
    """Why the nominal model is not a physical model of this axis ("" when it is)."""
    p = d.nominal_parameters
    why = mislabel_reason(p)
    bad = [k for k in ("Jm", "K", "JL", "J") if k in p and not p[k] > 0]
    if not why and bad:
        why = ", ".join(f"{k} = {p[k]:.4g}" for k in bad) + " must be positive"
    if not why and any(DEGREES in w for w in d.warnings):
        why = ("the positions look like degrees (warning): every parameter but the Coulomb "
               "frictions scales with the angle unit, 57 times off in degrees")
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
