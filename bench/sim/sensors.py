"""Sensors of the virtual experiment: quantised encoders and current-loop torque noise."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class Sensors:
    """Encoder resolutions [rad per count, joint side] (0: ideal) and the standard deviation of
    the torque the current loop adds to the command [N m] (white, seeded).

    Defaults (`Sensors.default`): a 17-bit motor encoder seen through the gear ratio N
    (2 pi / (2^17 N)), a 20-bit absolute link encoder (2 pi / 2^20), and current-loop torque
    noise of 1.25 % of the torque limit (37.5 N m on the prototype). That level still leaves
    the virtual data several times cleaner than the paper's robot (its Table 1 reports
    sigma_K = 1.07 %, ours about 0.15 %); much cleaner data makes the paper's sigma, which
    only sees noise, smaller than the model's own small biases (README, "Accuracy").
    """

    motor_resolution: float
    link_resolution: float
    torque_noise_std: float

    @classmethod
    def default(cls, gear_ratio: float | None, tau_max: float) -> "Sensors":
        N = gear_ratio or 100.0
        return cls(motor_resolution=2 * math.pi / (2**17 * N),
                   link_resolution=2 * math.pi / 2**20, torque_noise_std=0.0125 * tau_max)

    @classmethod
    def ideal(cls) -> "Sensors":
        return cls(0.0, 0.0, 0.0)

    @classmethod
    def from_log(cls, log) -> "Sensors | None":
        """The sensors a log's metadata describes (`to_meta`'s keys, as every jointbench log
        carries them), None when any key is absent; LogError when one is not a number."""
        keys = ("motor_encoder_resolution_rad", "link_encoder_resolution_rad",
                "torque_noise_std")
        values = [log.meta_float(k) for k in keys]
        if any(v is None for v in values):
            return None
        return cls(*values)

    @staticmethod
    def _quantizer(res: float) -> Callable[[float], float]:
        if res <= 0:
            return float
        inv = 1.0 / res
        return lambda x: round(x * inv) * res

    def motor_quantizer(self) -> Callable[[float], float]:
        return self._quantizer(self.motor_resolution)

    def link_quantizer(self) -> Callable[[float], float]:
        return self._quantizer(self.link_resolution)

    def torque_noise(self, rng: np.random.Generator, n: int) -> np.ndarray:
        return rng.normal(0.0, self.torque_noise_std, n) if self.torque_noise_std > 0 else np.zeros(n)

    def to_meta(self) -> dict[str, str]:
        return {"motor_encoder_resolution_rad": f"{self.motor_resolution:.6g}",
                "link_encoder_resolution_rad": f"{self.link_resolution:.6g}",
                "torque_noise_std": f"{self.torque_noise_std:.6g}"}
