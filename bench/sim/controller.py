"""The discrete controllers a log's metadata describes (docs/controller.md).

One implementation serves the virtual experiment and the closed-loop replay of a measured log;
the torque is held between samples (zero-order hold). The default, the PI cascade (section 2),
feeds back the motor encoder:

    w[k]     = (q_m[k] - q_m[k-1]) / T
    v_ref[k] = kp (q_ref[k] - q_m[k]) + ff (q_ref[k] - q_ref[k-1]) / T
    e[k]     = v_ref[k] - w[k]
    I[k]     = I[k-1] + ki T e[k]
    tau_m[k] = clip(kv e[k] + I[k], -tau_max, tau_max)

The position loops P, PD, PI and PID (section 3, metadata `controller`) feed back y = q_m or
q (`feedback`):

    e[k]     = q_ref[k] - y[k]
    I[k]     = I[k-1] + ki T e[k]
    D[k]     = kd (ff (q_ref[k] - q_ref[k-1]) - (y[k] - y[k-1])) / T
    tau_m[k] = clip(kp e[k] + I[k] + D[k], -tau_max, tau_max)

A general discrete transfer function C(z) (section 3.3, `controller: TF`) runs as its
difference equation on e[k] = q_ref[k] - y[k].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from jointbench.identification.log import Log, LogError, format_meta_number


@dataclass(frozen=True)
class Gains:
    """Controller gains: kp [1/s], kv [N m s/rad], ki [N m/rad], tau_max [N m]."""

    kp: float
    kv: float
    ki: float
    tau_max: float
    velocity_feedforward: bool = True

    def to_meta(self) -> dict[str, str]:
        return {"kp": format_meta_number(self.kp), "kv": format_meta_number(self.kv),
                "ki": format_meta_number(self.ki), "tau_max": format_meta_number(self.tau_max),
                "velocity_feedforward": "true" if self.velocity_feedforward else "false"}

    @classmethod
    def from_log(cls, log: Log) -> "Gains":
        """Gains from a log's metadata; LogError when any of kp, kv, ki, tau_max is missing."""
        values = {key: log.meta_float(key) for key in ("kp", "kv", "ki", "tau_max")}
        missing = [key for key, value in values.items() if value is None]
        if missing:
            raise LogError("cannot replay: the metadata lacks the controller gains "
                           f"{', '.join(missing)} (docs/controller.md)", log.path)
        return cls(velocity_feedforward=log.meta_bool("velocity_feedforward", True), **values)


def gains_rule(Jm: float, JL: float, K: float, tau_max: float, T: float) -> Gains:
    """The default gain rule, from the axis' own parameters (no hand tuning).

    The velocity loop is a PI on the rigid inertia J = Jm + JL with crossover wv = min(w1, 0.1
    w_s) where w1 = sqrt(K (1/Jm + 1/JL)) is the locked first mode (the motor-side loop is
    collocated, so crossing at the mode is safe; 0.1 w_s keeps the sampling delay's phase loss
    under 20 degrees). The PI zero sits a factor four below wv (ki = kv wv / 4) and the
    position loop crosses a factor four below wv too (kp = wv / 4): the usual cascade
    separation. Stability on both shipped models is checked by tests/unit/test_controller.py.
    """
    w1 = math.sqrt(K * (1.0 / Jm + 1.0 / JL))
    wv = min(w1, 0.1 * 2.0 * math.pi / T)
    kv = (Jm + JL) * wv
    return Gains(kp=wv / 4.0, kv=kv, ki=kv * wv / 4.0, tau_max=tau_max)


CASCADE = "PI cascade"
POSITION_KINDS = ("P", "PD", "PI", "PID")   # the position loops: which of kp, ki, kd they use
FEEDBACK = ("q_m", "q")
POSITION_KEYS = {"kp": "pid_kp", "ki": "pid_ki", "kd": "pid_kd"}   # metadata key of each gain


