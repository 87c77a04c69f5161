"""When `diagnose` must not name its best candidate: the
answer is then "inconclusive", with the reason.

- **A nominal that cannot be this axis.** Jm, K, JL (or the rigid J) not positive: the fit
  describes no physical axis, so no effect measured against it means anything
  (identification.checks.plausibility.mislabel_reason names the likely mislabelling: q and q_m swapped, the
  torque's sign; a swap only when the fit with them swapped is a physical axis, swap_refuted).
  Positions that look like degrees (identification.log.unit_warnings) are a
  warning, never a veto by themselves: a model in degrees is the model in radians rescaled
  (every parameter but the Coulomb frictions 180 / pi times off), and a low-gain position
  loop moves its axis over turns by design. The nominal's first
  mode sqrt(K (1/Jm + 1/JL)) / 2 pi is not checked against the one measured on the log: with
  heavy spring damping the measurement can be far off, and a right nominal overruled.
- **An extended model that is worse.** The named effect must improve the inverse view's
  error of its equation (after < before) and, when the log replays, must not make the
  forward view's torque error worse: a forward gain under 1 overrules it.
  A replay is not noise-free (the logged torque's noise, which no model predicts; a replay
  that drifts off the logged motion, so that a ripple of a hundredth of a radian meets the
  motor angle out of phase), so the reason says whether the loss is beyond this log's spread
  (the segment test of the inverse view, identification.discrepancy.heldout, on
  log(sum e_ext^2 / sum e_nom^2), at its level ALPHA) or within it: the first says the fit
  does not describe the experiment, the second that the replay does not confirm it. An extended model that
  does not replay while the nominal does is worse too. A cause periodic in the motor angle
  (torque_ripple) is judged only on the segments where both replays keep its phase
  (bench.analysis.diagnose.forward.forward_scope); on fewer than a quarter of them the
  forward view cannot judge it, and the diagnosis says so (`forward_note`).
  The gain pools the segments, and a chirp makes their torque differ by orders of magnitude:
  an effect the model does not hold (the stronger of a pair, when only the weaker passed
  its test; a hardening at the mode) can make a few loud segments replay worse and the
  pooled gain fall under 1 while the extended model replays better in most of them. So a
  gain under 1 overrules only when the same segment test does not find the extended model's
  replay better (log(sum e_nom^2 / sum e_ext^2), at ALPHA): the loss is then in the loud
  segments that another cause dominates, and the replay confirms the named one elsewhere.
  Nor does it overrule when the same segment test finds the extended replay's envelope closer
  to the log's (each segment's RMS torque, `envelope_better`): a model with the right
  damping at a lightly damped mode (a torque lag) rings with the log's amplitude but a
  fraction of a cycle off, which a sample-by-sample error penalises against a more damped
  replay that rings less.
  With several named causes, when the model holding them all is rejected against the
  nominal's replay but the model holding all but the last is not, the last cause is judged
  by the same rules against that model's replay (`gain_reason`'s `before`): the weaker of a
  pair is tested against the model holding the stronger, in the forward view as in the
  inverse one (bench.analysis.diagnose.run).
- **"None" from a small part of the experiment.** Rows within reach of a clipped torque sample
  are left out (identification.saturation). When no effect passes and the rows left are under
  half of the experiment's, "none" would speak for the whole experiment from the minority of
  it (a torque lag that drives the loop into its limit leaves a few percent of the rows):
  the inverse view is run again on every row when the clip is the controller's own
  (bench.analysis.diagnose.clipped), and when that names nothing either, or nothing in the
  forward view confirms its reading (a replay that reaches the limit as the log does, or
  for a lag the loop's own stability: every_row_reason), the answer is "inconclusive", with
  the share of clipped samples and each candidate's held-out share in each view.
- **Two effects that mask each other.** No effect passes alone, but the two physical
  candidates that explain the most of the held-out residual pass together against the
  nominal, or one on top of the other (identification.discrepancy.masked): "none" would be
  silence on a discrepancy the log carries; the answer is "inconclusive", with the pair's
  share and every test.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from jointbench.bench.analysis.diagnose.clipped import USABLE_MIN, undecided  # noqa: F401
from jointbench.bench.analysis.diagnose.forward import forward_scope, limit_mismatch
from jointbench.bench.analysis.diagnose.stability import LimitCycle, limit_cycle
from jointbench.bench.sim.controller import Gains, controller_from_log
from jointbench.bench.analysis.diagnose.types import Diagnosis, ForwardView
from jointbench.identification.discrepancy.heldout import ALPHA, segment_sums, segment_t
from jointbench.identification.band_choice import CONSISTENCY_Z
from jointbench.identification.checks.plausibility import mislabel_reason
from jointbench.identification.discrepancy.lag_band import discretisation, jackknife
from jointbench.identification.discrepancy.nominal import nominal
from jointbench.identification.effects.base import spread


def _unphysical(p: dict[str, float]) -> str:
    why = mislabel_reason(p)
    bad = [k for k in ("Jm", "K", "JL", "J") if k in p and not p[k] > 0]
    if not why and bad:
        why = ", ".join(f"{k} = {p[k]:.4g}" for k in bad) + " must be positive"
    return why


def nominal_reason(d: Diagnosis, extended: dict[str, float] | None = None) -> str:
    """Why the nominal model is not a physical model of this axis ("" when it is). A nominal
    that is unphysical only for lack of the named causes passes: `extended`, its parameters
    fitted jointly with them (the model diagnose proposes), is then physical (a spring damping
    as large as the spring's stiffness times the first mode leaves eq. 13 alone with K = 779
    and JL = -0.16 on the prototype, true 2.03e4 and 47; with D, K = 1.69e4 and JL = 40).
    A spring that pushes the wrong way is said to be q and q_m swapped only when the fit with
    them swapped is a physical axis (swap_refuted)."""
    p = d.nominal_parameters
    why = _unphysical(p)
    if why and extended and not _unphysical({**p, **extended}):
        why = ""
    if not why:
        return ""
    why = swap_refuted(d) or why
    return f"the nominal model is not a physical model of this axis: {why}; no effect is named"


def swap_refuted(d: Diagnosis) -> str:
    """Why the wrong-way spring of d's nominal is not read as q and q_m swapped ("" when it
    is, or when the nominal's fault is another). Swapped columns make eq. 13 fit the link
    side as the motor's, and the fit with them swapped back is the axis, physical; when that
    fit is no physical axis either, the log does not hold the spring as eq. 13 has it (a
    deflection qm - q that a damping far beyond the spring's stiffness times the first mode
    holds to a few encoder counts: its columns are quantisation, and K and JL come out of the
    fit with either sign), and naming a mislabelling would be a confident wrong answer."""
    p = d.nominal_parameters
    if not ("K" in p and p.get("Jm", 0.0) > 0 and (p["K"] <= 0 or p.get("JL", 1.0) <= 0)):
        return ""
    log = d.log
    if log.q is None:
        return ""
    try:
        every_row = d.clipped is not None and bool(d.clipped.named_by)
        other = nominal(dataclasses.replace(log, q=log.q_m, q_m=log.q), d.settings,
                        limit_applied=every_row)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return ""
    s = {n: float(v) for n, v in zip(other.names, other.X) if n in ("Jm", "K", "JL")}
    if all(s.get(k, 1.0) > 0 for k in ("Jm", "K", "JL")):
        return ""
    return (f"K = {p['K']:.4g}, JL = {p.get('JL', math.nan):.4g} with Jm = {p['Jm']:.4g}: a "
            f"spring cannot push the wrong way, and with q and q_m swapped the fit is no "
            f"physical axis either (Jm = {s.get('Jm', math.nan):.4g}, K = "
            f"{s.get('K', math.nan):.4g}, JL = {s.get('JL', math.nan):.4g}): the log does not "
            "hold the spring's deflection qm - q as eq. 13 has it")


def gain_reason(d: Diagnosis, before: ForwardView | None = None) -> str:
    """Why the named effect's extended model is worse than the nominal ("" when it is not).
    `before`: the replay of the model holding every named cause but the last (d.causes[:-1]);
    the last cause is then judged against it, as its inverse test was against the model
    holding the causes before it, not against the nominal's replay: beside a stronger cause
    that the nominal lacks, the nominal's replay misses that cause's part of the torque
    too, and the two models' difference there says nothing of the last one."""
    c = d.inverse.named if before is None else d.causes[-1]
    if c is None:
        return ""
    if not c.after_pct < c.before_pct:
        return (f"{c.effect} does not improve the inverse view ({c.before_pct:.3g} % -> "
                f"{c.after_pct:.3g} %)")
    a, b = (d.forward_nominal if before is None else before), d.forward_extended
    effects = [x.effect for x in d.causes]
    if before is not None:
        model = (f"{c.effect}'s extended model, against the one holding "
                 f"{', '.join(effects[:-1])},")
    elif len(effects) > 1:
        model = f"the extended model with {', '.join(effects)}"
    else:
        model = f"{c.effect}'s extended model"
    if a is not None and b is None:
        return (f"{model} does not replay while the "
                f"{'nominal' if before is None else 'other'} does ({d.forward_note})")
    if a is not None and b is not None:
        # a torque periodic in q_m: only where the replays keep its phase
        scope = forward_scope(d, a)
        if not scope.judged:
            return ""              # the forward view cannot judge it (d.forward_note says so)
        t, p = forward_worse(d.log.tau_m, a.tau_m, b.tau_m, scope.keep)
        ea, eb, where = a.tau_rel_pct, b.tau_rel_pct, ""
        if scope.keep is not None:
            ea, eb = (_error_pct(d.log.tau_m, x.tau_m, scope.keep) for x in (a, b))
            where = f" on the {int(scope.keep.sum())} segments it judges"
        gain = f"gain {ea / eb:.2f}x"
        improves = f"though the inverse view improves ({c.before_pct:.3g} % -> {c.after_pct:.3g} %)"
        if p < ALPHA:
            return (f"{model} is worse in the forward view{where}: torque "
                    f"error {ea:.3g} % -> {eb:.3g} % ({gain}; worse over the "
                    f"experiment's segments with t = {t:.3g}, p = {p:.2g} < {ALPHA:g}), "
                    f"{improves}: the fit does not describe the experiment")
        if not eb < ea and not forward_worse(d.log.tau_m, b.tau_m, a.tau_m,
                                             scope.keep)[1] < ALPHA \
                and not envelope_better(d.log.tau_m, a.tau_m, b.tau_m, scope.keep)[1] < ALPHA:
            # no named effect whose extended model has a gain below 1, even when the
            # replay's noise could explain the loss: the replay does not confirm it; unless
            # its replay is significantly better segment by segment, sample by sample or in
            # its envelope (module docstring)
            return (f"{model} does not improve the forward view{where}: "
                    f"torque error {ea:.3g} % -> {eb:.3g} % ({gain}, under 1; "
                    f"within the experiment's spread, t = {t:.3g}, p = {p:.2g}), {improves}: "
                    "the replay does not confirm it")
    return ""


