"""Unit tests of identification/band_choice.py: the excitation's top measured on a log, the
wide candidate, and the rule that picks the joint-motor band by the fit's own precision
(stand-in fits: no identification, no MuJoCo)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from scipy import signal

from jointbench.identification.filtering import stencil_gain
from jointbench.identification.band_choice import (CONSISTENCY_Z, butterworth_flat_top_hz,
                                                   choose_band, excitation_top_hz,
                                                   stencil_top_hz, wide_settings)
from jointbench.identification.filter_choice import PAPER_RATE, STENCIL_DISTORTION_MAX, default_settings
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log

RATE = PAPER_RATE   # the mission's rate


def _chirp_log(f_hi: float, with_ref: bool = True, seconds: float = 60.0) -> Log:
    """A linear 0.1 Hz - f_hi sweep with 2 s cosine tapers, as the bench's references
    (bench/sim/reference.py), as q_ref, and a noisy torque that follows it."""
    t = np.arange(int(seconds * RATE)) / RATE
    q = 0.1 * signal.chirp(t, 0.1, t[-1], f_hi) * signal.windows.tukey(len(t), 4 / seconds)
    tau = np.gradient(np.gradient(q, t), t) + np.random.default_rng(0).normal(0, 1e-3, len(t))
    return Log(t=t, q_m=q, tau_m=tau, q=q, q_ref=q if with_ref else None,
               meta={"sample_rate_hz": f"{RATE}"})


@pytest.mark.parametrize("f_hi", [12.0, 30.0])
@pytest.mark.parametrize("with_ref", [True, False], ids=["q_ref", "tau_m"])
def test_excitation_top_is_the_sweeps_top(f_hi, with_ref):
    # measured 12.63-12.75 and 30.14-30.26 Hz: the tapered sweep's spectrum spreads past
    # f_hi by the taper's modulation and the window's skirt; 1 Hz moves Nd by 1 at most
    top, what = excitation_top_hz(_chirp_log(f_hi, with_ref))
    assert f_hi <= top < f_hi + 1, top
    assert ("reference" in what) == with_ref


def test_stencil_top_is_where_the_distortion_reaches_the_chooser_s_bound():
    f = stencil_top_hz(RATE)
    x = 2 * math.pi * f / RATE
    assert 1 - stencil_gain(x, 5) ** 2 == pytest.approx(STENCIL_DISTORTION_MAX, rel=1e-6)
    assert 30 < f < 40   # (x^4 / 15 = 1 %: x = 0.62, 34.8 Hz at 350.87 Hz)


def test_butterworth_flat_top_is_where_the_filtfilt_gain_loses_1_percent():
    s = default_settings(RATE, 6.0)
    f = butterworth_flat_top_hz(s)
    gain = 1 / (1 + (2 * math.pi * f / s.wn) ** (2 * s.m))   # |H|^2: forward and back
    assert gain == pytest.approx(1 - STENCIL_DISTORTION_MAX, rel=1e-9)


@pytest.mark.parametrize("f_hi", [12.0, 30.0])
def test_wide_settings_reach_the_top_with_the_chooser_s_butterworth(f_hi):
    base = default_settings(RATE, 4.0)           # the paper's: Nd 26, cutoff 5.4 Hz
    wide, top, _ = wide_settings(_chirp_log(f_hi), base)
    assert wide.wn == base.wn and wide.Nd < base.Nd
    limit = min(top, stencil_top_hz(RATE), butterworth_flat_top_hz(base))
    assert wide.decimated_cutoff_hz <= limit
    # the smallest Nd under the top: one less would cut above it
    assert 0.8 * RATE / (2 * (wide.Nd - 1)) > limit
    assert wide.stencil == 5


def test_no_wide_band_when_the_chooser_s_reaches_the_top():
    base = default_settings(RATE, 6.0)
    wide, _, why = wide_settings(_chirp_log(0.9 * base.decimated_cutoff_hz), base)
    assert wide is None and "already reaches" in why


@dataclass(frozen=True)
class _Fit:
    settings: FilterSettings
    physical: dict
    sigma: dict


def _fit(settings, jm, rel_sigma):
    return _Fit(settings, {"K": 1.0, "Jm": jm, "JL": 1.0},
                {"K": rel_sigma, "Jm": rel_sigma * jm, "JL": rel_sigma})


def _estimate(fit):
    return fit.physical, fit.sigma


def _choose(jm_wide, rel_wide, rel_chooser=0.01):
    log = _chirp_log(30.0)
    base = default_settings(RATE, 6.0)
    chosen = _fit(base, 1.0, rel_chooser)
    wide = wide_settings(log, base)
    return choose_band(chosen, _fit(wide[0], jm_wide, rel_wide), wide, _estimate)


def test_the_more_precise_band_is_kept():
    fit, band = _choose(1.005, 0.004)
    assert band.used == "wide" and fit.settings.Nd < band.alternative.Nd
    assert band.rel_sigma == 0.004 and band.alt_rel_sigma == 0.01
    fit, band = _choose(1.005, 0.02)
    assert band.used == "chooser" and fit.settings == default_settings(RATE, 6.0)
    assert band.alt_rel_sigma == 0.02 and not band.warning


def test_disagreeing_bands_keep_the_chooser_s_and_warn():
    # Jm 1 against 1 + dz, dz = sqrt(0.01^2 - 0.004^2) (Hausman: the sigma of the difference
    # of two estimates from one log, the wide one efficient): just over and just under 3 sigma
    dz = math.sqrt(0.01 ** 2 - 0.004 ** 2)
    fit, band = _choose(1 + 1.01 * CONSISTENCY_Z * dz, 0.004 / (1 + 1.01 * CONSISTENCY_Z * dz))
    assert band.used == "chooser" and "Jm" in band.warning
    assert "sigma of their difference apart" in band.warning
    fit, band = _choose(1 + 0.99 * CONSISTENCY_Z * dz, 0.004 / (1 + 0.99 * CONSISTENCY_Z * dz))
    assert band.used == "wide" and not band.warning


def test_a_failing_wide_fit_keeps_the_chooser_s():
    chosen = _fit(default_settings(RATE, 6.0), 1.0, 0.01)
    wide = wide_settings(_chirp_log(30.0), chosen.settings)
    fit, band = choose_band(chosen, ValueError("too few rows"), wide, _estimate)
    assert fit is chosen and band.used == "chooser" and "too few rows" in band.reason
    assert math.isnan(band.alt_rel_sigma) and band.to_json()["alternative"] is not None