@dataclass(frozen=True)
class PositionGains:
    """A position loop (module docstring): `kind` one of POSITION_KINDS, kp [N m/rad],
    ki [N m/(rad s)], kd [N m s/rad] (the gains a kind does not name are zero), tau_max [N m],
    `feedback` the position fed back ("q_m" or "q"), `velocity_feedforward`: the derivative
    acts on the error (true) or on the measurement alone (false)."""

    kind: str
    kp: float
    tau_max: float
    ki: float = 0.0
    kd: float = 0.0
    feedback: str = "q_m"
    velocity_feedforward: bool = False

    def __post_init__(self):
        if self.kind not in POSITION_KINDS:
            raise ValueError(f"controller kind must be one of {', '.join(POSITION_KINDS)} or "
                             f"{CASCADE!r}, got {self.kind!r}")
        if self.feedback not in FEEDBACK:
            raise ValueError(f"feedback must be one of {', '.join(FEEDBACK)}, got "
                             f"{self.feedback!r}")
        unused = [g for g in ("ki", "kd") if getattr(self, g) != 0
                  and g[1].upper() not in self.kind]
        if unused:
            raise ValueError(f"a {self.kind} loop has no {', '.join(unused)}")

    def to_meta(self) -> dict[str, str]:
        meta = {"controller": self.kind, "feedback": self.feedback,
                "tau_max": format_meta_number(self.tau_max),
                "velocity_feedforward": "true" if self.velocity_feedforward else "false"}
        for gain, key in POSITION_KEYS.items():
            if gain == "kp" or gain[1].upper() in self.kind:
                meta[key] = format_meta_number(getattr(self, gain))
        return meta

    def describe(self) -> str:
        gains = ", ".join(f"{g} {getattr(self, g):g}" for g in ("kp", "ki", "kd")
                          if g == "kp" or g[1].upper() in self.kind)
        ff = "on" if self.velocity_feedforward else "off"
        return (f"{self.kind} position loop on {self.feedback} ({gains}, tau_max "
                f"{self.tau_max:g}" + (f", velocity feed-forward {ff})" if "D" in self.kind
                                       else ")"))


TF = "TF"   # a general discrete transfer function (section 3.3)


@dataclass(frozen=True)
class TransferGains:
    """A position loop u = C(z) (q_ref - y) (docs/controller.md section 3.3): C(z) =
    (b0 + b1 z^-1 + ...) / (a0 + a1 z^-1 + ...), `num` the b, `den` the a (a0 != 0),
    tau_max [N m], `feedback` "q_m" or "q"."""

    num: tuple[float, ...]
    den: tuple[float, ...]
    tau_max: float
    feedback: str = "q_m"

    def __post_init__(self):
        if not self.num or not self.den or self.den[0] == 0:
            raise ValueError("a transfer function needs a numerator and a denominator whose "
                             "first coefficient is not zero")
        if self.feedback not in FEEDBACK:
            raise ValueError(f"feedback must be one of {', '.join(FEEDBACK)}, got "
                             f"{self.feedback!r}")

    @classmethod
    def from_control(cls, sys, tau_max: float, feedback: str = "q_m") -> "TransferGains":
        """From a discrete python-control transfer function (`control.tf(num, den, dt)`,
        SISO, coefficients in descending powers of z, padded to z^-1 powers)."""
        num = [float(x) for x in sys.num[0][0]]
        den = [float(x) for x in sys.den[0][0]]
        num = [0.0] * (len(den) - len(num)) + num   # b z^-d: the delay of a lower degree
        return cls(tuple(num), tuple(den), tau_max, feedback)

    def to_meta(self) -> dict[str, str]:
        return {"controller": TF, "feedback": self.feedback,
                "tau_max": format_meta_number(self.tau_max),
                "tf_num": " ".join(format_meta_number(x) for x in self.num),
                "tf_den": " ".join(format_meta_number(x) for x in self.den)}

    def describe(self) -> str:
        return (f"transfer function on {self.feedback} (num {list(self.num)}, den "
                f"{list(self.den)} in powers of z^-1, tau_max {self.tau_max:g})")