def _error_pct(tau: np.ndarray, replayed: np.ndarray, keep: np.ndarray) -> float:
    """The replay's torque error [% RMS of the logged torque] over the kept segments."""
    tau = np.asarray(tau, float)
    num, den = segment_sums((np.asarray(replayed) - tau) ** 2), segment_sums(tau ** 2)
    return 100.0 * float(np.sqrt(num[keep].sum() / den[keep].sum()))


def forward_worse(tau: np.ndarray, nominal: np.ndarray, extended: np.ndarray,
                  keep: np.ndarray | None = None) -> tuple[float, float]:
    """Is the extended model's replayed torque significantly worse than the nominal's? The
    segments' log-ratios log(sum e_ext^2 / sum e_nom^2) (e = replayed - logged torque, the
    held-out test's SEGMENTS contiguous segments, identification.discrepancy.heldout; only
    those `keep` marks when given): t of their mean with the successive-difference spread,
    and its one-sided p-value."""
    tau = np.asarray(tau, float)
    h0 = segment_sums((np.asarray(nominal) - tau) ** 2)
    h1 = segment_sums((np.asarray(extended) - tau) ** 2)
    ok = (h0 > 0) & (h1 > 0) & (True if keep is None else keep)
    return segment_t(np.log(h1[ok] / h0[ok]))


