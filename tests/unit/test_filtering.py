"""Unit tests of identification/filtering.py on synthetic arrays (section 3.2, eqs. 22-25).

No MuJoCo: every input is a closed-form signal whose filtered or differentiated value is known.
"""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.identification.filtering import (FilterSettings, central_difference,
                                                 central_difference5, decimate_parallel,
                                                 derivatives, kink_corrected, lowpass, zoh_align)

RATE = 1000.0
TS = 1.0 / RATE


def _amplitude_phase(x: np.ndarray, t: np.ndarray, w: float) -> tuple[float, float]:
    """Amplitude and phase [rad] of the component sin(w t + phase) of x (projection over an
    integer number of periods)."""
    a = 2.0 * np.mean(x * np.sin(w * t))
    b = 2.0 * np.mean(x * np.cos(w * t))
    return float(np.hypot(a, b)), float(np.arctan2(b, a))


def _middle(t: np.ndarray, period: float, periods: int) -> slice:
    """Samples spanning `periods` whole periods centred in t, away from filtfilt's edge
    transients."""
    n = int(round(periods * period / TS))
    start = (len(t) - n) // 2
    return slice(start, start + n)


def test_lowpass_passes_an_in_band_sine_with_unit_gain_and_zero_lag():
    wn = 2 * np.pi * 20.0
    f = 1.0
    t = np.arange(int(20 * RATE)) * TS
    x = np.sin(2 * np.pi * f * t)
    y = lowpass(x, wn, TS, m=4)
    mid = _middle(t, 1.0 / f, 10)
    gain, phase = _amplitude_phase(y[mid], t[mid], 2 * np.pi * f)
    # Eq. (25) at w = wn/20: 1 / (1 + 20^-8) = 1 - 4e-11; 1e-9 leaves room for rounding in
    # the projection and the edge transients, decayed to nothing 5 s from the ends.
    assert gain == pytest.approx(1.0, abs=1e-9)
    # filtfilt is zero phase: 1e-9 rad at 1 Hz is a lag of 0.16 ns.
    assert abs(phase) < 1e-9
    np.testing.assert_allclose(y[mid], x[mid], atol=1e-9)


@pytest.mark.parametrize("m", [2, 4, 6])
def test_lowpass_halves_a_sine_at_wn_as_eq_25_says(m):
    wn = 2 * np.pi * 25.0
    t = np.arange(int(8 * RATE)) * TS
    x = np.sin(wn * t)
    y = lowpass(x, wn, TS, m=m)
    mid = _middle(t, 2 * np.pi / wn, 100)
    gain, phase = _amplitude_phase(y[mid], t[mid], wn)
    # Eq. (25) at w = wn: 1 / (1 + 1) = 0.5 for forward and reverse; scipy's bilinear design
    # prewarps wn, so the digital |H(wn)|^2 is 0.5 exactly. 1e-9 covers rounding in the
    # projection and the edge transients (the filter settles within ~0.2 s at 25 Hz; the
    # window starts 2 s in).
    assert gain == pytest.approx(0.5, abs=1e-9)
    assert abs(phase) < 1e-9


def test_central_difference_is_exact_on_a_quadratic():
    t = np.arange(50) * 0.01
    x = 3.0 - 2.0 * t + 7.0 * t ** 2
    d = central_difference(x, 0.01)
    assert np.isnan(d[0]) and np.isnan(d[-1])
    # Eq. (22) is exact to second order: only rounding (values ~10, 1e-9 relative) remains.
    np.testing.assert_allclose(d[1:-1], -2.0 + 14.0 * t[1:-1], rtol=0, atol=1e-9)


@pytest.mark.parametrize("wT", [0.05, 0.5, 1.2])
def test_central_difference_gain_is_sinc_as_eq_24_says(wT):
    ts = 0.01
    w = wT / ts
    t = np.arange(400) * ts
    d = central_difference(np.sin(w * t), ts)
    # (sin(w(t+T)) - sin(w(t-T))) / 2T = w cos(w t) sin(wT)/(wT) is an identity: eq. (24)'s
    # gain with zero phase holds to rounding (1e-12 on values of order w = 5..120).
    expected = w * np.sin(wT) / wT * np.cos(w * t)
    np.testing.assert_allclose(d[1:-1], expected[1:-1], rtol=0, atol=1e-12 * w)


def test_central_difference5_is_exact_on_a_quartic():
    ts = 0.02
    t = np.arange(60) * ts
    x = 1.0 + 0.5 * t - 3.0 * t ** 2 + 2.0 * t ** 3 - 0.7 * t ** 4
    d = central_difference5(x, ts)
    assert np.all(np.isnan(d[:2])) and np.all(np.isnan(d[-2:]))
    exact = 0.5 - 6.0 * t + 6.0 * t ** 2 - 2.8 * t ** 3
    # The 5-point stencil is exact to degree 4: only rounding (values ~10) remains.
    np.testing.assert_allclose(d[2:-2], exact[2:-2], rtol=0, atol=1e-9)
    # The 3-point stencil is not (its error is T^2 x'''/6): the quartic tells them apart.
    assert np.nanmax(np.abs(central_difference(x, ts)[2:-2] - exact[2:-2])) > 1e-5


