"""Frequency responses: measured from a log (spectral estimate) and of the two-mass model
of eqs. (5)-(6) (python-control), for the demo's figure and the first-mode estimate."""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
from scipy import signal

from identification.log import Log


@dataclass(frozen=True)
class FRF:
    f_hz: np.ndarray
    H: np.ndarray          # complex q_m / tau_m [rad / (N m)]
    coherence: np.ndarray


def measured_frf(log: Log, nperseg: int | None = None) -> FRF:
    """q_m / tau_m from the log. With `q_ref` logged, the closed-loop (indirect) estimate
    S(ref, q_m) / S(ref, tau_m), unbiased by the feedback; otherwise the H1 estimate."""
    fs = log.sample_rate_hz
    nperseg = nperseg or min(len(log), int(2 ** np.floor(np.log2(fs * 8))))
    x = log.q_ref if log.q_ref is not None else log.tau_m
    f, s_xq = signal.csd(x, log.q_m, fs=fs, nperseg=nperseg)
    _, s_xt = signal.csd(x, log.tau_m, fs=fs, nperseg=nperseg)
    _, coh = signal.coherence(log.tau_m, log.q_m, fs=fs, nperseg=nperseg)
    return FRF(f, s_xq / s_xt, coh)


def two_mass_tf(Jm: float, K: float, JL: float, FVm: float = 0.0, FV: float = 0.0,
                G: float = 0.0) -> control.TransferFunction:
    """q_m / tau_m of eqs. (5)-(6) linearised (G: gravity stiffness on the link):
    (JL s^2 + FV s + K + G) / ((Jm s^2 + FVm s + K)(JL s^2 + FV s + K + G) - K^2)."""
    link = np.array([JL, FV, K + G])
    motor = np.array([Jm, FVm, K])
    den = np.polysub(np.polymul(motor, link), np.array([K * K]))
    return control.tf(link, den)


def model_frf(tf: control.TransferFunction, f_hz: np.ndarray) -> np.ndarray:
    return np.asarray(tf(2j * np.pi * np.asarray(f_hz)), dtype=complex).ravel()


def first_mode_hz(frf: FRF, fmin: float = 0.5, fmax: float | None = None) -> float:
    """The first resonance: the largest |q_m / tau_m| peak past the antiresonance dip, found
    as the maximum of |H| f^2 (which flattens the rigid-body 1/f^2 slope) in [fmin, fmax]."""
    fmax = fmax or frf.f_hz[-1] / 4
    band = (frf.f_hz >= fmin) & (frf.f_hz <= fmax)
    flat = np.abs(frf.H[band]) * frf.f_hz[band] ** 2
    return float(frf.f_hz[band][np.argmax(flat)])
