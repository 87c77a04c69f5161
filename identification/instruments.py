"""Instruments for the closed-loop identification: each signal's part that the reference
explains (the instrumental variables of IDIM-IV; Janot, Gautier, Jubien, Dumas 2014).

In closed loop the current loop's torque noise moves the positions: Jm qm'' answers a noise
the logged torque does not hold, so the columns of W are correlated with the equation error
and least squares is biased (at the paper rate on the six-axis arm: K -0.5 to -1.3 %, Jm +0.3 to
+1.2 %, 3-5 times the corrected sigma). The reference q_ref is exogenous: the signals predicted
from it through the measured closed-loop responses, S(q_ref, x) / S(q_ref, q_ref) (Welch),
carry no noise, and the same regressor built from them is a valid instrument Z.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy import fft as scipy_fft
from scipy import signal

from jointbench.identification.log import Log

RESOLUTION_OVER_F1 = 1.0 / 40.0   # Welch resolution: the response is smooth on this scale
SEGMENT_S = 8.0                   # Welch segment when no first mode is known
MIN_SEGMENTS = 4                  # segments the log must hold (Welch averages)


def segment_length(rate_hz: float, f1_hz: float | None, n: int) -> int | None:
    """Welch segment [samples]: a power of two giving a resolution of f1 / 40 (fine enough for
    a resonance of damping ratio >= 0.05 at f1), or 8 s without f1; None when the log holds
    fewer than four such segments: too few averages, and instruments that smear the mode do
    worse than least squares (prototype, 10 s: K -1.4 % against -0.1 %)."""
    df = f1_hz * RESOLUTION_OVER_F1 if f1_hz and math.isfinite(f1_hz) else 1.0 / SEGMENT_S
    nper = 2 ** int(math.ceil(math.log2(rate_hz / df)))
    return nper if MIN_SEGMENTS * nper <= n else None


def predicted(x: np.ndarray, ref: np.ndarray, rate_hz: float, nperseg: int,
              spectra: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """x as the reference predicts it: the inverse FFT of H(f) Ref(f), H = S(ref, x) / S(ref,
    ref) (Welch, interpolated on the record's bins), plus x's mean. `spectra`: what depends on
    the reference alone (`reference_spectra`), when already made."""
    x = np.asarray(x, dtype=float)
    ref, s_rr, R = spectra or reference_spectra(ref, rate_hz, nperseg)
    f, s_rx = signal.csd(ref, x, fs=rate_hz, nperseg=nperseg)
    with np.errstate(divide="ignore", invalid="ignore"):
        H = np.where(s_rr > 0, s_rx / s_rr, 0.0)
    F = np.fft.rfftfreq(len(x), 1.0 / rate_hz)
    Hi = np.interp(F, f, H.real) + 1j * np.interp(F, f, H.imag)
    return scipy_fft.irfft(Hi * R, len(x)) + np.mean(x)


def reference_spectra(ref: np.ndarray, rate_hz: float, nperseg: int
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`predicted`'s reference without its mean, its Welch spectrum S(ref, ref) and its FFT:
    the same for every signal predicted from it."""
    ref = np.asarray(ref, dtype=float) - np.mean(ref)
    _, s_rr = signal.welch(ref, fs=rate_hz, nperseg=nperseg)
    return ref, s_rr, scipy_fft.rfft(ref)


def instrument_log(log: Log, f1_hz: float | None = None) -> Log | None:
    """The log with q_m and q replaced by their predictions from q_ref (`predicted`),
    or None when the log has no q_ref, the reference does not move, or the log is too short
    for the response's resolution (`segment_length`)."""
    if log.q_ref is None or not np.ptp(log.q_ref) > 0:
        return None
    rate = log.sample_rate_hz
    nper = segment_length(rate, f1_hz, len(log.t))
    if nper is None:
        return None
    spectra = reference_spectra(log.q_ref, rate, nper)

    def pred(x: np.ndarray | None) -> np.ndarray | None:
        return None if x is None else predicted(x, log.q_ref, rate, nper, spectra)

    # the joint-motor regressor's columns hold positions only: the torque is y, kept
    return replace(log, q_m=pred(log.q_m), q=pred(log.q))
