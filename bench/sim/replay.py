"""Closed-loop replay of a logged experiment on a MuJoCo axis (forward simulation).

The log's reference q_ref is tracked again by the controller its metadata describes
(docs/controller.md: the PI cascade or a P/PD/PI/PID position loop,
`bench.sim.controller.controller_from_log`), on any model
that follows the axis convention (a nominal axis from `bench.nominal`, a shipped or user
MJCF through `bench.axes.build_experiment_model`). Per sample k (period T of the log):
  1. the motor position q_m[k] is measured as it is (no noise, no quantisation);
  2. the controller computes tau_m[k] from q_m[k] and q_ref[k];
  3. tau_m[k] (plus a disturbance at the motor input, if asked) drives the actuator and a
     disturbance on the link (or carriage) goes into qfrc_applied, both held over the sample
     (zero-order hold) while MuJoCo integrates `substeps` steps of T / substeps.
The replay starts at rest at the logged q_m[0] (and q[0] when logged; else the link at its
static equilibrium) with the integrator holding I[-1] = tau_m[0] (docs/controller.md), unless
another `tau0` is given.

`forward_errors` compares the replay with the measured signals: that is the forward view of
a model, where the inverse view (identification residuals) only sees the torque.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from jointbench.bench.sim.controller import controller_from_log
from jointbench.bench.sim.friction import log_substeps, plant_meta
from jointbench.bench.sim.loop import LoopChecks, first_warning, run_loop
from jointbench.bench.sim.nominal import static_link_position
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.log import Log, LogError
from jointbench.identification.output_values import rms
from jointbench.models import Axis

DISTURBANCE_AT = ("link", "motor")


class ReplayError(RuntimeError):
    """The replay diverged or MuJoCo raised a warning."""


@dataclass(frozen=True)
class ReplayResult:
    """The replayed signals, sampled as the log: `t` [s], `q_m` motor position, `q` link
    position (None for a rigid axis), `tau_m` the motor torque a log records (the controller's
    output, plus the disturbance when it enters at the motor), `saturated` the number of
    samples clipped at tau_max, `disturbance` as applied (None when none), `plant` how the
    replay's plant switches its friction (bench.sim.friction.plant_meta), which a log of the
    replay carries in place of the measured log's."""

    t: np.ndarray
    q_m: np.ndarray
    q: np.ndarray | None
    tau_m: np.ndarray
    saturated: int
    disturbance: np.ndarray | None = None
    disturbance_at: str = "link"
    plant: dict[str, str] = field(default_factory=dict)


def _with_timestep(model: mujoco.MjModel, dt: float) -> mujoco.MjModel:
    if model.opt.timestep == dt:
        return model
    m = copy.copy(model)
    m.opt.timestep = dt
    return m


TRACK_FACTOR = 10.0       # the replay may track this many times worse than the log did ...
SATURATION_SHARE = 0.2    # ... and saturate this share of the samples beyond the log's own


def _clipped(log: Log, tau_max: float) -> int:
    """Samples of the log at its torque limit (within 1e-6 relative)."""
    return int(np.count_nonzero(np.abs(log.tau_m) >= tau_max * (1 - 1e-6)))


class _ReplayChecks(LoopChecks):
    """The replay's checks, each tick (as `simulate`'s): q_m beyond a million times the
    logged motion (at least 1e6), or the motor farther from the reference than
    TRACK_FACTOR times the log's worst tracking error (at least the reference's span), is a
    diverged replay (negative gains, a wrong model, a huge initial integrator state)."""

    def __init__(self, log: Log, T: float, tau_max: float):
        self.log, self.T = log, T
        self.position_limit = 1e6 * max(1.0, float(np.max(np.abs(log.q_m))))
        worst = float(np.max(np.abs(log.q_ref - log.q_m)))
        self.track_limit = max(TRACK_FACTOR * worst, float(np.ptp(log.q_ref)), 1e-9)
        self.torque_limit, self.clipped = tau_max, 0

    def saturated(self, k: int, u: float) -> None:
        self.clipped += 1

    def _fail(self, k: int, what: str) -> None:
        held = (f"; {self.clipped} of {k} samples so far at the torque limit tau_max = "
                f"{self.torque_limit:g}, the log has {_clipped(self.log, self.torque_limit)} "
                "in all" if self.clipped else "")
        raise ReplayError(f"replay of {self.log.path or 'the log'} diverged at t = "
                          f"{k * self.T:.4f} s ({what}): the model is unstable under the "
                          "logged gains (check their signs and sizes) or does not describe "
                          f"the axis{held}")

    def diverged(self, k: int, q_m: float, q: float) -> None:
        if not abs(q_m) < self.position_limit:
            self._fail(k, f"q_m = {q_m:.3g}")

    def lost_track(self, k: int, error: float) -> None:
        self._fail(k, f"the motor is {abs(error):.3g} from the reference, over "
                      f"{self.track_limit:.3g} = {TRACK_FACTOR:g} times the log's worst "
                      "tracking error or the reference's span")


