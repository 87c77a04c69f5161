"""Forward view of `diagnose`: the nominal and the extended MuJoCo axes, built from the
parameters identified on the log, replay the logged experiment in closed loop (docs/controller.md,
bench.replay) and are compared with the measured q_m, q and tau_m.

The named effect goes into the MJCF where MuJoCo expresses it (bench.effects.write_extended,
each effect's module there): backlash as a dead-band tendon, spring damping as tendon damping,
hardening as a stacked dead-band tendon, link Coulomb friction as frictionloss, torque lag as
an exact first-order filter actuator, gravity as the link's mass and centre of mass, an offset
as a passive constant-bias actuator. Torque ripple and asymmetric friction depend on the
motor angle and velocity in ways no MuJoCo actuator bias does: they are written as custom
numerics (`X_ripple` = amplitude, period, phase; `X_asymmetry` = a, FVm, FSm) that the bench
loop applies (bench.effects.loop_effects_from_model), in the replay and in `jointbench simulate`.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Callable

import mujoco
import numpy as np

from jointbench.bench.analysis.diagnose.types import Diagnosis, ForwardView
from jointbench.bench.effects import loop_effects_from_model, write_effects
from jointbench.bench.effects.base import positive_part as _pos
from jointbench.bench.sim import nominal as nominal_axes
from jointbench.bench.sim.friction import integrator_for_log, timeconst_for_log
from jointbench.bench.sim.controller import controller_from_log, has_controller
from jointbench.bench.sim.replay import ReplayError, replay
from jointbench.identification.discrepancy import SEGMENTS
from jointbench.identification.discrepancy import nominal as nominal_rows, predict, with_parameters
from jointbench.identification.discrepancy.heldout import ALPHA, segment_sums, segment_t
from jointbench.identification.effects import EFFECTS
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log
from jointbench.identification.log.read import position_quantum
from jointbench.bench.sim.plant_keys import PLANT_INTEGRATOR_KEY, plant_steps
from jointbench.identification.saturation import CLIP_RELATIVE


def _axis_name(d: Diagnosis) -> str:
    return d.log.meta.get("joint") or "axis1"


def build_spec(d: Diagnosis, extended: bool, substeps: int = 1) -> mujoco.MjSpec:
    """The nominal (extended=False) or extended MjSpec of the diagnosed axis, with MuJoCo's
    timestep the log's period over `substeps`."""
    log = d.log
    name = _axis_name(d)
    p = dict(d.nominal_parameters)
    causes = d.causes if extended else ()
    if causes:
        p.update(d.extended_parameters)
    common = dict(timestep=log.ts / substeps, tau_max=log.meta_float("tau_max"),
                  gravity=log.gravity, prismatic=log.prismatic, name=name,
                  integrator=integrator_for_log(log))
    if "K" in d.nominal_parameters:
        # FS: the nominal's link Coulomb friction (eq. 13); the extended model's is refitted.
        FS = _pos(p, "FS")
        spec = nominal_axes.two_mass_axis(
            Jm=p["Jm"], FVm=_pos(p, "FVm"), FSm=_pos(p, "FSm"), K=p["K"], JL=p["JL"],
            FV=_pos(p, "FV"), FS=FS, MX=0.0 if log.prismatic else p.get("MX", 0.0),
            MY=0.0 if log.prismatic else p.get("MY", 0.0),
            friction_timeconst=friction_timeconst(log), **common)
        K = p["K"]
    else:
        spec = nominal_axes.rigid_axis(J=p["J"], FV=_pos(p, "FV"), FS=_pos(p, "FS"),
                                       offset=0.0, **common)
        K = 0.0
    if causes:   # every named cause, in order: one (effect, parameters) pair each
        # d.extended_parameters holds every cause's parameters from one joint fit
        write_effects(spec, name, [(c.effect, p) for c in causes], K)
    return spec


def friction_timeconst(log: Log) -> float:
    """The Coulomb frictions' time constant of the replayed axis [s]: the log's own (a
    jointbench log carries its MuJoCo model's: arm6 0.25 ms), else the nominal default
    (bench.sim.nominal.SOLREF_FRICTION, the prototype's 2 ms)."""
    return timeconst_for_log(log, nominal_axes.SOLREF_FRICTION[0])[0]


