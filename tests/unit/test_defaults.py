"""Unit tests of identification/filter_choice.py, the one filter chooser, against the paper's
section 4 and the design numbers of the ERRATA (no MuJoCo)."""

from __future__ import annotations

import numpy as np
import math

import pytest

from jointbench.identification.checks.band import MIN_CUTOFF_OVER_F1
from jointbench.identification.filter_choice import (GENERIC_ND, GENERIC_WN_RATIO, PAPER_F1,
                                                PAPER_ND, PAPER_RATE, PAPER_WN,
                                                default_settings, design_rate_hz,
                                                generic_settings, nd_from_f1, settings_for,
                                                wn_from_f1)
from jointbench.identification.log import Log

# Ratio of the paper's decimated cutoff (5.4 Hz) to its first mode (3.9 Hz), section 4.
CUTOFF_OVER_F1 = 5.4 / 3.9


def _log(rate_hz: float, n: int = 100, with_meta: bool = True) -> Log:
    t = np.arange(n) / rate_hz
    meta = {"sample_rate_hz": f"{rate_hz:g}"} if with_meta else {}
    return Log(t=t, q_m=np.zeros(n), tau_m=np.zeros(n), meta=meta)


def test_the_papers_constants():
    assert (PAPER_RATE, PAPER_WN, PAPER_ND, PAPER_F1) == (350.87, 176.0, 26, 3.9)


@pytest.mark.parametrize("f1", [None, 3.9, 3.72, 3.2, 4.6])
def test_prototype_rate_gives_the_papers_filter(f1):
    # Section 4: wn = 176 rad/s, Nd = 26 at 350.87 Hz, for no f1 or one within 20 % of 3.9 Hz
    # (3.72 Hz is the first mode of Table 1's values, per the ERRATA).
    s = default_settings(PAPER_RATE, f1)
    assert (s.wn, s.Nd, s.m) == (176.0, 26, 4)
    assert s.ts == pytest.approx(1 / 350.87, rel=1e-15)


def test_a_mode_far_from_the_prototypes_gets_its_own_filter():
    s = default_settings(PAPER_RATE, 15.0)
    assert s.wn == pytest.approx(wn_from_f1(PAPER_RATE, 15.0))
    assert s.Nd == nd_from_f1(PAPER_RATE, 15.0)
    assert s.Nd < PAPER_ND


def test_another_rate_needs_f1():
    with pytest.raises(ValueError, match="first mode"):
        default_settings(1000.0)
    s = default_settings(1000.0, 10.0)
    assert (s.wn, s.Nd) == (pytest.approx(wn_from_f1(1000.0, 10.0)), nd_from_f1(1000.0, 10.0))


def test_wn_from_f1_is_eq_28_and_capped_below_nyquist():
    # ERRATA table: nd = 2, m = 4, f1 = 3.9 Hz gives wn = 181.04 rad/s (paper: 181 rad/s);
    # the ERRATA quotes two decimals, hence abs=0.005.
    assert wn_from_f1(PAPER_RATE, 3.9) == pytest.approx(181.04, abs=0.005)
    # wn scales with f1 (eq. 28 is linear in wc = 6 w1) until the cap at 0.8 of Nyquist.
    assert wn_from_f1(PAPER_RATE, 7.8) == pytest.approx(2 * wn_from_f1(PAPER_RATE, 3.9))
    assert wn_from_f1(100.0, 10.0) == pytest.approx(0.8 * np.pi * 100.0)


def test_nd_from_f1_reproduces_the_papers_26():
    # 0.8 x 350.87 / (2 x 5.4) = 25.99: the paper's Nd = 26 for its f1 = 3.9 Hz.
    assert nd_from_f1(PAPER_RATE, 3.9) == 26


@pytest.mark.parametrize("rate, f1", [(PAPER_RATE, 3.9), (1000.0, 10.0), (2000.0, 15.0),
                                      (5000.0, 19.5), (350.87, 60.0)])