def test_central_difference5_gain_matches_its_docstring():
    ts, wT = 0.01, 0.6
    w = wT / ts
    t = np.arange(300) * ts
    d = central_difference5(np.sin(w * t), ts)
    gain = (8 * np.sin(wT) - np.sin(2 * wT)) / (6 * wT)
    # A trigonometric identity, like eq. (24): exact to rounding.
    np.testing.assert_allclose(d[2:-2], w * gain * np.cos(w * t[2:-2]), rtol=0, atol=1e-12 * w)


def test_derivatives_repeat_the_chosen_stencil():
    ts = 0.05
    t = np.arange(40) * ts
    x = t ** 3
    d3 = derivatives(x, ts, 2)
    d5 = derivatives(x, ts, 2, stencil=5)
    assert len(d3) == 3 and len(d5) == 3
    np.testing.assert_array_equal(d3[0], x)
    # Two 3-point passes are a 5-wide stencil: 2 NaN at each end; two 5-point passes: 4.
    assert np.isnan(d3[2][:2]).all() and np.isfinite(d3[2][2:-2]).all()
    assert np.isnan(d5[2][:4]).all() and np.isfinite(d5[2][4:-4]).all()
    # The 5-point stencil is exact on a cubic (degree <= 4), twice: x'' = 6 t.
    np.testing.assert_allclose(d5[2][4:-4], 6 * t[4:-4], atol=1e-9)


def test_zoh_align_averages_the_two_held_values():
    tau = np.array([1.0, 3.0, -1.0, 5.0])
    np.testing.assert_array_equal(zoh_align(tau), [1.0, 2.0, 1.0, 2.0])
    # The input is not modified.
    np.testing.assert_array_equal(tau, [1.0, 3.0, -1.0, 5.0])


def test_zoh_align_removes_the_half_sample_shift_of_a_held_sine():
    ts, w = 0.01, 2 * np.pi * 3.0
    t = np.arange(200) * ts
    held = np.sin(w * (t + ts / 2))   # the value held over [t_k, t_k+1), taken at mid-interval
    aligned = zoh_align(held)
    # (sin(w(t - T/2)) + sin(w(t + T/2))) / 2 = cos(wT/2) sin(w t): zero phase at t_k, an
    # identity (rounding only).
    np.testing.assert_allclose(aligned[1:], np.cos(w * ts / 2) * np.sin(w * t[1:]), atol=1e-12)


def test_decimate_parallel_keeps_the_linear_relation():
    rng = np.random.default_rng(0)
    n = 3000
    t = np.arange(n) * TS
    W = np.column_stack([np.sin(2 * np.pi * 2.0 * t), np.cos(2 * np.pi * 5.0 * t) * t,
                         rng.standard_normal(n), np.ones(n)])
    W[:2] = np.nan     # the undefined ends of a derivative column
    W[-2:] = np.nan
    X = np.array([2.5, -1.0, 0.3, 4.0])
    y = W @ X
    s = FilterSettings(wn=2 * np.pi * 50.0, m=4, Nd=7, ts=TS)
    yd, Wd, index = decimate_parallel(y, W, s)
    assert np.isfinite(Wd).all() and np.isfinite(yd).all()
    # Decimation is linear and column-wise, so y_d = W_d X still holds: least squares
    # recovers X to rounding (1e-10 relative).
    Xd, *_ = np.linalg.lstsq(Wd, yd, rcond=None)
    np.testing.assert_allclose(Xd, X, rtol=1e-10)
    # Rows are every Nd-th raw sample from the first finite one, `edge` dropped at each end.
    assert index[0] == 2 + s.edge * s.Nd
    assert np.all(np.diff(index) == s.Nd)
    assert index[-1] < n - 2


def test_decimate_parallel_skip_and_nd_one():
    n = 200
    W = np.column_stack([np.arange(n, dtype=float), np.ones(n)])
    y = W @ np.array([0.5, 1.0])
    s = FilterSettings(wn=2 * np.pi * 50.0, m=4, Nd=1, ts=TS, edge=2, skip=10)
    yd, Wd, index = decimate_parallel(y, W, s)
    # Nd = 1 copies: the rows are the raw rows from skip + edge to n - edge.
    np.testing.assert_array_equal(index, np.arange(12, n - 2))
    np.testing.assert_array_equal(Wd, W[12:n - 2])
    np.testing.assert_array_equal(yd, y[12:n - 2])