def plant_substeps(log: Log) -> int:
    """MuJoCo steps per log sample that integrate the replay as the log's plant was integrated.
    A log of a MuJoCo plant (its `integrator` one of MuJoCo's, mjINT_...) gives its own
    `substeps`: its discretisation is its physics (the bench's one RK4 step a sample). Any
    other log (a measured axis, another simulator) comes from a continuous plant: steps no
    longer than the friction constraint's time constant, which a longer step does not resolve
    (the soft constraint then chatters through the stick phases)."""
    if _mujoco_plant(log):
        steps = plant_steps(log)
        if steps is not None and steps >= 1:
            return int(steps)
    return max(1, math.ceil(log.ts / friction_timeconst(log) - 1e-9))


def replay_substeps(d: Diagnosis, extended: bool) -> int:
    """MuJoCo steps per log sample for the model's replay: the plant's (`plant_substeps`), or
    for a named torque lag as short as the log's half period, enough that the filter written
    half a step shorter (bench.effects.torque_lag.extend) keeps a positive time constant of at
    least half a step, where RK4 on it is stable; otherwise a lag under ts / 2 (a bench lag run
    with substeps, a drive's fast current loop) would be written as no lag at all."""
    n = plant_substeps(d.log)
    lag = d.extended_parameters.get("lag_s", 0.0) if extended else 0.0
    if not (lag > 0 and any(c.effect == "torque_lag" for c in d.causes)):
        return n
    return max(n, math.ceil(d.log.ts / lag))


def replay_tau0(log: Log) -> float | None:
    """The integrator's initial state of a replay of `log` (None: the logged tau_m[0])."""
    # With ki = 0 there is no integrator: docs/controller.md's I[-1] = tau_m[0] would hold the first
    # logged torque for ever, which is only right for a log starting at rest (EMPS starts in
    # motion: 89 N held, a constant 65 um off). A P-only drive starts with I = 0.
    return 0.0 if log.meta_float("ki") == 0 else None


def _view(d: Diagnosis, spec: mujoco.MjSpec, disturbance: np.ndarray | None = None,
          disturbance_at: str = "link", substeps: int = 1) -> ForwardView:
    log = d.log
    model, axis = nominal_axes.compile_axis(spec, "<diagnosis>")
    loop = loop_effects_from_model(model, axis.name)
    r = replay(model, axis, log, disturbance=disturbance, disturbance_at=disturbance_at,
               tau0=replay_tau0(log), loop=loop, substeps=substeps)
    e_qm = float(np.sqrt(np.mean((r.q_m - log.q_m) ** 2)))
    motion = float(np.sqrt(np.mean((log.q_m - np.mean(log.q_m)) ** 2)))
    e_tau = 100 * float(np.linalg.norm(r.tau_m - log.tau_m) / np.linalg.norm(log.tau_m))
    e_q = None
    if r.q is not None and log.q is not None:
        e_q = float(np.sqrt(np.mean((r.q - log.q) ** 2)))
    return ForwardView(q_m_rms=e_qm, q_rms=e_q, tau_rel_pct=e_tau,
                       q_m_rel_pct=100 * e_qm / motion if motion > 0 else float("nan"),
                       t=r.t, q_m=r.q_m, q=r.q, tau_m=r.tau_m)


def add_forward_view(d: Diagnosis, say: Callable[[str], None],
                     nominal_view: ForwardView | None = None) -> Diagnosis:
    """Replay the nominal (unless `nominal_view` is its replay already) and (when an effect
    is named) the extended axis."""
    log = d.log
    if log.q_ref is None or not has_controller(log):
        return dataclasses.replace(d, forward_note=_motor_driven_note(d, no_replay_note(log)))
    fn = nominal_view
    try:
        if fn is None:
            say("forward view: nominal replay")
            n = replay_substeps(d, extended=False)
            fn = _view(d, build_spec(d, extended=False, substeps=n), substeps=n)
    except (ReplayError, ValueError) as err:
        return dataclasses.replace(d, forward_note=f"not replayed: {err}")
    fe, note = None, ""
    if d.named is not None:
        say(f"forward view: extended replay ({d.named_cause})")
        try:
            n = replay_substeps(d, extended=True)
            fe = _view(d, build_spec(d, extended=True, substeps=n), substeps=n)
        except (ReplayError, ValueError) as err:
            note = f"extended model not replayed: {err}"
    d = dataclasses.replace(d, forward_nominal=fn, forward_extended=fe, forward_note=note)
    if fe is not None:
        d = dataclasses.replace(d, forward_note=forward_scope(d).note)
    return d


