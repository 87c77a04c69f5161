"""Bandpass (lowpass Butterworth x central difference) design, Pham, Gautier, Poignet 2001.

Section 3.2 of the paper: derivatives of positions are obtained by a zero-phase
(forward-reverse, ``filtfilt``) Butterworth lowpass H followed by a central difference D.
Their product F = H D is a band-limited derivative filter. Given the bandwidth ``wc``
inside which the magnitude distortion of the order-``nd`` derivative filter is bounded by
``Ac`` (eq. 26), and the split ``rc`` of that distortion between H and D (eq. 27), the
Butterworth frequency ``wn`` follows from eq. (28) and the sampling frequency from eq. (29).

Pure numpy/scipy. Angular frequencies are in rad/s, frequencies in Hz, times in s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Integral, Real

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

__all__ = [
    "FilterDesign",
    "design_bandpass",
    "butterworth_magnitude",
    "central_difference_magnitude",
    "distortion",
    "decimation_cutoff_hz",
]


@dataclass(frozen=True)
class FilterDesign:
    """Result of the bandpass design of eqs. (26)-(29).

    Attributes:
        f1_hz: first mode of the joint f1 (Hz); w1 = 2 pi f1.
        wc_rad_s: bandwidth wc = ratio * w1 (rad/s), where A(wc) = Ac (eq. 26).
        wn_rad_s: Butterworth cutoff wn from eq. (28) (rad/s).
        fs_hz: sampling frequency Fs = ws / (2 pi) with ws = (2 / xc) wc, eq. (29) (Hz).
        ts_s: sampling period Ts = 1 / Fs (s).
        xc: root of sinc(xc) = (Ac / rc)^(1 / (2 nd)) in (0, 1), eq. (29); xc = wc Ts / pi.
        m: order of the forward Butterworth filter (eq. 25).
        nd: order of the highest derivative approximated by F_nd (eq. 26).
        ac: magnitude distortion bound Ac = A(wc) (eq. 26); sqrt(2)/2 is -3 dB.
        rc: ratio of the lowpass distortion to the central-difference distortion at wc
            (eq. 27).
        ratio: wc / w1 (the paper uses 6, within its advised range 2..10).
    """

    f1_hz: float
    wc_rad_s: float
    wn_rad_s: float
    fs_hz: float
    ts_s: float
    xc: float
    m: int
    nd: int
    ac: float
    rc: float
    ratio: float


def _check_positive(name: str, value: float) -> float:
    # bool is an Integral; a True/False "frequency" is surely a caller mistake.
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ValueError(f"{name} must be a real number, got {value!r}")
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return float(value)


def _check_order(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    if value < 1:
        raise ValueError(f"{name} must be >= 1, got {value!r}")
    return int(value)


def design_bandpass(
    f1_hz: float,
    nd: int,
    m: int,
    ac: float = math.sqrt(2.0) / 2.0,
    rc: float = 1.0,
    ratio: float = 6.0,
) -> FilterDesign:
    """Design the bandpass derivative filter of section 3.2, eqs. (26)-(29).

    wc = ratio * 2 pi f1 (rad/s);
    wn = wc (1 / sqrt(rc Ac) - 1)^(-1 / (2 m))                     eq. (28);
    sinc(xc) = sin(pi xc) / (pi xc) = (Ac / rc)^(1 / (2 nd)),  xc in (0, 1)   eq. (29);
    ws = 2 pi / Ts = (2 / xc) wc, Fs = ws / (2 pi), Ts = 1 / Fs.

    Eq. (28) follows from A(wc) = Ac (eq. 26) and eq. (27): the lowpass share at wc is
    |H(jwc)| = sqrt(rc Ac) and the central-difference share is sinc^nd = sqrt(Ac / rc).

    Args:
        f1_hz: first mode of the joint f1 (Hz), > 0.
        nd: highest derivative order, >= 1 (2 with joint and motor positions, 4 with the
            motor position only).
        m: forward Butterworth order, >= 1.
        ac: distortion bound Ac in (0, 1); default sqrt(2)/2 (-3 dB).
        rc: distortion split of eq. (27), > 0, with rc * ac < 1 and ac / rc < 1.
        ratio: wc / w1, > 0; default 6 as in the paper.

    Returns:
        The FilterDesign (wn in rad/s, Fs in Hz, Ts in s).

    Raises:
        ValueError: naming the argument, if f1_hz, ratio or rc is not finite and > 0, if nd
            or m is not an integer >= 1, if ac is not in (0, 1), if rc * ac >= 1 (eq. 28
            then has no positive base), or if ac / rc >= 1 (eq. 29 then has no root in
            (0, 1)).
    """
    f1 = _check_positive("f1_hz", f1_hz)
    nd_ = _check_order("nd", nd)
    m_ = _check_order("m", m)
    if isinstance(ac, bool) or not isinstance(ac, Real) or not (0.0 < ac < 1.0):
        raise ValueError(f"ac must be a real number in (0, 1), got {ac!r}")
    rc_ = _check_positive("rc", rc)
    ratio_ = _check_positive("ratio", ratio)
    ac_ = float(ac)
    if rc_ * ac_ >= 1.0:
        raise ValueError(
            f"rc * ac must be < 1 so that eq. (28) is defined (the lowpass share "
            f"sqrt(rc*Ac) of the distortion must be < 1), got rc={rc_!r}, ac={ac_!r}"
        )
    target = (ac_ / rc_) ** (1.0 / (2.0 * nd_))
    if target >= 1.0:
        # sinc maps (0, 1) onto (0, 1) only; sinc(xc) = 1 would need Ts = 0.
        raise ValueError(
            f"rc must be > ac so that eq. (29) has a root xc in (0, 1) "
            f"((Ac/rc)^(1/(2nd)) must be < 1), got rc={rc_!r}, ac={ac_!r}"
        )

    wc = ratio_ * 2.0 * math.pi * f1
    wn = wc * (1.0 / math.sqrt(rc_ * ac_) - 1.0) ** (-1.0 / (2.0 * m_))
    # sinc is strictly decreasing from 1 to 0 on [0, 1], so the root is unique and
    # bracketed by the open interval's ends.
    xc = float(brentq(lambda x: float(np.sinc(x)) - target, 0.0, 1.0, xtol=1e-15, rtol=1e-15))
    ws = 2.0 * wc / xc
    fs = ws / (2.0 * math.pi)
    return FilterDesign(
        f1_hz=f1,
        wc_rad_s=wc,
        wn_rad_s=wn,
        fs_hz=fs,
        ts_s=1.0 / fs,
        xc=xc,
        m=m_,
        nd=nd_,
        ac=ac_,
        rc=rc_,
        ratio=ratio_,
    )


def butterworth_magnitude(w: ArrayLike, wn: float, m: int) -> NDArray[np.float64]:
    """|H(jw)| of eq. (25): 1 / (1 + (w / wn)^(2 m)).

    This is the magnitude of the forward-and-reverse (filtfilt) order-m Butterworth
    filter, i.e. the square of the order-m Butterworth magnitude (ERRATA), in the
    continuous approximation valid when ws/2 is well above wn.

    Args:
        w: angular frequency (rad/s), scalar or array.
        wn: Butterworth cutoff (rad/s), > 0; |H(j wn)| = 1/2.
        m: forward filter order, >= 1.

    Returns:
        Dimensionless magnitude, same shape as w.

    Raises:
        ValueError: if wn is not finite and > 0 or m is not an integer >= 1.
    """
    wn_ = _check_positive("wn", wn)
    m_ = _check_order("m", m)
    w_arr = np.asarray(w, dtype=float)
    return 1.0 / (1.0 + np.abs(w_arr / wn_) ** (2 * m_))


def central_difference_magnitude(w: ArrayLike, ts: float) -> NDArray[np.float64]:
    """|D(jw)| of eq. (24): w |sin(w Ts) / (w Ts)| = |sin(w Ts)| / Ts.

    Central difference of eq. (22), q_cd[k] = (q[k+1] - q[k-1]) / (2 Ts). The value at
    w = 0 is 0 (np.sinc removes the 0/0).

    Args:
        w: angular frequency (rad/s), scalar or array.
        ts: sampling period Ts (s), > 0.

    Returns:
        Magnitude in 1/s (rad/s), same shape as w.

    Raises:
        ValueError: if ts is not finite and > 0.
    """
    ts_ = _check_positive("ts", ts)
    w_arr = np.asarray(w, dtype=float)
    # np.sinc(x) = sin(pi x)/(pi x), hence the division by pi.
    return np.abs(w_arr) * np.abs(np.sinc(w_arr * ts_ / np.pi))


def distortion(w: ArrayLike, wn: float, ts: float, m: int, nd: int) -> NDArray[np.float64]:
    """Magnitude distortion A(w) of eq. (26) of the order-nd derivative filter F_nd.

    A(w) = 1 / (1 + (w / wn)^(2 m)) * (sin(w Ts) / (w Ts))^nd, i.e. |F_nd(jw)| / w^nd.
    The sinc factor is taken in absolute value (a magnitude); this equals eq. (26) below
    the Nyquist frequency ws/2 = pi / Ts, where it is positive.

    Args:
        w: angular frequency (rad/s), scalar or array.
        wn: Butterworth cutoff (rad/s), > 0.
        ts: sampling period Ts (s), > 0.
        m: forward Butterworth order, >= 1.
        nd: derivative order, >= 1.

    Returns:
        Dimensionless distortion, same shape as w; A(0) = 1.

    Raises:
        ValueError: if wn or ts is not finite and > 0, or m or nd is not an integer >= 1.
    """
    ts_ = _check_positive("ts", ts)
    nd_ = _check_order("nd", nd)
    w_arr = np.asarray(w, dtype=float)
    sinc = np.abs(np.sinc(w_arr * ts_ / np.pi))
    return butterworth_magnitude(w_arr, wn, m) * sinc**nd_


def decimation_cutoff_hz(fs_hz: float, nd_decim: int) -> float:
    """Anti-alias cutoff (Hz) of decimation by Nd, as scipy.signal.decimate's default.

    scipy.signal.decimate's default IIR (Chebyshev I, order 8) has its cutoff at 0.8 of
    the new Nyquist frequency: 0.8 * (Fs / 2) / Nd. With the paper's Fs and Nd = 26 this
    is 5.40 Hz, the paper's 5.4 Hz (section 4.1, ERRATA).

    Args:
        fs_hz: sampling frequency before decimation (Hz), > 0.
        nd_decim: decimation factor Nd (keep one sample over Nd), integer >= 1.

    Returns:
        Cutoff frequency in Hz.

    Raises:
        ValueError: if fs_hz is not finite and > 0 or nd_decim is not an integer >= 1.
    """
    fs = _check_positive("fs_hz", fs_hz)
    nd_ = _check_order("nd_decim", nd_decim)
    return 0.8 * fs / 2.0 / nd_