def test_filter_settings_refuse_bad_values():
    with pytest.raises(ValueError, match="Nyquist"):
        FilterSettings(wn=np.pi * RATE, m=4, Nd=1, ts=TS)
    with pytest.raises(ValueError, match="order"):
        FilterSettings(wn=100.0, m=0, Nd=1, ts=TS)
    with pytest.raises(ValueError, match="decimation"):
        FilterSettings(wn=100.0, m=4, Nd=0, ts=TS)
    with pytest.raises(ValueError, match="skip"):
        FilterSettings(wn=100.0, m=4, Nd=1, ts=TS, skip=-1)
    with pytest.raises(ValueError, match="stencil"):
        FilterSettings(wn=100.0, m=4, Nd=1, ts=TS, stencil=4)


def test_decimated_cutoff_is_the_papers_5_4_hz():
    s = FilterSettings(wn=176.0, m=4, Nd=26, ts=1 / 350.87)
    # ERRATA: 0.8 x 350.87 / 2 / 26 = 5.40 Hz, the paper's 5.4 Hz (section 4).
    assert s.decimated_cutoff_hz == pytest.approx(5.398, abs=1e-3)


@pytest.mark.parametrize("stencil", [3, 5])
def test_kink_corrected_puts_the_reversal_back(stencil):
    """A reversal under Coulomb friction: the velocity crosses zero at t0 with its slope
    jumping from -(A + r) to -(A - r) (friction rate r = FS / J helps the deceleration, then
    resists the new motion). The filtered velocity crosses zero late by about 2 r m1 / A
    (m1 the filter's half-moment): 11.3 ms, four samples, here. `kink_corrected` with the
    same r puts the crossing back at t0 to within a third of a sample (0.85 ms measured with
    its 3 passes; the fixed point is 0.62 ms, about what the stencil alone leaves on the
    unfiltered samples, 0.9-1.4 ms)."""
    ts, A, r, t0 = 1 / 350.87, 2.0, 1.5, 3.0
    t = np.arange(0, 6.0, ts)
    x = t - t0
    q = np.where(x < 0, -(A + r) * x ** 2 / 2, -(A - r) * x ** 2 / 2)
    s = FilterSettings(wn=2 * np.pi * 8.0, m=4, Nd=6, ts=ts, stencil=stencil)
    vf = derivatives(lowpass(q, s.wn, s.ts, s.m), ts, 1, stencil)[1]

    def crossing(u):
        k = np.flatnonzero((u[:-1] > 0) & (u[1:] <= 0) & (np.abs(x[:-1]) < 0.5))[0]
        return t[k] + ts * u[k] / (u[k] - u[k + 1])

    late = crossing(vf) - t0
    assert late > 3 * ts                       # the filter's displacement is real
    assert abs(crossing(kink_corrected(vf, r, s)) - t0) < ts / 3
    assert np.allclose(kink_corrected(vf, 0.0, s), vf, equal_nan=True)


def test_zero_phase_is_scipys_sosfiltfilt():
    """`zero_phase` (the filter's initial conditions made once) gives scipy.signal.
    sosfiltfilt's numbers bit for bit, along either axis, and its error for a record shorter
    than the odd extension."""
    from scipy import signal

    from jointbench.identification.filtering import antialias, butterworth, zero_phase

    rng = np.random.default_rng(0)
    for sos in (butterworth(4, 0.1), antialias(9)):
        for shape, axis in (((3000,), -1), ((3000, 3), 0), ((3, 3000), 1)):
            x = np.cumsum(rng.standard_normal(shape), axis=axis)
            assert np.array_equal(zero_phase(sos, x, axis=axis),
                                  signal.sosfiltfilt(np.array(sos), x, axis=axis))
    with pytest.raises(ValueError, match="padlen"):
        zero_phase(antialias(9), np.ones(10))


@pytest.mark.parametrize("q", [5, 26])
def test_antialias_gain_is_the_zero_phase_pass(q):
    """`antialias_gain` on a bin is what `decimate`'s zero-phase pass does to a tone at that
    bin, away from the record's ends (300 decimated samples or more: the transient decayed,
    measured 4e-13 of the tone's amplitude), in the passband, the transition band and the
    stopband."""
    from jointbench.identification.filtering import antialias, antialias_gain, zero_phase
    n_fft = 16384
    gain = antialias_gain(q, n_fft)
    t = np.arange(n_fft)
    for k in (3, int(0.7 * n_fft / (2 * q)), int(n_fft / (2 * q)), int(2 * n_fft / (2 * q))):
        x = np.cos(2 * np.pi * k * t / n_fft + 0.3)
        mid = slice(n_fft // 2 - 50, n_fft // 2 + 50)
        np.testing.assert_allclose(zero_phase(antialias(q), x)[mid], gain[k] * x[mid],
                                   rtol=0, atol=1e-9)