def no_replay_note(log: Log) -> str:
    """Why the closed-loop replay cannot run: no q_ref, a controller the metadata names but
    does not describe completely (controller_from_log's reason, e.g. the missing tau_max),
    or no controller at all."""
    if log.q_ref is None:
        return "not replayed: the log has no q_ref column (the closed loop's reference)"
    if "controller" in log.meta:
        try:
            controller_from_log(log)
        except ValueError as err:     # LogError included
            return f"not replayed: {getattr(err, 'message', None) or err}"
    return ("not replayed: the log's metadata does not describe the controller (the PI "
            "cascade's kp, kv, ki or a position loop's `controller` and pid_kp..., "
            "docs/controller.md)")


def _motor_driven_note(d: Diagnosis, note: str) -> str:
    """`note`, and the motor-driven view (identification.motor_driven: the measured q_m
    drives the nominal model, no controller needed) when the log has q and the nominal is a
    two-mass model."""
    from jointbench.identification.motor_driven import motor_driven_view

    p = d.nominal_parameters
    if d.log.q is None or "K" not in p:
        return note
    try:
        view = motor_driven_view(d.log, p, d.settings.decimated_cutoff_hz)
    except ValueError as err:
        return f"{note}; the motor-driven view did not run: {err}"
    return f"{note}; {view.text()}"


# A torque periodic in the motor angle (torque_ripple, amplitude A, period p) replayed with a
# phase error delta ~ N(0, s^2) correlates with the logged one by rho = exp(-s^2 / 2) on
# average; the replayed ripple then leaves E (r - r')^2 = A^2 (1 - rho) of it, against A^2 / 2
# without it: adding it lowers the error only for rho > 1/2, s < sqrt(2 ln 2) = 1.18 rad.
# Where the replay is farther off, the forward view cannot tell a right ripple from a wrong one.
PHASE_LIMIT = math.sqrt(2.0 * math.log(2.0))   # rad
MIN_JUDGED = SEGMENTS // 4   # segments the forward view must judge (else: it cannot judge)


@dataclasses.dataclass(frozen=True)
class ForwardScope:
    """Where the forward view can judge the extended model: `keep` the SEGMENTS contiguous
    segments of the log it judges (None: all of them), `judged` False when it cannot judge at
    all (fewer than MIN_JUDGED segments), `note` what the report says ("" when all judged)."""

    keep: np.ndarray | None
    judged: bool
    note: str


def _segment_rms(x: np.ndarray) -> np.ndarray:
    count = segment_sums(np.ones(len(x)))
    return np.sqrt(segment_sums(x ** 2) / np.maximum(count, 1))


def phase_errors(log_q_m: np.ndarray, replays: list[np.ndarray], period: float,
                 held: bool = False) -> np.ndarray:
    """Per segment, the RMS phase error [rad] of a torque of spatial `period` in the motor
    angle as the replays apply it against the one the logged motion carried:
    2 pi / period x sqrt(e^2 + (dq / 2)^2), e the worst replay's RMS motor-angle error in the
    segment, dq the logged motion per sample: the replay holds the torque of the sample's
    angle over the sample (bench.sim.loop), a continuous one follows the angle through it,
    half a sample's motion off on average. `held`: the log's plant held it too (a jointbench
    log of a MuJoCo plant, whose bench loop is the replay's): dq counts 0."""
    q = np.asarray(log_q_m, float)
    e = np.max([_segment_rms(np.asarray(r, float) - q) for r in replays], axis=0)
    half = 0.0 if held else _segment_rms(0.5 * np.diff(q, append=q[-1]))
    return 2.0 * math.pi / period * np.sqrt(e ** 2 + half ** 2)


def _mujoco_plant(log: Log) -> bool:
    """A jointbench log of a MuJoCo plant (its `integrator` one of MuJoCo's, mjINT_...)."""
    return log.meta.get(PLANT_INTEGRATOR_KEY, "").strip().startswith("mjINT_")


