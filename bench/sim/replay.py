"""Closed-loop replay of a logged experiment on a MuJoCo axis (forward simulation).

The log's reference q_ref is tracked again by the controller its metadata describes
(CONTRACT section 2, `bench.controller.PIController` with `Gains.from_log`), on any model
that follows the axis convention (a nominal axis from `bench.nominal`, a shipped or user
MJCF through `bench.axes.build_experiment_model`). Per sample k (period T of the log):
  1. the motor position q_m[k] is measured as it is (no noise, no quantisation);
  2. the controller computes tau_m[k] from q_m[k] and q_ref[k];
  3. tau_m[k] (plus a disturbance at the motor input, if asked) drives the actuator and a
     disturbance on the link (or carriage) goes into qfrc_applied, both held over the sample
     (zero-order hold) while MuJoCo integrates `substeps` steps of T / substeps.
The replay starts at rest at the logged q_m[0] (and q[0] when logged; else the link at its
static equilibrium) with the integrator holding I[-1] = tau_m[0] (CONTRACT section 2), unless
another `tau0` is given.

`forward_errors` compares the replay with the measured signals: that is the forward view of
a model, where the inverse view (identification residuals) only sees the torque.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import mujoco
import numpy as np

from jointbench.bench.sim.controller import Gains
from jointbench.bench.sim.loop import LoopChecks, first_warning, run_loop
from jointbench.bench.sim.nominal import static_link_position
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.log import Log, LogError
from jointbench.models import Axis

DISTURBANCE_AT = ("link", "motor")


class ReplayError(RuntimeError):
    """The replay diverged or MuJoCo raised a warning."""


@dataclass(frozen=True)
class ReplayResult:
    """The replayed signals, sampled as the log: `t` [s], `q_m` motor position, `q` link
    position (None for a rigid axis), `tau_m` the motor torque a log records (the controller's
    output, plus the disturbance when it enters at the motor), `saturated` the number of
    samples clipped at tau_max, `disturbance` as applied (None when none)."""

    t: np.ndarray
    q_m: np.ndarray
    q: np.ndarray | None
    tau_m: np.ndarray
    saturated: int
    disturbance: np.ndarray | None = None
    disturbance_at: str = "link"


def _with_timestep(model: mujoco.MjModel, dt: float) -> mujoco.MjModel:
    if model.opt.timestep == dt:
        return model
    m = copy.copy(model)
    m.opt.timestep = dt
    return m


class _ReplayChecks(LoopChecks):
    """The replay's one check in the loop: q_m beyond a million times the logged motion
    (at least 1e6) is a diverged replay."""

    def __init__(self, log: Log, T: float):
        self.log, self.T = log, T
        self.position_limit = 1e6 * max(1.0, float(np.max(np.abs(log.q_m))))

    def diverged(self, k: int, q_m: float, q: float) -> None:
        if not abs(q_m) < self.position_limit:
            raise ReplayError(f"replay of {self.log.path or 'the log'} diverged at t = "
                              f"{k * self.T:.4f} s (q_m = {q_m:.3g}): the model is unstable "
                              "under the logged gains")


def replay(model: mujoco.MjModel, axis: Axis, log: Log, disturbance: np.ndarray | None = None,
           substeps: int = 1, *, disturbance_at: str = "link",
           tau0: float | None = None, loop=None, sensors: Sensors | None = None,
           seed: int = 0) -> ReplayResult:
    """Re-run the logged closed-loop experiment of `log` on `axis` of `model` (module
    docstring). `disturbance`: force/torque per sample [N or N m, joint side], applied to the
    link (carriage) through qfrc_applied (`disturbance_at="link"`), or added to the motor
    command after the controller (`"motor"`, as a pulse injected into a drive's input; then
    the recorded tau_m includes it, as the drive's own log would). `tau0`: the integrator's
    initial state, default tau_m[0] (CONTRACT section 2). `loop`: bench-loop effects
    (bench.effects.LoopEffects, e.g. from an extended MJCF's numerics) whose torque, a function
    of the rotor angle and velocity, adds to the applied motor torque. `sensors`: measure as
    the virtual experiment does (`bench.experiment`): the controller and the returned q_m, q
    see the quantised encoders, and white torque noise (seeded by `seed`, as an experiment's)
    adds to the applied torque but not to the recorded tau_m; default: exact measurements, no
    noise (step 1 above). The model is not modified (a copy takes the log's timestep when it
    differs).

    Raises LogError when the log lacks q_ref or the controller gains, ValueError for bad
    arguments, ReplayError when the simulation diverges.
    """
    if log.q_ref is None:
        raise LogError("cannot replay: the log has no column 'q_ref' (the reference the "
                       "controller tracked)", log.path, column="q_ref")
    gains = Gains.from_log(log)
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

    checks = _ReplayChecks(log, T)
    trace = run_loop(m, d, axis, gains, T, float(log.tau_m[0]) if tau0 is None else float(tau0),
                     log.q_ref, substeps=substeps, sensors=sensors, seed=seed, loop=loop,
                     disturbance=disturbance, disturbance_at=disturbance_at, checks=checks)
    warning = first_warning(d)
    if warning is not None:
        raise ReplayError(f"replay of {log.path or 'the log'}: MuJoCo warning {warning[0]} "
                          f"({warning[1]} times)")
    return ReplayResult(t=np.asarray(log.t, dtype=float).copy(), q_m=trace.q_m,
                        q=None if axis.rigid else trace.q, tau_m=trace.tau_m,
                        saturated=trace.saturated, disturbance=disturbance,
                        disturbance_at=disturbance_at)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


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
    e_pos = _rms(result.q_m[k] - qm)
    e_tau = _rms(result.tau_m[k] - log.tau_m[k])
    out: dict = {
        "samples": len(qm),
        "skip": skip,
        "position_unit": "m" if log.prismatic else "rad",
        "torque_unit": "N" if log.prismatic else "N m",
        "position_rms": e_pos,
        "position_rel_pct": pct(e_pos, _rms(qm - np.mean(qm))),
        "tracking_rel_pct": (pct(e_pos, _rms(log.q_ref[k] - qm))
                             if log.q_ref is not None else None),
        "torque_rms": e_tau,
        "torque_rel_pct": pct(e_tau, _rms(log.tau_m[k])),
        "saturated_samples": result.saturated,
    }
    if result.q is not None and log.q is not None:
        e_q = _rms(result.q[k] - log.q[k])
        out["link_position_rms"] = e_q
        out["link_position_rel_pct"] = pct(e_q, _rms(log.q[k] - np.mean(log.q[k])))
    return out


def simulated_log(log: Log, result: ReplayResult, source: str) -> Log:
    """The replay as a log (CONTRACT section 1): the measured log's metadata (rate, gains,
    axis, gravity) with `source` and `replay_of`; columns t, q_m, q (two-mass models), tau_m,
    q_ref, and `disturbance` when one was applied."""
    meta = {k: v for k, v in log.meta.items()
            if not k.startswith("truth_") and k not in ("source", "saturated_samples")}
    meta["source"] = source
    if log.path:
        meta["replay_of"] = str(log.path)
    meta["saturated_samples"] = str(result.saturated)
    extra = {}
    if result.disturbance is not None:
        extra["disturbance"] = result.disturbance
        meta["disturbance_at"] = result.disturbance_at
    return Log(t=result.t, q_m=result.q_m, tau_m=result.tau_m, q=result.q,
               q_ref=None if log.q_ref is None else log.q_ref.copy(), extra=extra, meta=meta)


def plot_replay(log: Log, result: ReplayResult, title: str = ""):
    """Figure: measured and replayed q_m (and tracking error q_ref - q_m) and tau_m against t.
    pyplot is imported here; the caller picks the backend."""
    import matplotlib.pyplot as plt

    pu, fu = ("m", "N") if log.prismatic else ("rad", "N m")
    fig, ax = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    ax[0].plot(log.t, log.q_m, lw=0.8, label="measured")
    ax[0].plot(result.t, result.q_m, lw=0.8, ls="--", label="replay")
    ax[0].set_ylabel(f"q_m [{pu}]")
    if log.q_ref is not None:
        ax[1].plot(log.t, log.q_ref - log.q_m, lw=0.8, label="measured")
        ax[1].plot(result.t, log.q_ref - result.q_m, lw=0.8, ls="--", label="replay")
        ax[1].set_ylabel(f"q_ref - q_m [{pu}]")
    ax[2].plot(log.t, log.tau_m, lw=0.8, label="measured")
    ax[2].plot(result.t, result.tau_m, lw=0.8, ls="--", label="replay")
    ax[2].set_ylabel(f"tau_m [{fu}]")
    ax[2].set_xlabel("t [s]")
    for a in ax:
        a.legend(loc="upper right", fontsize=8)
        a.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


@dataclass(frozen=True)
class ReplayReport:
    """A replay run from a log file (`replay_log_file`): what was replayed on which model and
    how it compares (`forward_errors`)."""

    log: Log
    result: ReplayResult
    errors: dict
    model: str                            # "nominal rigid", "nominal joint-motor" or the file
    axis: str
    parameters: dict[str, float] | None   # the identified parameters of a nominal model
    notes: tuple[str, ...] = ()
    spec: mujoco.MjSpec | None = None     # the nominal axis (None when a model was given)


def replay_log_file(path, model: str | None = None, joint: str | None = None,
                    config: dict[str, float] | None = None, lock: str = "rigid",
                    substeps: int = 1, tau0: float | None = None, skip: int = 0,
                    identify_model: str = "auto") -> ReplayReport:
    """Read the log at `path` and replay it (`replay`) on `model` (shipped name or MJCF file,
    through `bench.axes.build_experiment_model` with the other axes locked as `config`
    says), or without a model on the nominal axis of its own identification
    (`identification.identify.identify(log, identify_model)`, then `bench.nominal.for_log`).
    """
    from jointbench.identification.identify import identify
    from jointbench.identification.log import read_log

    log = read_log(path)
    if log.q_ref is None:
        raise LogError("cannot replay: the log has no column 'q_ref' (the reference the "
                       "controller tracked)", log.path, column="q_ref")
    gains = Gains.from_log(log)
    notes: list[str] = []
    if model is None:
        from jointbench.bench.sim.nominal import compile_axis, for_log

        ident = identify(log, identify_model)
        notes += [f"identify: {n}" for n in ident.notes]
        nominal = for_log(ident, log, joint)
        notes += [f"nominal: {n}" for n in nominal.notes]
        m, axis = compile_axis(nominal.spec, f"nominal {nominal.model} axis of {path}")
        label, params, spec = f"nominal {nominal.model}", dict(nominal.parameters), nominal.spec
    else:
        from jointbench.bench.sim.axes import build_experiment_model

        start = log.q[0] if log.q is not None else log.q_m[0]
        exp = build_experiment_model(model, joint, config=config, center=float(start),
                                     lock=lock, substeps=substeps,
                                     sample_rate_hz=log.sample_rate_hz, tau_max=gains.tau_max)
        m, axis, label, params, spec = exp.model, exp.axis, str(exp.source), None, None
    result = replay(m, axis, log, substeps=substeps, tau0=tau0)
    return ReplayReport(log=log, result=result, errors=forward_errors(log, result, skip),
                        model=label, axis=axis.name, parameters=params, notes=tuple(notes),
                        spec=spec)


def format_report(rep: ReplayReport) -> str:
    """The forward comparison as text (what `jointbench simulate --replay` prints)."""
    log, e = rep.log, rep.errors
    g = Gains.from_log(log)
    pu, fu = e["position_unit"], e["torque_unit"]
    lines = [f"replayed {log.path}: {len(log)} samples at {log.sample_rate_hz:g} Hz in closed "
             f"loop (CONTRACT section 2: kp {g.kp:g}, kv {g.kv:g}, ki {g.ki:g}, tau_max "
             f"{g.tau_max:g}, velocity feed-forward {'on' if g.velocity_feedforward else 'off'}) "
             f"on {rep.model}, axis {rep.axis}"]
    if rep.parameters:
        lines.append("model: " + ", ".join(f"{k} = {v:.6g}" for k, v in rep.parameters.items()))

    def pct(x, what):
        return "" if x is None else f", {x:.3g} % of {what}"

    span = f" (from sample {e['skip']})" if e["skip"] else ""
    lines.append(f"position q_m{span}: RMS error {e['position_rms']:.4g} {pu}"
                 f"{pct(e['position_rel_pct'], 'the motion')}"
                 f"{pct(e['tracking_rel_pct'], 'the measured tracking error')}")
    if "link_position_rms" in e:
        lines.append(f"link position q: RMS error {e['link_position_rms']:.4g} {pu}"
                     f"{pct(e['link_position_rel_pct'], 'the motion')}")
    lines.append(f"{'force' if log.prismatic else 'torque'} tau_m{span}: RMS error "
                 f"{e['torque_rms']:.4g} {fu}{pct(e['torque_rel_pct'], 'the measured RMS')}")
    lines.append(f"saturated samples in the replay: {rep.result.saturated}")
    lines += [f"note: {n}" for n in rep.notes]
    return "\n".join(lines)


def report_json(rep: ReplayReport) -> dict:
    """The JSON object of `jointbench simulate --replay --json`."""
    return {"replay": str(rep.log.path), "model": rep.model, "axis": rep.axis,
            "parameters": rep.parameters, "samples": len(rep.log),
            "saturated_samples": rep.result.saturated, "errors": rep.errors,
            "notes": list(rep.notes)}