class TransferController:
    """State of a transfer-function loop: a0 u[k] = sum b_i e[k-i] - sum_{i>=1} a_i u[k-i],
    clipped at tau_max (the state keeps the unclipped output: no anti-windup). At k = 0 the
    past errors equal e[0] and the past outputs the logged initial torque tau0 (at rest)."""

    def __init__(self, gains: TransferGains, T: float, tau0: float = 0.0):
        self.gains = gains
        self.tau0 = float(tau0)
        self.link = gains.feedback == "q"
        self._e: list[float] | None = None
        self._u: list[float] = []
        self.saturated = 0

    def step(self, q_m: float, q_ref: float, q: float | None = None) -> float:
        g = self.gains
        y = q if self.link else q_m
        if y is None:
            raise ValueError("a loop on q needs the link position")
        e = q_ref - y
        if self._e is None:
            self._e = [e] * (len(g.num) - 1)
            self._u = [self.tau0] * (len(g.den) - 1)
        es = [e] + self._e
        u = (sum(b * x for b, x in zip(g.num, es))
             - sum(a * x for a, x in zip(g.den[1:], self._u))) / g.den[0]
        self._e = es[:len(g.num) - 1]
        self._u = ([u] + self._u)[:len(g.den) - 1]
        if abs(u) > g.tau_max:
            self.saturated += 1
            return math.copysign(g.tau_max, u)
        return u


def _coefficients(log: Log, key: str) -> tuple[float, ...]:
    text = log.meta.get(key, "").replace(",", " ").split()
    try:
        values = tuple(float(x) for x in text)
    except ValueError:
        raise LogError(f"metadata '{key}': not a list of numbers: {log.meta.get(key)!r}",
                       log.path) from None
    if not values or not all(math.isfinite(v) for v in values):
        raise LogError(f"cannot replay: the metadata of a TF loop lacks {key} (numbers "
                       "separated by spaces, docs/controller.md section 3.3)", log.path)
    return values


def controller_from_log(log: Log) -> "Gains | PositionGains | TransferGains":
    """The controller a log's metadata describes (docs/controller.md): the PI cascade
    (`Gains.from_log`) when `controller` is absent or "PI cascade", else a position loop
    whose gains pid_kp (and pid_ki, pid_kd as its kind names them) and tau_max must be
    present. LogError names what is missing or wrong."""
    kind = log.meta.get("controller", CASCADE).strip()
    if kind.lower() in (CASCADE.lower(), "cascade"):
        return Gains.from_log(log)
    if kind.upper() == TF:
        tau_max = log.meta_float("tau_max")
        if tau_max is None:
            raise LogError("cannot replay: the metadata of a TF loop lacks tau_max", log.path)
        feedback = log.meta.get("feedback", "q_m").strip()
        try:
            return TransferGains(_coefficients(log, "tf_num"), _coefficients(log, "tf_den"),
                                 tau_max, feedback)
        except ValueError as err:
            raise LogError(f"metadata of a TF loop: {err}", log.path) from None
    if kind.upper() not in POSITION_KINDS:
        raise LogError(f"metadata 'controller': {kind!r} is none of {CASCADE!r}, "
                       f"{', '.join(POSITION_KINDS)}, {TF} (docs/controller.md)", log.path)
    kind = kind.upper()
    need = ["tau_max"] + [key for gain, key in POSITION_KEYS.items()
                          if gain == "kp" or gain[1].upper() in kind]
    values = {key: log.meta_float(key) for key in need}
    missing = [key for key, value in values.items() if value is None]
    if missing:
        raise LogError(f"cannot replay: the metadata of a {kind} loop lacks "
                       f"{', '.join(missing)} (docs/controller.md)", log.path)
    feedback = log.meta.get("feedback", "q_m").strip()
    if feedback not in FEEDBACK:
        raise LogError(f"metadata 'feedback': {feedback!r} is none of {', '.join(FEEDBACK)}",
                       log.path)
    return PositionGains(kind=kind, tau_max=values["tau_max"], feedback=feedback,
                         velocity_feedforward=log.meta_bool("velocity_feedforward", False),
                         **{gain: values[key] for gain, key in POSITION_KEYS.items()
                            if key in values})


def has_controller(log: Log) -> bool:
    """Does the metadata describe a controller completely (`controller_from_log` succeeds)?"""
    try:
        controller_from_log(log)
    except (LogError, ValueError):
        return False
    return True