def follows(tau: np.ndarray, replayed: np.ndarray) -> bool:
    """Does a replayed torque follow the logged one better than a zero torque, beyond this
    log's spread? The segment test of identification.discrepancy.heldout on log(sum tau^2 /
    sum (replayed - tau)^2), at its level ALPHA."""
    tau = np.asarray(tau, float)
    h0, h1 = segment_sums(tau ** 2), segment_sums((np.asarray(replayed) - tau) ** 2)
    ok = (h0 > 0) & (h1 > 0)
    return segment_t(np.log(h0[ok] / h1[ok]))[1] < ALPHA


def _tau_max(log: Log) -> float | None:
    try:
        value = float(log.meta.get("tau_max", "nan"))
    except ValueError:
        return None
    return value if value > 0 else None


def before_limit(log: Log) -> np.ndarray | None:
    """The segments before the first one where the logged torque reaches the controller's
    limit tau_max (None when it never does). Once the loop is clipped it is no longer
    linear: the integrator winds up at the limit, and a replay that reaches it a sample
    earlier or later than the log is left in another state; near the loop's stability limit
    (a torque lag) that difference grows instead of decaying. Past that point the replays
    follow the clip's history, not the model's, and their torque error judges neither model.
    A replay that reaches the limit where the log does not is the model's own doing and
    stays judged."""
    tau_max = _tau_max(log)
    if tau_max is None:
        return None
    at = np.abs(np.asarray(log.tau_m, float)) >= tau_max * (1 - CLIP_RELATIVE)
    hit = segment_sums(at.astype(float)) > 0
    if not hit.any():
        return None
    return np.arange(SEGMENTS) < int(np.argmax(hit))


def limit_mismatch(log: Log, replayed: np.ndarray) -> float:
    """How differently a replay reaches the controller's limit than the log [% of the
    samples]: the sum over the SEGMENTS segments of |replayed - logged count of samples at
    tau_max|, over the log's length (nan without tau_max). A limit cycle's clips fall at its
    own phase, so they are counted per segment, not matched sample by sample."""
    tau_max = _tau_max(log)
    if tau_max is None:
        return math.nan
    bar = tau_max * (1 - CLIP_RELATIVE)
    logged = segment_sums((np.abs(np.asarray(log.tau_m, float)) >= bar).astype(float))
    replay_at = segment_sums((np.abs(np.asarray(replayed, float)) >= bar).astype(float))
    return 100.0 * float(np.abs(replay_at - logged).sum()) / len(log.tau_m)


def forward_scope(d: Diagnosis, against: ForwardView | None = None) -> ForwardScope:
    """The segments where the forward view can judge the named causes: those before the loop
    first reaches its torque limit (before_limit), and, when a cause is periodic in the motor
    angle, those where both replays keep its phase (phase_errors < PHASE_LIMIT); none when
    they are fewer than MIN_JUDGED. `against`: the replay the extended one is judged against
    (d.forward_nominal when None)."""
    scope = _phase_scope(d, against)
    a, b = d.forward_nominal if against is None else against, d.forward_extended
    if not scope.judged or a is None or b is None:
        return scope
    before = before_limit(d.log)
    if before is not None:
        keep = before if scope.keep is None else before & scope.keep
        how = (f"the loop reaches its torque limit tau_max = {_tau_max(d.log):g} in segment "
               f"{int(np.argmin(before)) + 1} of {SEGMENTS}: the replays are judged before "
               f"it, in {int(keep.sum())} segments")
        scope = _narrowed(keep, how, scope)
        if not scope.judged:
            return scope
    return _reproduced_scope(d, a, scope)


def start_moved(log: Log) -> Log:
    """`log` with its replay's start moved by half a step of the position encoder the replay
    starts from (the link's when logged, else the motor's; identification.log.read.
    position_quantum, measured on the log): a rounding encoder cannot tell the two starts
    apart. Without a measurable step, by the text's precision (12 digits)."""
    name = "q" if log.q is not None else "q_m"
    x = np.asarray(getattr(log, name), float)
    step = position_quantum(x) or 1e-9 * max(1.0, float(np.nanmax(np.abs(x))))
    moved = x.copy()
    moved[0] += 0.5 * step
    return dataclasses.replace(log, **{name: moved})


