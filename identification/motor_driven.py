"""The motor-driven forward view: a forward view that needs no controller (docs/controller.md
section 4), for vendor drives whose loop nobody knows.

The measured motor angle q_m drives the link of eq. (5) (identification.link_sim
.simulate_link, exact between samples, the link Coulomb friction sticking and slipping): the
predicted link angle q is compared with the measured one. The motor torque of eq. (6),

    tau_m = Jm qm'' + FVm qm' + FSm sign(qm') + K (qm - q),

is predicted from q_m and the predicted q, both through a zero-phase Butterworth low-pass
(order 4, forward and backward) at the band's cutoff `fc_hz`, the derivatives by central
differences, and compared with the measured torque through the same low-pass: the view
judges the model in the band the identification used, where the differentiated encoder is
not noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

from jointbench.identification.link_sim import simulate_link
from jointbench.identification.log import Log


@dataclass(frozen=True)
class MotorDrivenView:
    """The predicted link angle `q` and band-limited torque `tau_m`, with `q_rms` [rad] and
    `q_rel_pct` (of the measured link motion about its mean), `tau_rel_pct` (RMS error over
    the RMS of the band-limited measured torque), `fc_hz` the band's cutoff."""

    q: np.ndarray
    tau_m: np.ndarray
    q_rms: float
    q_rel_pct: float
    tau_rel_pct: float
    fc_hz: float

    def text(self) -> str:
        return (f"motor-driven view (no controller needed: the measured q_m drives the model, "
                f"docs/controller.md section 4): link position q RMS error {self.q_rms:.3g} "
                f"({self.q_rel_pct:.3g} % of the motion), torque error {self.tau_rel_pct:.3g} "
                f"% RMS below {self.fc_hz:.3g} Hz")


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def motor_driven_view(log: Log, p: dict[str, float], fc_hz: float) -> MotorDrivenView:
    """The view of the module docstring for the joint-motor parameters `p` (Jm, FVm, FSm, K,
    JL, FV, FS, MX, MY; missing frictions and moments are zero). ValueError without q, for
    non-positive Jm, K, JL, or a cutoff outside (0, Nyquist)."""
    if log.q is None:
        raise ValueError("the motor-driven view needs the link position q")
    Jm, K, JL = p["Jm"], p["K"], p["JL"]
    if not (Jm > 0 and K > 0 and JL > 0):
        raise ValueError(f"the motor-driven view needs Jm, K, JL > 0 (got {Jm}, {K}, {JL})")
    fs = log.sample_rate_hz
    if not 0 < fc_hz < fs / 2:
        raise ValueError(f"cutoff {fc_hz} Hz outside (0, {fs / 2}) Hz")
    g = log.gravity
    q, _ = simulate_link(log.q_m, log.ts, K / JL, max(p.get("FV", 0.0), 0.0) / JL,
                         max(p.get("FS", 0.0), 0.0) / JL, g * p.get("MX", 0.0) / JL,
                         g * p.get("MY", 0.0) / JL)
    sos = signal.butter(4, fc_hz, fs=fs, output="sos")

    def low(x: np.ndarray) -> np.ndarray:
        return signal.sosfiltfilt(sos, np.asarray(x, float))

    qm, ql, tau = low(log.q_m), low(q), low(log.tau_m)
    qd = np.gradient(qm, log.ts)
    qdd = np.gradient(qd, log.ts)
    pred = (Jm * qdd + p.get("FVm", 0.0) * qd + p.get("FSm", 0.0) * np.sign(qd)
            + K * (qm - ql))
    motion = _rms(log.q - np.mean(log.q))
    e_q = _rms(q - log.q)
    den = _rms(tau)
    return MotorDrivenView(q=q, tau_m=pred, q_rms=e_q,
                           q_rel_pct=100 * e_q / motion if motion > 0 else math.nan,
                           tau_rel_pct=100 * _rms(pred - tau) / den if den > 0 else math.nan,
                           fc_hz=fc_hz)