def _check_saturation(log: Log, tau_max: float, saturated: int) -> None:
    """ReplayError when the replay sits at the torque limit on SATURATION_SHARE of the
    samples more than the log does: its signals would say nothing about the model."""
    n, logged = len(log), _clipped(log, tau_max)
    if saturated > logged + SATURATION_SHARE * n:
        raise ReplayError(f"replay of {log.path or 'the log'}: {saturated} of {n} samples "
                          f"saturated at tau_max = {tau_max:g} (the log: {logged}): the model "
                          "or the gains do not hold the axis; the replay says nothing")


def _check_tau0(tau0: float | None, tau_max: float) -> None:
    if tau0 is not None and not (math.isfinite(tau0) and abs(tau0) <= tau_max):
        raise ValueError(f"tau0 (--tau0) = {tau0:g}: the integrator's initial state must lie "
                         f"within the torque limit tau_max = {tau_max:g}")


def replay(model: mujoco.MjModel, axis: Axis, log: Log, disturbance: np.ndarray | None = None,
           substeps: int | None = None, *, disturbance_at: str = "link",
           tau0: float | None = None, loop=None, sensors: Sensors | None = None,
           seed: int = 0) -> ReplayResult:
    """Re-run the logged closed-loop experiment of `log` on `axis` of `model` (module
    docstring). `disturbance`: force/torque per sample [N or N m, joint side], applied to the
    link (carriage) through qfrc_applied (`disturbance_at="link"`), or added to the motor
    command after the controller (`"motor"`, as a pulse injected into a drive's input; then
    the recorded tau_m includes it, as the drive's own log would). `tau0`: the integrator's
    initial state, default tau_m[0] (docs/controller.md). `loop`: bench-loop effects
    (bench.effects.LoopEffects, e.g. from an extended MJCF's numerics) whose torque, a function
    of the rotor angle and velocity, acts on the rotor at each physics step
    (`bench.sim.loop`). `sensors`: measure as
    the virtual experiment does (`bench.experiment`): the controller and the returned q_m, q
    see the quantised encoders, and white torque noise (seeded by `seed`, as an experiment's)
    adds to the applied torque but not to the recorded tau_m; default: exact measurements, no
    noise (step 1 above). `substeps`: MuJoCo steps a sample, default the log's own (a
    jointbench log carries them), else 1 (`friction.log_substeps`). The model is not modified
    (a copy takes the log's timestep when it differs).

    Raises LogError when the log lacks q_ref or the controller gains, ValueError for bad
    arguments, ReplayError when the simulation diverges.
    """
    if log.q_ref is None:
        raise LogError("cannot replay: the log has no column 'q_ref' (the reference the "
                       "controller tracked)", log.path, column="q_ref")
    gains = controller_from_log(log)
    _check_tau0(tau0, float(gains.tau_max))
    if substeps is None:
        substeps = log_substeps(log, 1)
    if substeps < 1:
        raise ValueError(f"substeps must be >= 1, got {substeps}")
    if disturbance_at not in DISTURBANCE_AT:
        raise ValueError(f"disturbance_at must be one of {', '.join(DISTURBANCE_AT)}, "
                         f"got {disturbance_at!r}")
    n = len(log)
    if disturbance is not None:
        disturbance = np.asarray(disturbance, dtype=float)
        if disturbance.shape != (n,):
            raise ValueError(f"disturbance has shape {disturbance.shape}, the log has {n} samples")
        if not np.all(np.isfinite(disturbance)):
            raise ValueError("disturbance has non-finite values")
    T = log.ts
    m = _with_timestep(model, T / substeps)
    d = mujoco.MjData(m)
    d.qpos[axis.motor_qpos] = log.q_m[0]
    if not axis.rigid:
        d.qpos[axis.link_qpos] = log.q[0] if log.q is not None else \
            static_link_position(m, axis, d.qpos)
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)

    checks = _ReplayChecks(log, T, float(gains.tau_max))
    trace = run_loop(m, d, axis, gains, T, float(log.tau_m[0]) if tau0 is None else float(tau0),
                     log.q_ref, substeps=substeps, sensors=sensors, seed=seed, loop=loop,
                     disturbance=disturbance, disturbance_at=disturbance_at, checks=checks)
    warning = first_warning(d)
    if warning is not None:
        raise ReplayError(f"replay of {log.path or 'the log'}: MuJoCo warning {warning[0]} "
                          f"({warning[1]} times)")
    _check_saturation(log, float(gains.tau_max), trace.saturated)
    return ReplayResult(t=np.asarray(log.t, dtype=float).copy(), q_m=trace.q_m,
                        q=None if axis.rigid else trace.q, tau_m=trace.tau_m,
                        saturated=trace.saturated, disturbance=disturbance,
                        disturbance_at=disturbance_at,
                        plant=plant_meta(m, axis.motor_dof, substeps))