def envelope_better(tau: np.ndarray, nominal: np.ndarray, extended: np.ndarray,
                    keep: np.ndarray | None = None) -> tuple[float, float]:
    """Is the extended model's replayed torque significantly closer to the logged one in its
    envelope than the nominal's? Per segment (the held-out test's SEGMENTS contiguous
    segments; only those `keep` marks when given) the replay's RMS torque against the log's,
    e = (rms replayed - rms logged)^2, and the segment test (heldout.segment_t) on
    log(e_nom / e_ext): t and its one-sided p-value. The RMS over a segment does not depend
    on the replay's phase: near a lightly damped mode the phase of a replay moves by about
    1 / zeta radians per relative error of the mode's frequency, so a model with the right
    damping (a torque lag, which takes phase margin from the loop) rings with the log's
    amplitude a fraction of a cycle off, and its sample-by-sample error, 2 (1 - rho) of the
    segment's power at a correlation rho, exceeds that of a more damped replay that rings
    less. A replay's envelope that is no closer to the log's leaves that loss standing."""
    tau = np.asarray(tau, float)
    n = segment_sums(np.ones(len(tau)))
    rms = [np.sqrt(segment_sums(np.asarray(x, float) ** 2) / np.maximum(n, 1))
           for x in (tau, nominal, extended)]
    e0, e1 = (rms[1] - rms[0]) ** 2, (rms[2] - rms[0]) ** 2
    ok = (e0 > 0) & (e1 > 0) & (True if keep is None else keep)
    return segment_t(np.log(e0[ok] / e1[ok]))