class PositionController:
    """State of a position loop (module docstring). `step(q_m, q_ref, q)` returns tau_m[k].
    At k = 0: y[-1] = y[0], q_ref[-1] = q_ref[0], and I[-1] = tau0 - kp e[0] when the loop has
    an integrator (so that tau_m[0] = tau0: the experiment starts at rest, the integrator
    holding the logged initial torque), 0 without one."""

    def __init__(self, gains: PositionGains, T: float, tau0: float = 0.0):
        self.gains = gains
        self.kiT = float(gains.ki) * T
        self.kd_T = float(gains.kd) / T
        self.ff = 1.0 if gains.velocity_feedforward else 0.0
        self.tau0 = float(tau0)
        self.link = gains.feedback == "q"
        self._prev: tuple[float, float] | None = None
        self._I = 0.0
        self.saturated = 0

    def step(self, q_m: float, q_ref: float, q: float | None = None) -> float:
        g = self.gains
        y = q if self.link else q_m
        if y is None:
            raise ValueError("a position loop on q needs the link position")
        e = q_ref - y
        if self._prev is None:
            self._prev = (y, q_ref)
            self._I = self.tau0 - g.kp * e if g.ki != 0 else 0.0
        y_prev, r_prev = self._prev
        self._prev = (y, q_ref)
        self._I += self.kiT * e
        tau = g.kp * e + self._I + self.kd_T * (self.ff * (q_ref - r_prev) - (y - y_prev))
        if abs(tau) > g.tau_max:
            self.saturated += 1
            return math.copysign(g.tau_max, tau)
        return tau


def make_controller(gains: "Gains | PositionGains | TransferGains", T: float,
                    tau0: float = 0.0):
    """The stepped controller for `gains`: PIController (the cascade), PositionController or
    TransferController."""
    if isinstance(gains, PositionGains):
        return PositionController(gains, T, tau0)
    if isinstance(gains, TransferGains):
        return TransferController(gains, T, tau0)
    return PIController(gains, T, tau0)


def describe(gains: "Gains | PositionGains | TransferGains") -> str:
    """One line naming the controller and its gains (what a replay report prints)."""
    if isinstance(gains, (PositionGains, TransferGains)):
        return gains.describe()
    ff = "on" if gains.velocity_feedforward else "off"
    return (f"{CASCADE} (kp {gains.kp:g}, kv {gains.kv:g}, ki {gains.ki:g}, tau_max "
            f"{gains.tau_max:g}, velocity feed-forward {ff})")


class PIController:
    """State of the docs/controller.md law. `step` takes the sample k and returns tau_m[k].

    At k = 0: q_m[-1] = q_m[0], q_ref[-1] = q_ref[0] and I[-1] = tau0 (the logged initial
    torque: the experiment starts at rest in equilibrium).
    """

    __slots__ = ("kp", "kv", "kiT", "tau_max", "ff", "inv_T", "_qm_prev", "_qref_prev",
                 "_I", "saturated")

    def __init__(self, gains: Gains, T: float, tau0: float = 0.0):
        self.kp = float(gains.kp)
        self.kv = float(gains.kv)
        self.kiT = float(gains.ki) * T
        self.tau_max = float(gains.tau_max)
        self.ff = 1.0 if gains.velocity_feedforward else 0.0
        self.inv_T = 1.0 / T
        self._qm_prev: float | None = None
        self._qref_prev = 0.0
        self._I = float(tau0)
        self.saturated = 0  # number of samples clipped at tau_max

    def step(self, q_m: float, q_ref: float, q: float | None = None) -> float:
        """tau_m[k] from the motor encoder q_m[k] and q_ref[k] (`q` is not fed back)."""
        if self._qm_prev is None:
            self._qm_prev = q_m
            self._qref_prev = q_ref
        w = (q_m - self._qm_prev) * self.inv_T
        e = self.kp * (q_ref - q_m) + self.ff * (q_ref - self._qref_prev) * self.inv_T - w
        self._qm_prev = q_m
        self._qref_prev = q_ref
        self._I += self.kiT * e
        tau = self.kv * e + self._I
        if tau > self.tau_max:
            self.saturated += 1
            return self.tau_max
        if tau < -self.tau_max:
            self.saturated += 1
            return -self.tau_max
        return tau


def control_law(q_m: np.ndarray, q_ref: np.ndarray, gains: "Gains | PositionGains", T: float,
                tau0: float, q: np.ndarray | None = None) -> np.ndarray:
    """tau_m[k] that the law computes on the logged q_m, q_ref (and q, for a loop on the link)
    open loop over the data: a check that a log's metadata describes the controller that
    produced it."""
    ctrl = make_controller(gains, T, tau0)
    links = [None] * len(q_m) if q is None else np.asarray(q, float).tolist()
    return np.array([ctrl.step(float(a), float(b), c)
                     for a, b, c in zip(q_m, q_ref, links)])
