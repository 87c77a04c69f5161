"""One virtual identification experiment: a joint tracks a chirp, the others are locked.

Per control tick k (period T = 1 / PAPER_RATE by default; `bench.sim.loop.run_loop`):
  1. the encoders sample the motor and link angles (quantised);
  2. the docs/controller.md controller computes tau_m[k] from the motor encoder;
  3. the log records (t_k, q_m, q, tau_m, q_ref);
  4. the rotor receives tau_m[k] + current-loop noise, held over the tick (zero-order hold)
     while MuJoCo integrates `substeps` steps, and the bench-loop effects' torque, a function
     of the rotor's state at each step.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterator

import mujoco
import numpy as np

from jointbench.bench.sim.axes import ExperimentModel, build_experiment_model
from jointbench.bench.sim.defaults import default_substeps
from jointbench.bench.sim.controller import Gains, gains_rule
from jointbench.bench.sim.friction import plant_meta
from jointbench.bench.sim.defaults import (ACCELERATION_SHARE, AMPLITUDE_REDUCTION, AMPLITUDE_RAD,
                                           MAX_REDUCTIONS)
from jointbench.bench.sim.loop import (INSTABILITY_WARNINGS, LoopChecks, LoopTrace,
                                       first_warning, run_loop)
from jointbench.bench.effects import (HiddenEffect, LoopEffects, as_effects, effects_meta,
                                      loop_effects_from_model)
from jointbench.bench.sim.reference import Chirp
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.log import Log, format_meta_number
from jointbench.identification.filter_choice import PAPER_RATE

SAMPLE_RATE_HZ = PAPER_RATE  # the paper's acquisition rate, the mission's


def position_unit(model: mujoco.MjModel, axis) -> str:
    """"m" for an axis whose link joint slides (prismatic: m and N), else "rad"."""
    slide = int(model.jnt_type[axis.link_joint]) == int(mujoco.mjtJoint.mjJNT_SLIDE)
    return "m" if slide else "rad"


class SimulationError(RuntimeError):
    """The simulation diverged or MuJoCo raised a warning: names the joint, time and reason."""


# Fault detection in the control loop (`_simulate`); each stops the run at once, no log.
DIVERGED_POSITION = 1e4      # rad (m): |q_m| or |q| beyond it is a diverged state
TRACKING_LIMIT = 10.0        # |q_ref - q_m| over this many chirp amplitudes (at least
TRACKING_FLOOR = 0.1         # this many rad) is a loop that does not track: unstable
CHATTER_REVERSALS = 20       # this many sample-to-sample jumps between -tau_max and +tau_max,
CHATTER_SAMPLES = 3          # at most this many samples apart on average, is a limit cycle
                             # at over Fs/6 (58 Hz at the paper's rate), far above the reference
                             # (<= 30 Hz, whose bang-bang saturation jumps once per half period)


@contextmanager
def _mujoco_warnings() -> Iterator[list[str]]:
    """Collect MuJoCo's warning texts for the duration of a run instead of letting MuJoCo
    print them and append them to MUJOCO_LOG.TXT in the working directory; the previous
    handler is restored afterwards."""
    texts: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(texts.append)
    try:
        yield texts
    finally:
        mujoco.set_mju_user_warning(previous)


@dataclass(frozen=True)
class ExperimentResult:
    """The log and the true signals behind it (for tests and plots)."""

    log: Log
    q_m_true: np.ndarray
    q_true: np.ndarray
    tau_applied: np.ndarray
    saturated: int
    experiment: ExperimentModel = field(repr=False)
    clamped: int = 0  # samples where MuJoCo's actuator ctrlrange cut the applied torque


def run_experiment(model: str | Path = "prototype", joint: str | None = None, *,
                   duration: float = 60.0, seed: int = 0, chirp: Chirp | None = None,
                   amplitude: float | None = None, config: dict[str, float] | None = None,
                   lock: str = "rigid",
                   effect: HiddenEffect | tuple[HiddenEffect, ...] | None = None,
                   sensors: Sensors | None = None, gains: Gains | None = None,
                   substeps: int | None = None, sample_rate_hz: float = SAMPLE_RATE_HZ,
                   tau_max: float | None = None,
                   progress: Callable[[float], None] | None = None) -> ExperimentResult:
    """Run one closed-loop chirp experiment and return its log (docs/log-format.md).

    `effect`: one hidden effect, a tuple of several (each name once), or None.
    Same arguments and seed, same log, bit for bit. Raises SimulationError when the state
    diverges, ModelStructureError for a model off the axis convention, ValueError for bad
    arguments.
    """
    if substeps is None:
        substeps = default_substeps(sample_rate_hz)
    exp = build_experiment_model(model, joint, config=config, lock=lock, effect=effect,
                                 substeps=substeps, sample_rate_hz=sample_rate_hz,
                                 tau_max=tau_max)
    m, ax, truth = exp.model, exp.axis, exp.truth
    T = 1.0 / sample_rate_hz
    auto = chirp is None
    if chirp is None:
        chirp = default_chirp(exp, duration, amplitude)
    sensors = sensors or Sensors.default(truth.gear_ratio, exp.tau_max)
    gains = gains or gains_rule(truth.Jm, truth.JL, truth.K, exp.tau_max, T)
    reductions = 0
    while True:
        t, q_ref, trace = _simulate(exp, chirp, sensors, gains, seed, substeps, sample_rate_hz,
                                    effect, progress)
        # The default reference shrinks until nothing saturates: near the antiresonance
        # sqrt(K / JL) the motor needs far more torque than the acceleration cap foresees.
        if not auto or trace.saturated == 0 or reductions >= MAX_REDUCTIONS:
            break
        reductions += 1
        chirp = replace(chirp, amplitude=AMPLITUDE_REDUCTION * chirp.amplitude,
                        max_acceleration=0.6 * chirp.max_acceleration)
    meta = {"sample_rate_hz": format_meta_number(sample_rate_hz),
            "gravity": format_meta_number(truth.g)}
    meta.update(gains.to_meta())
    meta.update({
        "joint": ax.name, "source": f"jointbench virtual experiment, model {exp.source.name}",
        "seed": str(seed), "lock": lock,
        "chirp": f"{chirp.method} {chirp.f0:g}-{chirp.f1:g} Hz, amplitude {chirp.amplitude:g} "
                 f"{position_unit(m, ax)}, "
                 f"{chirp.duration:g} s, taper {chirp.taper:g} s",
        "locked_config": " ".join(f"{k}={v:.6g}" for k, v in exp.config.items()),
        "saturated_samples": str(trace.saturated),
        "actuator_clamped_samples": str(trace.clamped),
        "amplitude_reductions": str(reductions),
    })
    meta.update(plant_meta(m, ax.motor_dof, substeps))
    if position_unit(m, ax) == "m":   # a slide joint: m and N (docs/log-format.md)
        meta["axis"] = "prismatic"
    if truth.gear_ratio is not None:
        meta["gear_ratio"] = format_meta_number(truth.gear_ratio)
    meta.update(sensors.to_meta())
    for key, value in truth.as_dict().items():
        if key not in ("g", "gear_ratio"):
            meta[f"truth_{key}"] = format_meta_number(value)
    meta["truth_center"] = format_meta_number(exp.center)
    meta.update(effects_meta(as_effects(effect)))
    log = Log(t=t, q_m=trace.q_m, tau_m=trace.tau_m, q=trace.q, q_ref=q_ref, meta=meta)
    return ExperimentResult(log=log, q_m_true=trace.q_m_true, q_true=trace.q_true,
                            tau_applied=trace.tau_applied, saturated=trace.saturated,
                            experiment=exp, clamped=trace.clamped)


def _simulate(exp: ExperimentModel, chirp: Chirp, sensors: Sensors, gains: Gains, seed: int,
              substeps: int, sample_rate_hz: float,
              effect: HiddenEffect | tuple[HiddenEffect, ...] | None,
              progress: Callable[[float], None] | None) -> tuple[np.ndarray, np.ndarray, LoopTrace]:
    """The control loop of the module docstring (`bench.sim.loop.run_loop`); returns the
    sample times, the reference and the sampled signals."""
    m, ax, truth = exp.model, exp.axis, exp.truth
    T = 1.0 / sample_rate_hz
    n = int(round(chirp.duration * sample_rate_hz)) + 1
    t = np.arange(n) * T
    # Start the reference at the measured motor angle: then e[0] = 0 and the logged
    # tau_m[0] is the integrator's initial state, as docs/controller.md reads it back.
    q_ref = chirp(t) - chirp.center + sensors.motor_quantizer()(float(exp.qpos_init[ax.motor_qpos]))

    d = mujoco.MjData(m)
    d.qpos[:] = exp.qpos_init
    mujoco.mj_forward(m, d)
    loop = LoopEffects(effect, truth.FVm, truth.FSm, truth.gear_ratio)
    if not as_effects(effect):
        # An extended MJCF (jointbench diagnose) may carry bench-loop effects as numerics.
        loop = loop_effects_from_model(m, ax.name) or loop
    act = ax.actuator
    rk4 = int(m.opt.integrator) == int(mujoco.mjtIntegrator.mjINT_RK4)
    fault = _Faults(ax.name, T, chirp.amplitude, float(gains.tau_max),
                    float(np.max(np.abs(m.actuator_ctrlrange[act])))
                    if m.actuator_ctrllimited[act] else math.inf,
                    [d.warning[int(w)] for w in INSTABILITY_WARNINGS],
                    2 * math.pi * truth.f1_hz * m.opt.timestep, 2.78 if rk4 else 2.0,
                    position_unit(m, ax))
    with _mujoco_warnings() as fault.texts:
        trace = run_loop(m, d, ax, gains, T, exp.tau0, q_ref, substeps=substeps,
                         sensors=sensors, seed=seed, loop=loop if loop.active else None,
                         checks=fault, progress=progress)
    warning = first_warning(d)
    if warning is not None:
        texts = fault.texts
        raise SimulationError(
            f"joint {ax.name}: MuJoCo warning {warning[0]} "
            f"({warning[1]} times, last at t = {d.time:.4f} s)"
            + (f": {texts[-1]}" if texts else ""))
    return t, q_ref, trace


class _Faults(LoopChecks):
    """The fault checks of one run (`_simulate`): each failing check raises SimulationError
    naming the joint, the simulated time and the reason."""

    position_limit = link_limit = DIVERGED_POSITION

    def __init__(self, joint: str, T: float, amplitude: float, tau_max: float,
                 ctrl_limit: float, bad: list, w1_dt: float, w_dt_limit: float,
                 unit: str = "rad"):
        self.joint, self.T, self.tau_max, self.ctrl_limit, self.bad, self.unit = \
            joint, T, tau_max, ctrl_limit, bad, unit
        # w1 dt against the integrator's stability bound on the imaginary axis (RK4 2.78,
        # Euler 2): beyond it the spring mode itself blows up, whatever the gains.
        self.cause = (f"the timestep is too large for the joint's mode: w1 dt = {w1_dt:.3g} is "
                      f"over the integrator's stability limit {w_dt_limit:g}; raise the sample "
                      "rate or the substeps" if math.isfinite(w1_dt) and w1_dt > w_dt_limit else
                      "unstable gains, check their signs and sizes, or too large a timestep "
                      "for the model's stiffest mode")
        self.track_limit = max(TRACKING_LIMIT * amplitude, TRACKING_FLOOR)
        self.torque_limit = min(tau_max, ctrl_limit)  # the controller's or MuJoCo's clip
        self.texts: list[str] = []  # MuJoCo's warning texts of the run (`_mujoco_warnings`)
        self._last_sign = 0.0
        self._last_k = -2
        self._reversals: list[int] = []

    def _fail(self, k: int, reason: str) -> None:
        raise SimulationError(f"joint {self.joint}: the simulation stopped at "
                              f"t = {k * self.T:.4f} s: {reason}")

    def diverged(self, k: int, qm: float, q: float) -> None:
        self._fail(k, f"the state diverged (q_m = {qm:.3g}, q = {q:.3g} {self.unit}): "
                      f"{self.cause}")

    def lost_track(self, k: int, error: float) -> None:
        self._fail(k, f"the motor is {abs(error):.3g} {self.unit} from the reference (limit "
                      f"{self.track_limit:.3g} {self.unit}, {TRACKING_LIMIT:g} chirp "
                      "amplitudes): "
                      f"{self.cause}; or the torque limit {self.torque_limit:g} cannot hold "
                      "the axis")

    def saturated(self, k: int, u: float) -> None:
        sign = math.copysign(1.0, u)
        if self._last_k == k - 1 and sign == -self._last_sign:
            self._reversals.append(k)
            first = self._reversals[-CHATTER_REVERSALS] if \
                len(self._reversals) >= CHATTER_REVERSALS else None
            if first is not None and k - first <= CHATTER_SAMPLES * CHATTER_REVERSALS:
                self._fail(k, f"the torque jumps between -{self.torque_limit:g} and "
                              f"+{self.torque_limit:g} from one sample to the next ("
                              f"{CHATTER_REVERSALS} times in {(k - first) * self.T:.3g} s): a "
                              "limit cycle at the sampling rate, the velocity loop is unstable "
                              "(kv too large for the sampling period)")
        self._last_sign, self._last_k = sign, k

    def mujoco_unstable(self, k: int) -> None:
        names = [w for w, stat in zip(("qpos", "qvel", "qacc"), self.bad) if stat.number]
        texts = self.texts
        self._fail(k, f"MuJoCo found NaN, infinite or huge {'/'.join(names)} and reset the "
                      f"state ({texts[-1] if texts else 'no message'}): {self.cause}")


def default_chirp(exp: ExperimentModel, duration: float = 60.0,
                  amplitude: float | None = None) -> Chirp:
    """The default reference: a logarithmic 0.05-30 Hz chirp around the motor's rest angle,
    amplitude 0.1 rad, with the acceleration capped so that the rigid-body torque
    (Jm + JL) A (2 pi f)^2 stays under 40 % of the torque limit (the rest is left for
    friction, gravity and the resonance). Larger motion shrinks the share of the stick
    phases at velocity reversals, where the Coulomb model sign(qm') is wrong."""
    t = exp.truth
    return Chirp(duration=duration, amplitude=amplitude or AMPLITUDE_RAD,
                 center=float(exp.qpos_init[exp.axis.motor_qpos]),
                 max_acceleration=ACCELERATION_SHARE * exp.tau_max / (t.Jm + t.JL))