def every_row_reason(d: Diagnosis) -> str:
    """Why causes named on every row of a clipped log (bench.analysis.diagnose.clipped) are
    not named ("" when they stand): that view takes the torque at tau_max as the one the
    axis received, which is what the closed-loop replay assumes too (it applies the same
    clip); when the nominal or the extended model does not replay (it saturates far beyond
    the log, diverges, or the log describes no controller), or when the extended model's
    replay does not reach the limit more as the log does than the nominal's (the share of
    samples at tau_max, segment by segment: forward.limit_mismatch), and, for a named torque
    lag, the loop linearised with it is not unstable where the nominal's is stable at the
    frequency the log's clipped torque oscillates at (loop_cycle), nothing confirms that
    reading of the log: a torque clipped after the fact (a sensor's range) reads as an
    effect there."""
    views = getattr(d, "clipped", None)
    if views is None or not views.named_by or not d.inverse.causes:
        return ""
    a, b = d.forward_nominal, d.forward_extended
    head = (f"{d.inverse.causes[0].effect} is named only on every row, the torque at tau_max "
            f"taken as the one applied, and the closed-loop replay that applies it so does "
            f"not confirm that reading")
    if a is None or b is None:
        why = d.forward_note or "the forward view was not run"
        return f"{head} ({why})"
    if replay_at_limit(d):
        return ""
    ma, mb = (limit_mismatch(d.log, x.tau_m) for x in (a, b))
    cycle = loop_cycle(d)
    if cycle is not None and cycle.confirms:
        return ""
    why = f"; {cycle.text()}" if cycle is not None else ""
    return (f"{head} (the extended model's replay reaches the limit no more as the log does "
            f"than the nominal's: {mb:.3g} % of the samples off, against {ma:.3g} %{why})")


def replay_at_limit(d: Diagnosis) -> bool:
    """The extended model's replay reaches the limit more as the log does than the
    nominal's (forward.limit_mismatch, both replays run)."""
    a, b = d.forward_nominal, d.forward_extended
    return (a is not None and b is not None
            and limit_mismatch(d.log, b.tau_m) < limit_mismatch(d.log, a.tau_m))


def cycle_only(d: Diagnosis) -> bool:
    """The every-row reading of a clipped log stands on the loop's stability alone: a lag
    named on every row first or after the first view's causes only (lag_at), confirmed by
    loop_cycle and not by a replay at the limit. In a
    limit cycle every state is periodic in time, so the residual the lag's model leaves at
    the cycle is a function of the motor angle and of the deflection too, which a later
    cause's column can take (a torque ripple of a few periods per cycle); the replay that
    would tell them apart does not reach the cycle, and the loop's stability speaks of the
    lag alone: the causes after it are not named (bench.analysis.diagnose.run)."""
    if d.overruled or replay_at_limit(d):
        return False
    cycle = loop_cycle(d)
    return cycle is not None and cycle.confirms


