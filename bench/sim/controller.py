"""The discrete PI position/velocity controller of docs/controller.md.

One implementation serves the virtual experiment and the closed-loop replay of a measured log.
Feedback is on the motor encoder only; the torque is held between samples (zero-order hold).

    w[k]     = (q_m[k] - q_m[k-1]) / T
    v_ref[k] = kp (q_ref[k] - q_m[k]) + ff (q_ref[k] - q_ref[k-1]) / T
    e[k]     = v_ref[k] - w[k]
    I[k]     = I[k-1] + ki T e[k]
    tau_m[k] = clip(kv e[k] + I[k], -tau_max, tau_max)
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

    def step(self, q_m: float, q_ref: float) -> float:
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


def control_law(q_m: np.ndarray, q_ref: np.ndarray, gains: Gains, T: float,
                tau0: float) -> np.ndarray:
    """tau_m[k] that the law computes on the logged q_m and q_ref (open loop over the data):
    a check that a log's metadata describes the controller that produced it."""
    ctrl = PIController(gains, T, tau0)
    return np.array([ctrl.step(float(a), float(b)) for a, b in zip(q_m, q_ref)])