_SPREADS: dict[int, tuple[ForwardView, np.ndarray | None]] = {}


def start_spread(d: Diagnosis) -> np.ndarray | None:
    """Per segment, the RMS difference of the extended model's replayed torque from the same
    model's replay from a start the log cannot tell apart (start_moved); None when that
    replay does not run. Remembered for the replay it is of (forward_scope is asked for it
    by the report's note and by the verdict)."""
    b = d.forward_extended
    held = _SPREADS.get(id(b))
    if held is not None and held[0] is b:
        return held[1]
    try:
        moved = dataclasses.replace(d, log=start_moved(d.log))
        n = replay_substeps(moved, extended=True)
        other = _view(moved, build_spec(moved, extended=True, substeps=n), substeps=n)
        spread = _segment_rms(np.asarray(other.tau_m) - np.asarray(b.tau_m))
    except (ReplayError, ValueError):
        spread = None
    if len(_SPREADS) > 16:
        _SPREADS.clear()
    _SPREADS[id(b)] = (b, spread)
    return spread


def _reproduced_scope(d: Diagnosis, a: ForwardView, scope: ForwardScope) -> ForwardScope:
    """`scope` up to the first segment where the extended replay differs from its replay from
    an indistinguishable start (start_spread) as much as from the log: from there on the log
    is no closer to the replay than another start of the same model is (a link that floats
    in a dead band between impacts, whose phase a closed loop does not restore), and the
    replay's torque error says nothing of the model. Asked only when the extended replay is
    not better than `a` over `scope` (the veto's case): an extended replay that is better
    needs no more segments left out."""
    b, log = d.forward_extended, d.log
    if getattr(log, "q_ref", None) is None or not scope.judged:
        return scope
    keep = np.ones(SEGMENTS, bool) if scope.keep is None else scope.keep
    tau = np.asarray(log.tau_m, float)
    ea, eb = (segment_sums((np.asarray(x.tau_m) - tau) ** 2)[keep].sum() for x in (a, b))
    if eb < ea:
        return scope
    spread = start_spread(d)
    if spread is None:
        return scope
    off = (spread > 0) & (spread >= _segment_rms(np.asarray(b.tau_m) - tau))
    if not off.any():
        return scope
    at = int(np.argmax(off))
    keep = keep & (np.arange(SEGMENTS) < at)
    how = (f"the extended replay from a start half an encoder step away differs from itself "
           f"as much as from the log from segment {at + 1} of {SEGMENTS} on: the replays are "
           f"judged before it, in {int(keep.sum())} segments")
    return _narrowed(keep, how, scope)


def _narrowed(keep: np.ndarray, how: str, scope: ForwardScope) -> ForwardScope:
    """The scope judging the segments `keep` (`how` says why, after `scope`'s own note), or
    none when they are fewer than MIN_JUDGED: the causes are then named on the inverse view
    alone."""
    how = f"{how}; {scope.note}" if scope.note else how
    if keep.sum() < MIN_JUDGED:
        return ForwardScope(None, False, f"the forward view cannot judge the named causes on "
                            f"this log: {how}, under {MIN_JUDGED}; they are named on the "
                            "inverse view alone")
    return ForwardScope(keep, True, f"the forward view judges the named causes where {how}")


