"""Chirp references for the identification experiment (paper section 4: 0.05 to 30 Hz)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointbench.bench.sim.defaults import AMPLITUDE_RAD


@dataclass(frozen=True)
class Chirp:
    """A swept sine around `center` [rad].

    `amplitude` [rad] is the peak excursion; `taper` [s] the raised-cosine fade-in and fade-out
    at both ends (so the reference starts and ends at rest); `max_acceleration` [rad/s^2],
    when set, lowers the amplitude at high frequency so that A (2 pi f)^2 stays under it
    (a real axis cannot follow 30 Hz at the low-frequency amplitude without saturating).
    """

    duration: float = 60.0
    f0: float = 0.05
    f1: float = 30.0
    amplitude: float = AMPLITUDE_RAD
    center: float = 0.0
    method: str = "logarithmic"
    taper: float = 2.0
    max_acceleration: float | None = None

    def __post_init__(self):
        if self.duration <= 0:
            raise ValueError(f"chirp duration must be positive, got {self.duration}")
        if not 0 < self.f0 < self.f1:
            raise ValueError(f"chirp needs 0 < f0 < f1, got f0={self.f0}, f1={self.f1}")
        if self.amplitude <= 0:
            raise ValueError(f"chirp amplitude must be positive, got {self.amplitude}")
        if self.method not in ("linear", "logarithmic"):
            raise ValueError(f"chirp method must be 'linear' or 'logarithmic', got {self.method!r}")
        if not 0 <= 2 * self.taper <= self.duration:
            raise ValueError(f"chirp taper {self.taper} s does not fit twice in {self.duration} s")

    def phase(self, t: np.ndarray) -> np.ndarray:
        """Phase of the swept cosine [rad]: 2 pi times the integral of `frequency` (the
        expressions of scipy.signal.chirp, so the reference is the same to the last bit)."""
        f0, f1, t1 = float(self.f0), float(self.f1), float(self.duration)
        if self.method == "linear":
            beta = (f1 - f0) / t1
            return 2 * np.pi * (f0 * t + 0.5 * beta * t * t)
        beta = t1 / np.log(f1 / f0)
        return 2 * np.pi * beta * f0 * (pow(f1 / f0, t / t1) - 1.0)

    def frequency(self, t: np.ndarray) -> np.ndarray:
        """Instantaneous frequency [Hz]."""
        if self.method == "linear":
            return self.f0 + (self.f1 - self.f0) * t / self.duration
        return self.f0 * (self.f1 / self.f0) ** (t / self.duration)

    def envelope(self, t: np.ndarray) -> np.ndarray:
        env = np.full_like(t, self.amplitude, dtype=float)
        if self.taper > 0:
            ramp_in = np.clip(t / self.taper, 0.0, 1.0)
            ramp_out = np.clip((self.duration - t) / self.taper, 0.0, 1.0)
            env *= 0.5 * (1 - np.cos(np.pi * ramp_in)) * 0.5 * (1 - np.cos(np.pi * ramp_out))
        if self.max_acceleration is not None:
            w = 2 * np.pi * self.frequency(t)
            env = np.minimum(env, self.max_acceleration / w**2)
        return env

    def __call__(self, t: np.ndarray) -> np.ndarray:
        """q_ref(t) [rad]; sine phase so that q_ref(0) = center."""
        t = np.asarray(t, dtype=float)
        wave = np.cos(self.phase(t) + np.deg2rad(-90.0))
        return self.center + self.envelope(t) * wave