def forward_errors(log: Log, result: ReplayResult, skip: int = 0) -> dict[str, float | str | int]:
    """The replay against the measurement, over the samples from `skip` on (to leave out the
    start transient of a log that does not start at rest):
    - `position_rms`: RMS of q_m(replay) - q_m(log), in the log's unit (m or rad);
      `position_rel_pct`: 100 x that / RMS of the measured motion about its mean;
      `tracking_rel_pct`: 100 x that / RMS of the measured tracking error q_ref - q_m (how
      much of the measured tracking error the replay gets wrong);
    - `torque_rms` [N or N m] and `torque_rel_pct`: 100 x RMS(tau_m(replay) - tau_m(log)) /
      RMS(tau_m(log));
    - `link_position_rms`, `link_position_rel_pct` when both have q.
    A ratio whose denominator is zero is None.
    """
    if len(result.t) != len(log):
        raise ValueError(f"the replay has {len(result.t)} samples, the log {len(log)}")
    if not 0 <= skip < len(log) - 1:
        raise ValueError(f"skip must lie in [0, {len(log) - 1}), got {skip}")

    def pct(num: float, den: float) -> float | None:
        return 100.0 * num / den if den > 0 else None

    k = slice(skip, None)
    qm = log.q_m[k]
    e_pos = rms(result.q_m[k] - qm)
    e_tau = rms(result.tau_m[k] - log.tau_m[k])
    out: dict = {
        "samples": len(qm),
        "skip": skip,
        "position_unit": "m" if log.prismatic else "rad",
        "torque_unit": "N" if log.prismatic else "N m",
        "position_rms": e_pos,
        "position_rel_pct": pct(e_pos, rms(qm - np.mean(qm))),
        "tracking_rel_pct": (pct(e_pos, rms(log.q_ref[k] - qm))
                             if log.q_ref is not None else None),
        "torque_rms": e_tau,
        "torque_rel_pct": pct(e_tau, rms(log.tau_m[k])),
        "saturated_samples": result.saturated,
    }
    if result.q is not None and log.q is not None:
        e_q = rms(result.q[k] - log.q[k])
        out["link_position_rms"] = e_q
        out["link_position_rel_pct"] = pct(e_q, rms(log.q[k] - np.mean(log.q[k])))
    return out


def simulated_log(log: Log, result: ReplayResult, source: str) -> Log:
    """The replay as a log (docs/log-format.md): the measured log's metadata (rate, gains,
    axis, gravity) with `source` and `replay_of`; columns t, q_m, q (two-mass models), tau_m,
    q_ref, and `disturbance` when one was applied."""
    meta = {k: v for k, v in log.meta.items()
            if not k.startswith("truth_") and k not in ("source", "saturated_samples")}
    meta["source"] = source
    if log.path:
        meta["replay_of"] = str(log.path)
    meta["saturated_samples"] = str(result.saturated)
    meta.update(result.plant)    # the replay's plant, not the measured log's
    extra = {}
    if result.disturbance is not None:
        extra["disturbance"] = result.disturbance
        meta["disturbance_at"] = result.disturbance_at
    return Log(t=result.t, q_m=result.q_m, tau_m=result.tau_m, q=result.q,
               q_ref=None if log.q_ref is None else log.q_ref.copy(), extra=extra, meta=meta)

