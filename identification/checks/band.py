"""Honest checks of a band against the first mode: is the rate high enough for the
mode with the chosen differentiator (eq. 29), and does the band hold the mode."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from jointbench.identification.design import design_bandpass
from jointbench.identification.filtering import FilterSettings, stencil_gain
from jointbench.identification.log import Log, LogError

MIN_CUTOFF_OVER_F1 = 1.3   # decimated cutoff / f1 below which the band does not hold the mode
NYQUIST_CAP = 0.8          # wn_from_f1 caps the Butterworth at 0.8 of the Nyquist frequency


def required_rate_hz(f1_hz: float, stencil: int = 3, nd: int = 2, m: int = 4) -> float:
    """Eq. (29) with the chosen differentiator: the rate at which its distortion at
    wc = 6 w1 is sqrt(Ac / rc) (Ac = sqrt(2)/2, rc = 1). For eq. (22) this is
    design_bandpass(f1).fs_hz; the 5-point stencil solves gain(wc Ts)^nd = sqrt(Ac)."""
    d = design_bandpass(f1_hz, nd=nd, m=m)
    if stencil == 3:
        return d.fs_hz
    target = (d.ac / d.rc) ** (1.0 / (2.0 * nd))
    x = brentq(lambda v: stencil_gain(v, 5) - target, 1e-6, 1.79)
    return d.wc_rad_s / x


def band_warnings(rate_hz: float, s: FilterSettings, f1_hz: float, nd: int) -> list[str]:
    """Warnings for a band `s` at `rate_hz` and a mode f1 (derivative order nd): the rate is
    under eq. (29)'s for that differentiator; the decimated cutoff is under 1.3 f1 (the paper's
    5.4 Hz / 3.9 Hz = 1.385, less the uncertainty of a measured f1); eq. (28)'s wn is over the
    Nyquist cap."""
    out = []
    need = required_rate_hz(f1_hz, s.stencil, nd, s.m)
    if rate_hz < need:
        eq22 = design_bandpass(f1_hz, nd=nd, m=s.m).fs_hz
        out.append(f"the sample rate {rate_hz:g} Hz is too low for the mode f1 = {f1_hz:.4g} Hz: "
                   f"eq. (29) with the {s.stencil}-point differentiator (nd = {nd}, wc = 6 w1, "
                   f"Ac = sqrt(2)/2) asks {need:.4g} Hz (with eq. (22): {eq22:.4g} Hz); the "
                   "derivatives are distorted at the mode and K, Jm, JL may be biased")
    cut = s.decimated_cutoff_hz
    if cut < MIN_CUTOFF_OVER_F1 * f1_hz:
        out.append(f"the band cannot hold the mode: decimated cutoff {cut:.3g} Hz = "
                   f"{cut / f1_hz:.2f} f1 (< {MIN_CUTOFF_OVER_F1:g} f1, f1 = {f1_hz:.4g} Hz)")
    wn28 = design_bandpass(f1_hz, nd=2, m=s.m).wn_rad_s
    cap = NYQUIST_CAP * np.pi * rate_hz
    if wn28 > cap:
        out.append(f"the band cannot hold the mode: eq. (28) asks wn = {wn28:.4g} rad/s, over "
                   f"the Nyquist cap {cap:.4g} rad/s at {rate_hz:g} Hz")
    return out


def check_f1(log: Log, f1_hz: float) -> None:
    """LogError (naming --f1 and f1_hz) for a first mode the log cannot hold: under one
    cycle over the log, or at or over the Nyquist frequency (the band and its decimation are
    designed from it)."""
    duration = float(log.t[-1] - log.t[0])
    lo, hi = 1.0 / duration, 0.5 * log.sample_rate_hz
    if not (math.isfinite(f1_hz) and lo <= f1_hz < hi):
        raise LogError(f"f1 = {f1_hz:g} Hz (--f1, f1_hz): the first mode must lie in "
                       f"[{lo:.3g}, {hi:.4g}) Hz: at least one cycle over the {duration:.3g} s "
                       "log, below the Nyquist frequency", log.path)
