"""Frequency responses: measured from a log (spectral estimate) and of the two-mass model
of eqs. (5)-(6) (python-control), for the demo's figure and the first-mode estimate."""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
from scipy import signal

from jointbench.identification.log import Log


@dataclass(frozen=True)
class FRF:
    f_hz: np.ndarray
    H: np.ndarray          # complex q_m / tau_m [rad / (N m)]
    coherence: np.ndarray


def measured_frf(log: Log, nperseg: int | None = None, output: str = "q_m") -> FRF:
    """`output` / tau_m from the log (`q_m`, or `q` the link). With `q_ref` logged, the
    closed-loop (indirect) estimate S(ref, out) / S(ref, tau_m), unbiased by the feedback;
    otherwise the H1 estimate."""
    fs = log.sample_rate_hz
    nperseg = nperseg or min(len(log), int(2 ** np.floor(np.log2(fs * 8))))
    y = log.q_m if output == "q_m" else log.q
    if y is None:
        raise ValueError(f"the log has no column '{output}'")
    x = log.q_ref if log.q_ref is not None else log.tau_m
    f, s_xq = signal.csd(x, y, fs=fs, nperseg=nperseg)
    _, s_xt = signal.csd(x, log.tau_m, fs=fs, nperseg=nperseg)
    _, coh = signal.coherence(log.tau_m, y, fs=fs, nperseg=nperseg)
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


def first_mode_hz(frf: FRF, fmin: float = 0.5, fmax: float = 20.0) -> float:
    """The first resonance: the peak of |H| f^2 (which flattens the rigid-body 1/f^2 slope)
    in [fmin, fmax], refined by a parabola through the peak and its neighbours on a log
    scale. Use the link response q / tau_m = K / (s^2 (Jm JL s^2 + ... + K (Jm + JL))): its
    peak is the mode itself, while q_m / tau_m carries the antiresonance zero sqrt(K / JL),
    which pulls the peak of |H| f^2 up. Keep fmax inside the excited band."""
    band = np.flatnonzero((frf.f_hz >= fmin) & (frf.f_hz <= fmax))
    flat = np.log(np.abs(frf.H[band]) * frf.f_hz[band] ** 2)
    k = int(np.argmax(flat))
    if 0 < k < len(band) - 1:
        a, b, c = flat[k - 1], flat[k], flat[k + 1]
        shift = 0.5 * (a - c) / (a - 2 * b + c) if a - 2 * b + c != 0 else 0.0
        df = frf.f_hz[1] - frf.f_hz[0]
        return float(frf.f_hz[band[k]] + shift * df)
    return float(frf.f_hz[band[k]])
