"""An independent two-mass axis simulator (plain numpy/scipy, no MuJoCo) writing jointbench logs.

Accuracy must never be measured only on MuJoCo data. This module models one
flexible axis from the paper's eqs. (5)-(6) on the joint side (SI, radians):

    Jm qm'' = tau - FVm qm' - FSm tanh(qm' / v_s) - K (qm - q)                      (6)
    JL q''  = K (qm - q) - FV q' - FS tanh(q' / v_s) - MX g cos q - MY g sin q      (5), (7)

Coulomb friction is smoothed over `v_s` (a parameter, default 1e-3 rad/s). The hidden effects
of docs/effects.md (jointbench.testing.hidden_effects) add their terms to these equations. The
plant is integrated by fixed-step RK4, `substeps` steps per control period, with the torque held
over the period (zero-order hold). The controller is docs/controller.md, written here again from
the contract's text (not imported), evaluated at 350.87 Hz by default on the quantised motor
encoder; the applied torque is the command plus seeded white noise. Only the default gains
come from the package (`bench.sim.controller.gains_rule`, which needs no MuJoCo).

Same family, arguments and seed: the same log, bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from jointbench.bench.sim.controller import Gains, gains_rule
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.log import Log
from jointbench.testing.hidden_effects import (Plant, as_hidden, plant, rk4_step,
                                               spring_deflection, stepper_with_effects,
                                               truth_meta)

TWO_PI = 2.0 * math.pi
STEP_PHASE = 0.04        # substeps: w1 dt at most this (RK4 loses (w dt)^6 / 72 energy a step)
STEP_FRICTION = 2.0      # and the stiffest friction rate times dt at most this (RK4's real-axis
                         # stability limit is 2.785): the smoothed Coulomb slope FS / v_s is stiff
ACCELERATION_SHARE = 0.4  # the chirp's rigid-body torque (Jm + JL) A w^2 stays under this share
                          # of tau_max, the rule of bench.sim.experiment.default_chirp
DEFAULT_TAPER = 2.0       # s, the raised-cosine fades of the default reference
MAX_REDUCTIONS = 6        # the default reference shrinks at most this many times


@dataclass(frozen=True)
class AxisFamily:
    """One flexible axis, joint side, SI: inertias [kg m^2], K [N m/rad], viscous frictions
    [N m s/rad], Coulomb frictions [N m], first moments MX, MY [kg m], torque limit [N m];
    encoders in counts per turn of the joint (the motor's counts times the gear ratio), white
    torque noise std [N m]; `v_s` [rad/s] the Coulomb smoothing velocity."""

    name: str
    description: str
    Jm: float
    JL: float
    K: float
    FVm: float
    FSm: float
    FV: float
    FS: float
    tau_max: float
    torque_noise_std: float
    MX: float = 0.0
    MY: float = 0.0
    motor_counts_per_turn: float = 2**17 * 100.0   # 17-bit motor encoder behind a 100:1 gear
    link_counts_per_turn: float = 2**20            # 20-bit absolute link encoder
    v_s: float = 1e-3
    gear_ratio: float = 100.0    # only sets torque_ripple's default period

    @property
    def rest_angle(self) -> float:
        """The stable link angle without torque [rad]: atan2(MY, MX) - pi/2, or 0 without a
        link mass."""
        if self.MX == 0.0 and self.MY == 0.0:
            return 0.0
        return math.atan2(self.MY, self.MX) - math.pi / 2

    @property
    def f1_hz(self) -> float:
        """The locked first mode sqrt(K (1/Jm + 1/JL)) / 2 pi [Hz]."""
        return math.sqrt(self.K * (1.0 / self.Jm + 1.0 / self.JL)) / TWO_PI

    def truth(self) -> dict[str, float]:
        return {"K": self.K, "Jm": self.Jm, "JL": self.JL, "FVm": self.FVm, "FSm": self.FSm,
                "FV": self.FV, "FS": self.FS, "MX": self.MX, "MY": self.MY,
                "f1_hz": self.f1_hz}


def _k_for(f1_hz: float, Jm: float, JL: float) -> float:
    """The stiffness that puts the locked first mode at f1_hz [N m/rad]."""
    return round((TWO_PI * f1_hz) ** 2 / (1.0 / Jm + 1.0 / JL), 4)


# Axes unlike the paper's prototype (Jm 174.8, K 20341, JL 47.4, f1 3.7 Hz) and the arm (modes
# 15-19 Hz). Frictions: motor Coulomb 1.5-2 % of tau_max, viscous about 1.5 Jm per second on
# the motor and 1-2 JL per second on the link, as on the prototype; torque noise 1.25 % of
# tau_max (the bench's default current-loop noise). The first moments are zero (MX = MY = 0:
# a horizontal axis); replace() them to add gravity.
FAMILIES: dict[str, AxisFamily] = {f.name: f for f in (
    AxisFamily("wrist", "light wrist, Jm > JL (JL/Jm = 0.5), f1 = 12 Hz",
               Jm=0.030, JL=0.015, K=_k_for(12.0, 0.030, 0.015), FVm=0.045, FSm=0.40,
               FV=0.020, FS=0.10, tau_max=20.0, torque_noise_std=0.25),
    AxisFamily("heavy_link", "heavy link on a small motor (JL/Jm = 10), f1 = 6 Hz",
               Jm=0.50, JL=5.0, K=_k_for(6.0, 0.50, 5.0), FVm=0.75, FSm=6.0, FV=6.0, FS=2.0,
               tau_max=400.0, torque_noise_std=5.0),
    AxisFamily("stiff_small", "stiff small axis (JL/Jm = 2), f1 = 20 Hz",
               Jm=0.004, JL=0.008, K=_k_for(20.0, 0.004, 0.008), FVm=0.006, FSm=0.08,
               FV=0.012, FS=0.02, tau_max=5.0, torque_noise_std=0.0625),
    AxisFamily("soft", "soft axis (JL/Jm = 3), f1 = 4 Hz",
               Jm=2.0, JL=6.0, K=_k_for(4.0, 2.0, 6.0), FVm=3.0, FSm=12.0, FV=8.0, FS=4.0,
               tau_max=800.0, torque_noise_std=10.0),
    AxisFamily("balanced", "balanced axis (JL/Jm = 1), f1 = 9 Hz",
               Jm=0.20, JL=0.20, K=_k_for(9.0, 0.20, 0.20), FVm=0.30, FSm=1.0, FV=0.30,
               FS=0.30, tau_max=60.0, torque_noise_std=0.75),
)}


def frictionless(family: AxisFamily) -> AxisFamily:
    """`family` with every friction set to zero."""
    return replace(family, FVm=0.0, FSm=0.0, FV=0.0, FS=0.0)


def default_substeps(family: AxisFamily, sample_rate_hz: float = PAPER_RATE,
                     effects: Plant = Plant()) -> int:
    """RK4 substeps per control period: w1 dt <= STEP_PHASE and the stiffest friction rate
    ((FS / v_s + FV) / J, motor or link) times dt <= STEP_FRICTION; the effects' extra
    stiffness (hardening), damping and friction count in."""
    T = 1.0 / sample_rate_hz
    inv_j = 1.0 / family.Jm + 1.0 / family.JL
    FSm = family.FSm * (1.0 + abs(effects.asymmetry))
    rate = max((FSm / family.v_s + family.FVm) / family.Jm,
               (family.FS + effects.link_coulomb) / family.v_s / family.JL + family.FV / family.JL,
               effects.damping * inv_j)
    w1 = math.sqrt((family.K + effects.hardening) * inv_j)
    return max(1, math.ceil(w1 * T / STEP_PHASE), math.ceil(rate * T / STEP_FRICTION))


State = tuple[float, float, float, float]   # (qm, q, qm', q') [rad, rad, rad/s, rad/s]


def make_stepper(family: AxisFamily, gravity: float, T: float, substeps: int,
                 effects: Plant = Plant(), tau_init: float = 0.0) -> Callable[[State, float], State]:
    """The plant over one control period: `step(x, tau)` integrates eqs. (5)-(6) from state x
    by `substeps` RK4 steps with the torque tau held constant (zero-order hold). With
    `effects`, their terms (jointbench.testing.hidden_effects); a torque lag keeps the rotor's
    torque, starting at `tau_init`, inside the stepper."""
    if effects != Plant():
        return stepper_with_effects(family, gravity, T, substeps, effects, tau_init)
    Jm, JL, K = family.Jm, family.JL, family.K
    FVm, FSm, FV, FS, inv_vs = family.FVm, family.FSm, family.FV, family.FS, 1.0 / family.v_s
    gx, gy = family.MX * gravity, family.MY * gravity
    has_gravity = gx != 0.0 or gy != 0.0
    h = T / substeps
    tanh, cos, sin = math.tanh, math.cos, math.sin

    def accel(qm: float, q: float, vm: float, v: float, tau: float) -> tuple[float, float]:
        spring = K * (qm - q)
        am = (tau - FVm * vm - FSm * tanh(vm * inv_vs) - spring) / Jm
        load = spring - FV * v - FS * tanh(v * inv_vs)
        if has_gravity:
            load -= gx * cos(q) + gy * sin(q)
        return am, load / JL

    def step(x: State, tau: float) -> State:
        for _ in range(substeps):
            x = rk4_step(accel, x, h, tau, tau, tau)
        return x

    return step


def energy(family: AxisFamily, x: State) -> float:
    """Kinetic plus spring energy [J] of state x (no gravity)."""
    qm, q, vm, v = x
    return 0.5 * (family.Jm * vm**2 + family.JL * v**2 + family.K * (qm - q) ** 2)


def open_loop(family: AxisFamily, x0: State, tau: np.ndarray, sample_rate_hz: float = PAPER_RATE,
              substeps: int | None = None, gravity: float = 9.81, effects=None,
              tau_init: float = 0.0) -> np.ndarray:
    """States at every tick (len(tau) + 1 rows: x0, then after each tick) under the held
    torques `tau` [N m], loop open; `effects` as in `simulate` (a torque lag starts from
    the rotor torque `tau_init`)."""
    extra = plant(as_hidden(effects), family.K, family.gear_ratio, True)
    n = default_substeps(family, sample_rate_hz, extra) if substeps is None else substeps
    step = make_stepper(family, gravity, 1.0 / sample_rate_hz, n, extra, tau_init)
    out = np.empty((len(tau) + 1, 4))
    x = tuple(float(v) for v in x0)
    out[0] = x
    for k, u in enumerate(tau.tolist()):
        x = step(x, u)
        out[k + 1] = x
    return out


class ContractController:
    """docs/controller.md, from its text: velocity by backward difference of the measured motor
    angle, PI velocity loop, optional velocity feedforward, clip at tau_max;
    q_m[-1] = q_m[0], q_ref[-1] = q_ref[0], I[-1] = tau0. Call it with (q_m[k], q_ref[k])."""

    def __init__(self, gains: Gains, T: float, tau0: float):
        self.gains, self.T = gains, T
        self.ff = 1.0 if gains.velocity_feedforward else 0.0
        self.integral = tau0
        self.previous: tuple[float, float] | None = None
        self.saturated = 0

    def __call__(self, q_m: float, q_ref: float) -> float:
        g, T = self.gains, self.T
        qm_prev, qref_prev = self.previous if self.previous is not None else (q_m, q_ref)
        self.previous = (q_m, q_ref)
        w = (q_m - qm_prev) / T
        e = g.kp * (q_ref - q_m) + self.ff * (q_ref - qref_prev) / T - w
        self.integral += g.ki * T * e
        tau = g.kv * e + self.integral
        if abs(tau) > g.tau_max:
            self.saturated += 1
            tau = math.copysign(g.tau_max, tau)
        return tau


@dataclass(frozen=True)
class Reference:
    """The chirp q_ref(t) = center + env(t) sin(phase(t)) from f_lo to f_hi [Hz], linear or
    logarithmic sweep over `duration` [s]; env is the amplitude [rad] faded in and out by
    raised cosines of `taper` [s] (so it starts at rest, zero slope), and capped so that
    env (2 pi f)^2 <= max_acceleration [rad/s^2]."""

    duration: float
    sweep: str = "linear"
    f_lo: float = 0.05
    f_hi: float = 30.0
    amplitude: float = 0.1
    taper: float = DEFAULT_TAPER
    max_acceleration: float = math.inf

    def __post_init__(self):
        if self.sweep not in ("linear", "log"):
            raise ValueError(f"sweep must be 'linear' or 'log', got {self.sweep!r}")
        if not 0 < self.f_lo < self.f_hi:
            raise ValueError(f"need 0 < f_lo < f_hi, got {self.f_lo}, {self.f_hi}")
        if not 0 <= 2 * self.taper <= self.duration:
            raise ValueError(f"taper {self.taper} s does not fit twice in {self.duration} s")

    def frequency(self, t: np.ndarray) -> np.ndarray:
        if self.sweep == "linear":
            return self.f_lo + (self.f_hi - self.f_lo) * t / self.duration
        return self.f_lo * (self.f_hi / self.f_lo) ** (t / self.duration)

    def phase(self, t: np.ndarray) -> np.ndarray:
        """2 pi times the integral of the frequency from 0 to t."""
        if self.sweep == "linear":
            return TWO_PI * (self.f_lo * t + (self.f_hi - self.f_lo) * t**2 / (2 * self.duration))
        ratio = self.f_hi / self.f_lo
        return TWO_PI * self.f_lo * self.duration / math.log(ratio) * (ratio ** (t / self.duration) - 1)

    def __call__(self, t: np.ndarray, center: float = 0.0) -> np.ndarray:
        env = np.full(t.shape, self.amplitude)
        if self.taper > 0:
            fade = np.clip(np.minimum(t, self.duration - t) / self.taper, 0.0, 1.0)
            env *= 0.5 * (1.0 - np.cos(np.pi * fade))
        env = np.minimum(env, self.max_acceleration / (TWO_PI * self.frequency(t)) ** 2)
        return center + env * np.sin(self.phase(t))

    def describe(self) -> str:
        return (f"{self.sweep} {self.f_lo:g}-{self.f_hi:g} Hz, amplitude {self.amplitude:g} rad, "
                f"{self.duration:g} s, taper {self.taper:g} s, acceleration cap "
                f"{self.max_acceleration:.6g} rad/s^2")


def _quantiser(counts_per_turn: float) -> Callable[[float], float]:
    if counts_per_turn <= 0:
        return float
    res = TWO_PI / counts_per_turn
    return lambda x: round(x / res) * res


def _fmt(x: float) -> str:
    return f"{x:.10g}"


def default_reference(family: AxisFamily, duration: float, sweep: str = "linear",
                      reductions: int = 0) -> Reference:
    """`simulate`'s default reference, shrunk `reductions` times (as after that many
    saturated runs; the log's `amplitude_reductions`)."""
    reference = Reference(duration, sweep, taper=min(DEFAULT_TAPER, duration / 4),
                          max_acceleration=ACCELERATION_SHARE * family.tau_max
                          / (family.Jm + family.JL))
    for _ in range(reductions):
        reference = _reduced(reference)
    return reference


def _reduced(reference: Reference) -> Reference:
    return replace(reference, amplitude=0.7 * reference.amplitude,
                   max_acceleration=0.6 * reference.max_acceleration)


def simulate(family: AxisFamily, seed: int = 1, duration: float = 60.0, sweep: str = "linear",
             feedforward: bool = True, *, sample_rate_hz: float = PAPER_RATE,
             substeps: int | None = None, gravity: float = 9.81, center: float | None = None,
             reference: Reference | None = None, gains: Gains | None = None,
             ideal_sensors: bool = False, effects=None,
             torque_noise_std: float | None = None) -> Log:
    """One closed-loop chirp experiment on `family`, as a jointbench log (docs/log-format.md).

    The default reference is `Reference(duration, sweep)` (0.05-30 Hz, 0.1 rad, 2 s tapers,
    a quarter of the duration in logs under 8 s)
    with its acceleration capped at ACCELERATION_SHARE tau_max / (Jm + JL); the default gains
    are `gains_rule(Jm, JL, K, tau_max, T)` (the bench's rule). The link rests at `center`
    [rad] in static equilibrium (the motor deflected by the gravity torque / K, the integrator
    holding that torque); `center` defaults to the rest angle (`AxisFamily.rest_angle`).
    `ideal_sensors`: no quantisation and no torque noise; `torque_noise_std` [N m] replaces
    the family's noise level. `effects`: hidden effects (jointbench.testing.hidden_effects: a
    Hidden, a tuple of them, or simulate --effect's text such as "backlash=0.002,offset=1"); the
    gravity effect moves the centre `strength` from the rest angle.
    """
    T = 1.0 / sample_rate_hz
    hidden = as_hidden(effects)
    extra = plant(hidden, family.K, family.gear_ratio, family.MX != 0.0 or family.MY != 0.0)
    center = (family.rest_angle if center is None else center) + extra.center_shift
    n_sub = default_substeps(family, sample_rate_hz, extra) if substeps is None else substeps
    auto = reference is None
    if reference is None:
        reference = default_reference(family, duration, sweep)
    if gains is None:
        gains = gains_rule(family.Jm, family.JL, family.K, family.tau_max, T)
    gains = replace(gains, velocity_feedforward=feedforward)
    motor_counts = 0.0 if ideal_sensors else family.motor_counts_per_turn
    link_counts = 0.0 if ideal_sensors else family.link_counts_per_turn
    noise_std = 0.0 if ideal_sensors else family.torque_noise_std if torque_noise_std is None \
        else torque_noise_std

    reductions = 0
    while True:
        run = _run(family, reference, gains, seed, sample_rate_hz, n_sub, gravity, center,
                   motor_counts, link_counts, noise_std, extra)
        # The default reference shrinks until nothing saturates (the bench's rule): near the
        # antiresonance sqrt(K / JL) the motor needs more torque than the acceleration cap
        # foresees.
        if not auto or run["saturated"] == 0 or reductions >= MAX_REDUCTIONS:
            break
        reductions += 1
        reference = _reduced(reference)
    meta = {"sample_rate_hz": _fmt(sample_rate_hz), "gravity": _fmt(gravity)}
    meta.update(gains.to_meta())
    meta.update({
        "joint": family.name,
        "source": "jointbench.testing.simulator: numpy two-mass axis, no MuJoCo",
        "seed": str(seed), "substeps": str(n_sub), "integrator": "RK4 (fixed step, numpy)",
        "coulomb_smoothing_rad_s": _fmt(family.v_s),
        "chirp": reference.describe(),
        "saturated_samples": str(run["saturated"]),
        "amplitude_reductions": str(reductions),
        "motor_encoder_resolution_rad": f"{TWO_PI / motor_counts if motor_counts else 0.0:.6g}",
        "link_encoder_resolution_rad": f"{TWO_PI / link_counts if link_counts else 0.0:.6g}",
        "torque_noise_std": f"{noise_std:.6g}",
    })
    for key, value in family.truth().items():
        meta[f"truth_{key}"] = _fmt(value)
    meta["truth_center"] = _fmt(center)
    meta.update(truth_meta(hidden))
    return Log(t=run["t"], q_m=run["q_m"], tau_m=run["tau"], q=run["q"], q_ref=run["q_ref"],
               meta=meta)


def _run(family: AxisFamily, reference: Reference, gains: Gains, seed: int,
         sample_rate_hz: float, substeps: int, gravity: float, center: float,
         motor_counts: float, link_counts: float, noise_std: float,
         effects: Plant = Plant()) -> dict:
    """The control loop of `simulate`: the sampled signals and the saturated sample count."""
    T = 1.0 / sample_rate_hz
    quant_m, quant_l = _quantiser(motor_counts), _quantiser(link_counts)
    n = int(round(reference.duration * sample_rate_hz)) + 1
    t = np.arange(n) * T
    tau_g = gravity * (family.MX * math.cos(center) + family.MY * math.sin(center))
    # Static equilibrium: the spring holds the gravity torque, the integrator that plus the
    # offset (the rotor gets tau - c).
    tau0 = tau_g + effects.offset
    x: State = (center + spring_deflection(family.K, effects, tau_g), center, 0.0, 0.0)
    # The reference starts at the measured motor angle: e[0] = 0 and tau_m[0] = tau0 = I[-1].
    q_ref = reference(t, quant_m(x[0]))
    rng = np.random.default_rng(seed)
    noise = rng.normal(0.0, noise_std, n) if noise_std > 0 else np.zeros(n)
    step = make_stepper(family, gravity, T, substeps, effects, tau0)
    ctrl = ContractController(gains, T, tau0)
    q_m, q, tau = np.empty(n), np.empty(n), np.empty(n)
    for k, (r, w) in enumerate(zip(q_ref.tolist(), noise.tolist())):
        q_m[k], q[k] = quant_m(x[0]), quant_l(x[1])
        tau[k] = ctrl(q_m[k], r)
        x = step(x, tau[k] + w)
    return {"t": t, "q_m": q_m, "q": q, "tau": tau, "q_ref": q_ref,
            "saturated": ctrl.saturated}


# --- The lab rig: a voltage-driven rotary flexible joint under a proportional position loop --


@dataclass(frozen=True)
class LabRig:
    """A lab rotary flexible joint: a DC servo behind a gearbox of ratio `N` (no backlash)
    turns a hub; an arm rides on the hub on springs; the axis is horizontal (no gravity torque).

    The drive is a voltage: the rotor torque, joint side, is

        tau = eta N Kt (u - Ke N qm') / R = g_u u - B_emf qm',
        g_u = eta N Kt / R [N m/V],   B_emf = eta N^2 Kt Ke / R [N m s/rad],

    (eta = eta_gear eta_motor), so the back-EMF is a viscous damping on the motor side, heavy
    beside the mechanical one: the log's tau_m is g_u u (the command times the catalogue
    constant) and the back-EMF is part of FVm (`truth_FVm` = FVm_mech + B_emf,
    `truth_FVm_back_emf` = B_emf). Encoders of `counts` per turn read the servo output angle
    theta = qm (joint side) and the spring deflection alpha = qm - q; the log's q is
    theta - alpha (both quantised), and the columns theta, alpha and u are kept as they are.
    `family` holds the mechanics with FVm = FVm_mech + B_emf (the plant of eqs. 5-6)."""

    Jm: float = 0.0020          # kg m^2, servo and gear, joint side
    JL: float = 0.0035          # kg m^2, hub and arm
    K: float = 1.6              # N m/rad, the springs
    FVm_mech: float = 0.004     # N m s/rad, gear and bearings, joint side
    FSm: float = 0.004          # N m, Coulomb friction of the servo, joint side
    FV: float = 0.0015          # N m s/rad, light link damping
    N: float = 70.0             # gear ratio
    Kt: float = 7.68e-3         # N m/A, torque constant
    Ke: float = 7.68e-3         # V s/rad, back-EMF constant
    R: float = 2.6              # Ohm, armature resistance
    eta_gear: float = 0.9
    eta_motor: float = 0.69
    u_max: float = 10.0         # V, the amplifier's limit
    counts: float = 4096.0      # counts per turn of each encoder
    voltage_noise_std: float = 0.02   # V, white noise on the applied voltage

    @property
    def volt_to_torque(self) -> float:
        """g_u = eta N Kt / R [N m/V]."""
        return self.eta_gear * self.eta_motor * self.N * self.Kt / self.R

    @property
    def back_emf_damping(self) -> float:
        """B_emf = eta N^2 Kt Ke / R [N m s/rad], joint side."""
        return self.volt_to_torque * self.N * self.Ke

    @property
    def family(self) -> AxisFamily:
        g = self.volt_to_torque
        return AxisFamily("lab_rig", "lab rotary flexible joint, voltage drive, P loop",
                          Jm=self.Jm, JL=self.JL, K=self.K,
                          FVm=self.FVm_mech + self.back_emf_damping, FSm=self.FSm,
                          FV=self.FV, FS=0.0, tau_max=g * self.u_max,
                          torque_noise_std=g * self.voltage_noise_std,
                          motor_counts_per_turn=self.counts, link_counts_per_turn=self.counts,
                          gear_ratio=self.N)

    @property
    def link_mode_hz(self) -> float:
        """The link mode sqrt(K / JL) / 2 pi [Hz]: the resonance of q / q_m."""
        return math.sqrt(self.K / self.JL) / TWO_PI


@dataclass(frozen=True)
class Multisine:
    """A random-phase multisine: `components` frequencies spread logarithmically over
    f_lo-f_hi [Hz], equal amplitudes scaled to an RMS of `rms` [rad or V], phases uniform from
    the seed, faded in and out by raised cosines of `taper` [s]."""

    duration: float
    f_lo: float = 0.025
    f_hi: float = 10.0
    rms: float = 0.5
    components: int = 80
    taper: float = 1.0

    def __call__(self, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        f = self.f_lo * (self.f_hi / self.f_lo) ** np.linspace(0.0, 1.0, self.components)
        phase = rng.uniform(0.0, TWO_PI, self.components)
        a = self.rms * math.sqrt(2.0 / self.components)
        x = a * np.sin(TWO_PI * np.outer(t, f) + phase).sum(axis=1)
        fade = np.clip(np.minimum(t, self.duration - t) / self.taper, 0.0, 1.0)
        return x * 0.5 * (1.0 - np.cos(np.pi * fade))

    def describe(self) -> str:
        return (f"random-phase multisine {self.f_lo:g}-{self.f_hi:g} Hz, {self.components} "
                f"log-spaced components, RMS {self.rms:g}, {self.duration:g} s, taper "
                f"{self.taper:g} s")


@dataclass(frozen=True)
class PositionLoop:
    """docs/controller.md section 3, written here again from its text: a `kind` P, PD, PI or
    PID loop on `feedback` ("q_m" or "q") with kp [N m/rad], ki [N m/(rad s)], kd
    [N m s/rad]; `feedforward`: the derivative acts on the error, else on the measurement."""

    kind: str = "P"
    kp: float = 0.0
    ki: float = 0.0
    kd: float = 0.0
    feedback: str = "q_m"
    feedforward: bool = False

    def meta(self, tau_max: float) -> dict[str, str]:
        out = {"controller": self.kind, "feedback": self.feedback, "pid_kp": _fmt(self.kp),
               "tau_max": _fmt(tau_max),
               "velocity_feedforward": "true" if self.feedforward else "false"}
        if "I" in self.kind:
            out["pid_ki"] = _fmt(self.ki)
        if "D" in self.kind:
            out["pid_kd"] = _fmt(self.kd)
        return out

    def law(self, T: float) -> Callable[[float, float, float], float]:
        """tau(r, y) per tick; y[-1] = y[0], r[-1] = r[0], I[-1] = 0 (the rig starts at rest
        with no torque)."""
        state = {"prev": None, "I": 0.0}

        def tau(r: float, y: float) -> float:
            y_prev, r_prev = state["prev"] if state["prev"] is not None else (y, r)
            state["prev"] = (y, r)
            state["I"] += self.ki * T * (r - y)
            d = ((r - r_prev) if self.feedforward else 0.0) - (y - y_prev)
            return self.kp * (r - y) + state["I"] + self.kd * d / T

        return tau


LAB_RIG = LabRig()
LAB_RIG_RATE = 500.0    # Hz
LAB_RIG_KP = 1.0        # V/rad, the proportional position loop u = Kp (r - theta)


def simulate_lab_rig(rig: LabRig = LAB_RIG, seed: int = 1, duration: float = 40.0,
                     closed_loop: bool = True, *, kp_volt: float = LAB_RIG_KP,
                     reference: Multisine | None = None, loop: PositionLoop | None = None,
                     sample_rate_hz: float = LAB_RIG_RATE, effects=None) -> Log:
    """One run of the lab rig as a jointbench log (docs/log-format.md).

    Closed loop: u[k] = clip(Kp (r[k] - theta[k]), +-u_max) with Kp = `kp_volt` [V/rad] on
    the measured servo angle, r a random-phase multisine (default 0.025-10 Hz, RMS 0.5 rad);
    the metadata describes it as docs/controller.md's P loop on q_m with pid_kp = g_u Kp
    [N m/rad] and tau_max = g_u u_max. `loop`: another position loop (its torque
    command sent as u = tau / g_u) in place of the lab's. Open loop: u is the multisine itself (RMS 1 V), and
    the log has no q_ref nor controller. The voltage noise adds to the applied voltage, not to
    the logged command. The plant is eqs. (5)-(6) with the back-EMF in FVm (`LabRig`),
    integrated by RK4 as `simulate`. `effects`: hidden effects as `simulate`'s (no `gravity`:
    the rig's link has no mass), evaluated inside the RK4 stages on the joint-side torque
    g_u (u + noise). Same arguments, the same log bit for bit."""
    family = rig.family
    T = 1.0 / sample_rate_hz
    g = rig.volt_to_torque
    if reference is None:
        reference = Multisine(duration, rms=0.5 if closed_loop else 1.0)
    n = int(round(duration * sample_rate_hz)) + 1
    t = np.arange(n) * T
    rng = np.random.default_rng(seed)
    r = reference(t, rng)
    noise = rng.normal(0.0, rig.voltage_noise_std, n)
    hidden = as_hidden(effects)
    if hidden:
        extra = plant(hidden, family.K, family.gear_ratio, False)
        n_sub = default_substeps(family, sample_rate_hz, extra)
        step = stepper_with_effects(family, 0.0, T, n_sub, extra, 0.0)
    else:
        n_sub = default_substeps(family, sample_rate_hz)
        step = make_stepper(family, 0.0, T, n_sub)
    quant = _quantiser(rig.counts)
    x: State = (0.0, 0.0, 0.0, 0.0)
    if loop is None:
        loop = PositionLoop("P", kp=g * kp_volt)
    law = loop.law(T)
    theta, alpha, u = np.empty(n), np.empty(n), np.empty(n)
    saturated = 0
    for k in range(n):
        theta[k], alpha[k] = quant(x[0]), quant(x[0] - x[1])
        y = theta[k] if loop.feedback == "q_m" else theta[k] - alpha[k]
        v = law(r[k], y) / g if closed_loop else r[k]
        if abs(v) > rig.u_max:
            saturated += 1
            v = math.copysign(rig.u_max, v)
        u[k] = v
        x = step(x, g * (v + noise[k]))
    meta = {"sample_rate_hz": _fmt(sample_rate_hz), "gravity": "0",
            "joint": "lab_rig",
            "source": "jointbench tests/indep_sim.py: numpy lab rig (voltage drive), no MuJoCo",
            "seed": str(seed), "substeps": str(n_sub), "integrator": "RK4 (fixed step, numpy)",
            "coulomb_smoothing_rad_s": _fmt(family.v_s),
            "excitation": reference.describe() + (" (reference r [rad])" if closed_loop
                                                  else " (voltage u [V])"),
            "saturated_samples": str(saturated),
            "motor_encoder_resolution_rad": f"{TWO_PI / rig.counts if rig.counts else 0.0:.6g}",
            "link_encoder_resolution_rad": f"{TWO_PI / rig.counts if rig.counts else 0.0:.6g}",
            "torque_noise_std": f"{g * rig.voltage_noise_std:.6g}",
            "drive": (f"voltage: tau_m = {g:.6g} N m/V x u; back-EMF damping "
                      f"{rig.back_emf_damping:.6g} N m s/rad is part of FVm"),
            "gear_ratio": _fmt(rig.N)}
    if closed_loop:
        meta.update(loop.meta(g * rig.u_max))
    else:
        meta["controller_note"] = "open loop: u is the excitation"
    for key, value in family.truth().items():
        meta[f"truth_{key}"] = _fmt(value)
    meta["truth_MX"] = meta["truth_MY"] = "0"
    meta["truth_FVm_back_emf"] = _fmt(rig.back_emf_damping)
    meta["truth_link_mode_hz"] = _fmt(rig.link_mode_hz)
    if hidden:
        meta.update(truth_meta(hidden))
    return Log(t=t, q_m=theta, tau_m=g * u, q=theta - alpha,
               q_ref=r if closed_loop else None,
               extra={"theta": theta, "alpha": alpha, "u": u}, meta=meta)
