"""first_mode.analysis_log: the responses measured on the record decimated by the largest
power of two whose anti-alias cutoff keeps 1.1 times the excitation's top give the first mode
the logged record gives, well within a frequency bin (the same bins; the anti-alias filter is
common to every signal, so the responses' ratios and the coherences keep their values in the
band). On the prototype (60 s, 350.87 Hz)."""

from __future__ import annotations

import math

import numpy as np

from jointbench.identification import first_mode
from jointbench.identification.link_mode import excitation_top_hz
from jointbench.identification.spectra import Spectra


def test_the_prototype_is_analysed_at_a_quarter_of_its_rate(prototype_log):
    work, spectra = first_mode.analysis_log(prototype_log)
    fs = prototype_log.sample_rate_hz
    top = excitation_top_hz(prototype_log)
    # the band allows more (the reference's velocity stops at 7.5 Hz); the record's length
    # stops it at 4: a further halving would leave under ANALYSIS_MIN_SAMPLES
    assert spectra.decimation == 4 and spectra.hold_hz == fs
    assert 0.8 * fs / (2 * 4) >= 1.1 * top
    assert len(work) == math.ceil(len(prototype_log) / 4)
    assert len(prototype_log) // 8 < first_mode.ANALYSIS_MIN_SAMPLES <= len(work)
    assert np.array_equal(work.t, prototype_log.t[::4])


def test_decimated_analysis_gives_the_full_rate_first_mode(prototype_log, monkeypatch):
    fast = first_mode.measure_first_mode(prototype_log)
    with monkeypatch.context() as m:
        m.setattr(first_mode, "analysis_log", lambda log: (log, Spectra(log)))
        full = first_mode.measure_first_mode(prototype_log)
    assert fast.found and full.found and fast.method == full.method
    bin_hz = prototype_log.sample_rate_hz / 4096   # 8 s Welch segments at 350.87 Hz
    # measured: 1e-5 Hz apart, a ten-thousandth of a bin and of the standard deviation
    assert abs(fast.f1_hz - full.f1_hz) < 0.01 * bin_hz
    assert abs(fast.f1_hz - full.f1_hz) < 0.05 * full.sigma_hz
    assert math.isclose(fast.sigma_hz, full.sigma_hz, rel_tol=0.05)