def test_nd_from_f1_puts_the_decimated_cutoff_at_5_4_over_3_9_f1(rate, f1):
    nd = nd_from_f1(rate, f1)
    cutoff = 0.8 * rate / (2 * nd)       # scipy.signal.decimate's anti-alias cutoff
    ideal = 0.8 * rate / (2 * f1 * CUTOFF_OVER_F1)
    # Nd is an integer: the one nearest the ideal real factor (cutoff 5.4/3.9 f1 to within the
    # rounding), rounded down instead where rounding would cut under 1.3 f1 (the band must
    # hold the mode): 350.87 Hz and 60 Hz give 1.69 -> 1, not 2 (70 Hz = 1.17 f1).
    assert nd in (round(ideal), math.floor(ideal))
    assert cutoff >= MIN_CUTOFF_OVER_F1 * f1
    if nd == round(ideal):
        assert cutoff == pytest.approx(CUTOFF_OVER_F1 * f1, rel=0.5 / nd)


def test_nd_from_f1_is_at_least_one():
    assert nd_from_f1(100.0, 40.0) == 1


@pytest.mark.parametrize("rate", [100.0, 1000.0, 350.87, 4096.0])
def test_generic_settings_ratios(rate):
    s = generic_settings(rate)
    # The EMPS ratios: wn at a tenth of the rate, Nd = 10, decimated cutoff 0.04 Fs.
    assert s.wn / (2 * np.pi) == pytest.approx(GENERIC_WN_RATIO * rate)
    assert GENERIC_WN_RATIO == 0.1 and s.Nd == GENERIC_ND == 10
    assert s.decimated_cutoff_hz == pytest.approx(0.04 * rate)
    assert s.ts == pytest.approx(1.0 / rate)


def test_design_rate_hz():
    # ERRATA table: eq. (29) with nd = 2, m = 4, f1 = 3.9 Hz gives Fs = 205.70 Hz (paper:
    # 205 Hz); two decimals quoted, hence abs=0.005 (doubled with the default margin 2).
    assert design_rate_hz(3.9, margin=1.0) == pytest.approx(205.70, abs=0.005)
    assert design_rate_hz(3.9) == pytest.approx(2 * 205.70, abs=0.01)
    # "About 105 f1 for m = 4": the design is linear in f1.
    assert design_rate_hz(15.0) / 15.0 == pytest.approx(105.5, abs=0.1)
    with pytest.raises(ValueError, match="margin"):
        design_rate_hz(3.9, margin=0.5)


@pytest.mark.parametrize("rate", [PAPER_RATE, 1000.0])
def test_settings_for_a_log_without_resonance_is_generic_with_a_warning(rate):
    """No mode in the log (here: constant signals), at any rate, the paper's included: the
    paper's filter is the prototype's, not a default for an unknown axis; the generic band is
    stated, with the 5-point stencil its cutoff asks (0.04 Fs: sinc^4 distortion 4 %)."""
    s, note = settings_for(_log(rate))
    assert (s.wn, s.Nd, s.stencil) == (pytest.approx(2 * np.pi * 0.1 * rate), 10, 5)
    assert note is not None and note.startswith("no resonance found")
    assert "a tenth of the rate" in note and "Nd = 10" in note and "give --f1" in note


def test_settings_for_infers_the_rate_from_t():
    s, note = settings_for(_log(500.0, with_meta=False))
    assert s.ts == pytest.approx(1 / 500.0)
    assert note is not None and "314.2 rad/s (50 Hz" in note


def test_settings_for_with_f1_uses_the_mode():
    s, note = settings_for(_log(1000.0), f1_hz=10.0)
    assert note is None and s.stencil == 3   # 1000 Hz / 10 Hz: eq. (22)'s distortion 0.6 %
    assert (s.wn, s.Nd) == (pytest.approx(wn_from_f1(1000.0, 10.0)), nd_from_f1(1000.0, 10.0))


def test_settings_for_passes_a_bad_f1_on():
    # A given but invalid f1 (0 Hz) is the caller's error: it is raised, not swallowed
    # into the generic filter.
    with pytest.raises(ValueError):
        settings_for(_log(1000.0), f1_hz=0.0)