def _phase_scope(d: Diagnosis, against: ForwardView | None = None) -> ForwardScope:
    """forward_scope without the torque limit: every segment unless a cause is periodic in
    the motor angle; then those where both replays keep its phase."""
    a, b = d.forward_nominal if against is None else against, d.forward_extended
    if a is not None and b is not None and not follows(d.log.tau_m, a.tau_m):
        # a nominal replay no closer to the logged torque than a zero torque follows nothing
        # of the experiment: the extended one's error beside it judges nothing either, and
        # would overrule a cause the inverse view found
        return ForwardScope(None, False, (
            f"the forward view cannot judge the named causes on this log: the nominal's replay "
            f"does not follow it (torque error {a.tau_rel_pct:.3g} %, not significantly under "
            f"a zero torque's 100 %); they are named on the inverse view alone"))
    periods = [(c.effect, d.extended_parameters.get(EFFECTS[c.effect].period, 0.0))
               for c in d.causes if EFFECTS[c.effect].period]
    periods = [(e, p) for e, p in periods if p > 0]
    if a is None or b is None or not periods:
        return ForwardScope(None, True, "")
    effect, period = min(periods, key=lambda x: x[1])
    held = _mujoco_plant(d.log)
    s = phase_errors(d.log.q_m, [a.q_m, b.q_m], period, held)
    motion = "" if held else " and half a sample's motion"
    keep = s < PHASE_LIMIT
    how = (f"the replays keep the phase of {effect} (period {period:.4g}) within "
           f"{PHASE_LIMIT:.2f} rad RMS (position error{motion}, against the period) in "
           f"{int(keep.sum())} of {SEGMENTS} segments of the experiment (median phase error "
           f"{float(np.median(s)):.2f} rad)")
    if keep.sum() < MIN_JUDGED:
        return ForwardScope(None, False, f"the forward view cannot judge {effect} on this log: "
                            f"{how}, under {MIN_JUDGED}; {effect} is named on the inverse view "
                            "alone")
    if keep.all():
        return ForwardScope(None, True, "")
    return ForwardScope(keep, True, f"the forward view judges {effect} where {how}")


def write_models(d: Diagnosis, out: Path, failures: list[str] | None = None) -> list[Path]:
    """nominal.xml and, when an effect is named, extended.xml (atomic writes), each only when
    MuJoCo compiles it: a model it refuses (a link mass under mjMINVAL, a negative inertia) is
    not written, and why goes into `failures` (the report says so instead of naming it)."""
    paths = []
    for name, extended in (("nominal.xml", False), ("extended.xml", True)):
        if extended and d.named is None:
            continue
        try:
            nominal_axes.write_xml(build_spec(d, extended=extended), out / name)
            paths.append(out / name)
        except (ValueError, TypeError) as err:    # MuJoCo's compile errors are ValueError
            if failures is not None:
                failures.append(f"{name} not written: {err}".replace("\n", " "))
            if not extended:
                if failures is not None and d.named is not None:
                    failures.append("extended.xml not written: the nominal axis it extends "
                                    "cannot be built")
                break
    return paths


def cross_validate(d: Diagnosis, other: Log, disturbance: np.ndarray | None = None,
                   disturbance_at: str = "link", settings: FilterSettings | None = None) -> dict:
    """Both models of diagnosis `d` (identified and extended on d.log) evaluated, unchanged, on
    another log: the inverse view (relative error of the motor equation, section 4's metric)
    and the forward view (closed-loop replay with `disturbance` applied to the link or
    carriage, or at the motor input: EMPS's pulses are volts at the drive input, already in
    the logged force, so they go in as gtau x pulses at the motor). `settings`: the other
    log's own band (diagnosis_settings(other); d's band when None). A log that cannot be
    replayed (no q_ref, no controller described) gets the inverse view and `forward_note`,
    why not the forward one."""
    rows = with_parameters(nominal_rows(other, settings or d.settings), d.inverse.nominal.X)
    out: dict = {"inverse": {}, "forward": {}}
    models = {"nominal": None, "extended": d.causes[-1] if d.causes else None}
    for label, c in models.items():
        if label == "extended" and c is None:
            continue
        res = predict(rows, c)
        out["inverse"][label] = {("motor", "link")[int(b)]: rows.relative_error_pct(res, int(b))
                                 for b in np.unique(rows.block)}
    dv = dataclasses.replace(d, log=other)
    if other.q_ref is None or not has_controller(other):
        # an open-loop run (or a loop nobody described) has no closed loop to replay: the
        # inverse view alone cross-validates on it
        out["forward_note"] = no_replay_note(other)
        return out
    for label, ext in (("nominal", False), ("extended", True)):
        if ext and d.named is None:
            continue
        n = replay_substeps(dv, ext)
        f = _view(dv, build_spec(dv, extended=ext, substeps=n), disturbance, disturbance_at, n)
        out["forward"][label] = {"tau_rel_pct": f.tau_rel_pct, "q_m_rms": f.q_m_rms,
                                 "q_m_rel_pct": f.q_m_rel_pct}
    return out
