"""identification/spectra.py: Welch's estimates from transforms taken once equal scipy.signal's
own csd, welch and coherence, element for element (the first mode and the instruments rely on
it to give the numbers scipy gives)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from jointbench.identification.log import Log
from jointbench.identification.spectra import Spectra, welch

FS = 350.87


def _log(n: int = 6000, seed: int = 0) -> Log:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    q_ref = 0.1 * np.sin(2 * np.pi * (0.5 + 2.0 * t / t[-1]) * t)
    q_m = np.convolve(q_ref + 1e-3 * rng.standard_normal(n), np.ones(5) / 5, "same")
    q = q_m + 1e-3 * rng.standard_normal(n)
    tau_m = 50 * np.gradient(q_m, t) + rng.standard_normal(n)
    return Log(t=t, q_m=q_m, tau_m=tau_m, q=q, q_ref=q_ref)


@pytest.mark.parametrize("nperseg,noverlap,sl", [(1024, None, slice(None)),
                                                  (512, 0, slice(0, 5488)),
                                                  (512, 0, slice(512, None)),
                                                  (256, 100, slice(7, 3001))])
def test_spectra_equal_scipy_bit_for_bit(nperseg, noverlap, sl):
    log = _log()
    S = Spectra(log)
    kw = dict(fs=log.sample_rate_hz, nperseg=nperseg, noverlap=noverlap)
    for a, b in (("q_ref", "q"), ("q_ref", "tau_m"), ("tau_m", "q_m"), ("tau_m", "tau_m")):
        x, y = getattr(log, a)[sl], getattr(log, b)[sl]
        f, Pxy = signal.csd(x, y, **kw)
        assert np.array_equal(f, S.frequencies(nperseg))
        assert np.array_equal(Pxy, S.csd(a, b, nperseg, noverlap, sl))
        assert np.array_equal(signal.welch(x, **kw)[1], S.welch(a, nperseg, noverlap, sl))
        assert np.array_equal(signal.coherence(x, y, **kw)[1],
                              S.coherence(a, b, nperseg, noverlap, sl))
    # scipy's csd of one array with itself is its real Welch spectrum
    whole = np.asarray(log.tau_m)
    assert np.array_equal(signal.csd(whole, whole, **kw)[1], S.welch("tau_m", nperseg, noverlap))


def test_spectra_refuse_a_missing_column_and_memoise():
    log = _log()
    S = Spectra(Log(t=log.t, q_m=log.q_m, tau_m=log.tau_m))
    with pytest.raises(ValueError, match="q_ref"):
        S.welch("q_ref", 256)
    calls = []
    assert S.memo("x", lambda: calls.append(1) or 2.5) == 2.5
    assert S.memo("x", lambda: calls.append(1) or 3.5) == 2.5 and calls == [1]


@pytest.mark.parametrize("n,nperseg", [(6000, 1024), (6001, 256), (5000, 4096)])
def test_welch_of_an_array_equals_scipy_bit_for_bit(n, nperseg):
    x = np.diff(_log(n + 1).q_ref) * FS
    f, P = signal.welch(x, fs=FS, nperseg=nperseg)
    f2, P2 = welch(x, FS, nperseg)
    assert np.array_equal(f, f2) and np.array_equal(P, P2)


def test_spectra_results_are_shared_read_only():
    S = Spectra(_log())
    a = S.csd("q_ref", "q", 512)
    assert S.csd("q_ref", "q", 512) is a and not a.flags.writeable
    assert not S.welch("q", 512).flags.writeable


def test_welch_with_the_linear_detrend_equals_scipy_to_rounding():
    x = np.cumsum(_log(6001).q)   # a trend for the detrend to take out
    f, P = signal.welch(x, fs=FS, nperseg=1024, detrend="linear")
    f2, P2 = welch(x, FS, 1024, detrend="linear")
    assert np.array_equal(f, f2)
    np.testing.assert_allclose(P2, P, rtol=1e-10, atol=0)
    with pytest.raises(ValueError, match="detrend"):
        welch(x, FS, 1024, detrend="quadratic")