def lag_at(d: Diagnosis) -> int | None:
    """Where a torque lag stands among the causes named on every row, when every cause before
    it is one the first view names on its own rows (clipped.stopped_short: those stand
    without the every-row reading) or one that passes again on top of the model holding the
    lag and the other named causes (clipped.held_before_lag: the set the log supports
    together); None when there is no such lag."""
    views = getattr(d, "clipped", None)
    names = [c.effect for c in d.inverse.causes]
    if views is None or "torque_lag" not in names:
        return None
    i = names.index("torque_lag")
    held = set(views.first_named) | {e for e, _, _ in views.before_lag}
    return i if set(names[:i]) <= held else None


def loop_cycle(d: Diagnosis) -> LimitCycle | None:
    """The loop's linearisation with the named lag (bench.analysis.diagnose.stability) on a
    log whose causes rest on every row; None when none is named there, or no lag, or the
    controller is not the PI cascade. A replay from rest need not reach a limit cycle that
    the lag makes the loop grow into (stability's module docstring): the extended loop
    unstable where the nominal's is stable, at the frequency of the log's clipped
    oscillation, confirms the every-row reading as a replay at the limit does. That
    frequency is asked within the band the fitted lag and spring damping allow
    (fitted_spread)."""
    views = getattr(d, "clipped", None)
    if views is None or not views.named_by or lag_at(d) is None:
        return None
    try:
        gains = controller_from_log(d.log)
    except ValueError:   # LogError included: no controller described
        return None
    if not isinstance(gains, Gains):
        return None
    return limit_cycle(d.log, d.nominal_parameters, d.extended_parameters,
                       gains.kp, gains.kv, gains.ki, fitted_spread(d))


def fitted_spread(d: Diagnosis) -> dict[str, float]:
    """The half-width of the range the named lag's T and spring damping's D may take: the
    fit's own standard error at CONSISTENCY_Z (band_choice: the level at which two estimates
    of one value are said to agree), the delete-a-fold jackknife of the folds' preferred T
    (lag_band.jackknife) plus what the led columns' discretisation allows T
    (lag_band.discretisation), and of the folds' fits of D (effects.base.spread)."""
    out: dict[str, float] = {}
    for c in d.inverse.causes:
        if c.effect == "torque_lag" and c.fold_values:
            T = float(c.parameters.get("lag_s", 0.0))
            out["lag_s"] = (CONSISTENCY_Z * jackknife(c.fold_values)
                            + discretisation(d.settings, T))
        elif c.effect == "spring_damping":
            out["D"] = CONSISTENCY_Z * spread(c.fold_fits, lambda v: v["D"])
    return {k: v for k, v in out.items() if np.isfinite(v)}


def with_clipping(d: Diagnosis) -> str:
    """The reason of an inconclusive answer on a clipped log, with the share of clipped
    samples and each candidate's held-out share in each view (clipped.ClippedViews)."""
    views = d.clipped
    if not d.overruled or views is None or views.text() in d.overruled:
        return d.overruled
    return f"{d.overruled}; {views.text()}"


def masked_reason(d: Diagnosis) -> str:
    """Why "none" cannot be said of this log ("" when it can, or when a cause is named): no
    effect passes alone, but the two that explain the most pass together or one on top of
    the other (identification.discrepancy.masked)."""
    pair = d.inverse.masked
    if d.inverse.causes or pair is None or not pair.passes:
        return ""
    return f"{pair.describe()}: the log carries a discrepancy that no one cause names"


def clipped_reason(d: Diagnosis) -> str:
    """Why "none" cannot be said of this log ("" when it can, or when a cause is named): the
    rows left after the clipped torque's are under USABLE_MIN of the experiment's."""
    if not undecided(d.inverse):
        return ""
    keep = d.inverse.nominal.sig.keep
    why = (f"only {int(keep.sum())} of {len(keep)} regression rows "
           f"({100 * keep.mean():.3g} %) are out of reach of the clipped torque samples: no "
           f"effect passes on them, which does not say that the experiment has none")
    return why
