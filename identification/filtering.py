"""Data processing of section 3.2: zero-phase Butterworth, central differences (eq. 22),
zero-order-hold alignment of the torque, and the parallel decimation of y and W."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import fft as scipy_fft
from scipy import signal

from jointbench.identification.friction_state import friction_integrals

# (drive at each interval's start, at its end [rad/s^2], viscous rate FV / J [1/s])
Drive = tuple[np.ndarray, np.ndarray, float]

@dataclass(frozen=True)
class FilterSettings:
    """The bandpass chain: Butterworth order `m` and frequency `wn` [rad/s], decimation `Nd`,
    at sample period `ts` [s]; `edge` decimated samples dropped at each end.

    `zoh`: pair positions with the zero-order-hold-aligned torque (`zoh_align`); `filter_torque`:
    pass the torque through the same Butterworth as the positions (else only through the
    decimation's anti-alias filter); `skip`: raw samples dropped at the start, after filtering
    and differentiation, before decimation; `stencil`: points of the central difference, 3 for
    the paper's eq. (22) (the default) or 5 for the fourth-order one (`central_difference5`),
    which removes the sinc distortion eq. (29) only bounds. The rigid model honours all three; `skip` applies
    to every model (it acts in `decimate_parallel`). The EMPS reference chain (Janot, Gautier,
    Brunot 2019) is wn = 2 pi 100 rad/s, m = 4, Nd = 10, zoh False, skip 49.
    """

    wn: float
    m: int
    Nd: int
    ts: float
    edge: int = 3
    zoh: bool = True
    filter_torque: bool = True
    skip: int = 0
    stencil: int = 3

    def __post_init__(self):
        nyquist = np.pi / self.ts
        if not 0 < self.wn < nyquist:
            raise ValueError(f"Butterworth frequency wn = {self.wn:g} rad/s must lie in "
                             f"(0, {nyquist:.4g}) rad/s, the Nyquist frequency at this rate")
        if self.m < 1:
            raise ValueError(f"Butterworth order m must be >= 1, got {self.m}")
        if self.Nd < 1:
            raise ValueError(f"decimation factor Nd must be >= 1, got {self.Nd}")
        if self.skip < 0:
            raise ValueError(f"samples to skip must be >= 0, got {self.skip}")
        if self.stencil not in STENCILS:
            raise ValueError(f"central-difference stencil must be 3 (eq. 22) or 5 points, "
                             f"got {self.stencil}")

    @property
    def decimated_cutoff_hz(self) -> float:
        """Cutoff of scipy.signal.decimate's anti-alias filter: 0.8 of the new Nyquist."""
        return 0.8 / (2 * self.ts * self.Nd)

    def min_samples(self, nd: int) -> int:
        """Fewest raw samples the chain needs: the edges, the derivatives and 10 rows left."""
        return self.Nd * (2 * self.edge + 10) + (self.stencil - 1) * nd + 1 + self.skip


@lru_cache(maxsize=64)
def butterworth(m: int, wn_nyquist: float) -> tuple[tuple[float, ...], ...]:
    """The Butterworth of order m at wn_nyquist (wn over the Nyquist frequency) as second-order
    sections, designed once per setting (a tuple: the cache's value cannot be changed)."""
    return tuple(map(tuple, signal.butter(m, wn_nyquist, output="sos")))


@lru_cache(maxsize=64)
def antialias(q: int) -> tuple[tuple[float, ...], ...]:
    """scipy.signal.decimate's anti-alias filter for the factor q (Chebyshev type I, order 8,
    0.05 dB ripple, cutoff 0.8 of the new Nyquist) as second-order sections, designed once
    per factor."""
    return tuple(map(tuple, signal.cheby1(8, 0.05, 0.8 / q, output="sos")))


@lru_cache(maxsize=16)
def antialias_gain(q: int, n_fft: int) -> np.ndarray:
    """The zero-phase gain |G(e^(j w Ts))|^2 of `decimate`'s anti-alias pass (`antialias`,
    forward and reverse) on the bins w Ts = 2 pi k / n_fft, k = 0 ... n_fft / 2, of a real FFT
    of length n_fft: `decimate` applied in the frequency domain (the same filter on the
    record's inside; at its ends the record continues as it is, not oddly). Made once per
    (q, n_fft), read-only: shared."""
    w = 2 * np.pi * np.arange(n_fft // 2 + 1) / n_fft
    gain = np.abs(signal.sosfreqz(np.array(antialias(q)), worN=w)[1]) ** 2
    gain.setflags(write=False)
    return gain


@lru_cache(maxsize=64)
def _zero_phase_design(sos: tuple[tuple[float, ...], ...]) -> tuple[np.ndarray, np.ndarray, int]:
    """The sections as an array, their steady-state initial conditions
    (scipy.signal.sosfilt_zi) and scipy.signal.sosfiltfilt's default odd-extension length,
    made once per filter (read-only: shared)."""
    a = np.array(sos)
    ntaps = 2 * len(a) + 1 - min(int((a[:, 2] == 0).sum()), int((a[:, 5] == 0).sum()))
    zi = signal.sosfilt_zi(a)
    zi.setflags(write=False)
    return a, zi, 3 * ntaps


def zero_phase(sos: tuple[tuple[float, ...], ...], x: np.ndarray, axis: int = -1) -> np.ndarray:
    """scipy.signal.sosfiltfilt(np.array(sos), x, axis=axis) (odd extension of the default
    length, each pass started in its steady state) with the filter's initial conditions made
    once (`_zero_phase_design`): the same operations, so the same numbers."""
    a, zi, edge = _zero_phase_design(sos)
    x = np.moveaxis(np.asarray(x, dtype=float), axis, -1)
    if x.shape[-1] <= edge:   # scipy's own error for a record shorter than the extension
        return signal.sosfiltfilt(a, np.moveaxis(x, -1, axis), axis=axis)
    ext = np.concatenate((2 * x[..., :1] - x[..., edge:0:-1], x,
                          2 * x[..., -1:] - x[..., -2:-(edge + 2):-1]), axis=-1)
    zi = zi.reshape((len(a),) + (1,) * (x.ndim - 1) + (2,))
    y, _ = signal.sosfilt(a, ext, zi=zi * ext[..., :1])
    y, _ = signal.sosfilt(a, y[..., ::-1], zi=zi * y[..., -1:])
    return np.moveaxis(y[..., ::-1][..., edge:-edge], -1, axis)


def decimate(x: np.ndarray, q: int, axis: int = 0) -> np.ndarray:
    """scipy.signal.decimate(x, q, axis=axis, zero_phase=True) with the filter designed once
    (`antialias`, `zero_phase`): the same numbers."""
    y = zero_phase(antialias(q), x, axis=axis)
    sl = [slice(None)] * y.ndim
    sl[axis] = slice(None, None, q)
    return y[tuple(sl)]


def lowpass(x: np.ndarray, wn: float, ts: float, m: int = 4) -> np.ndarray:
    """Zero-phase Butterworth of order m at wn [rad/s] (forward and reverse, eq. 25)."""
    return zero_phase(butterworth(m, wn * ts / np.pi), x)


class Lowpassed:
    """`lowpass` of a log's arrays, each filtered once per Butterworth (wn, ts, m) and kept
    while this object lives: the chooser's band and the wide one, the excitation check and
    the instruments' chains all filter the same positions with the same Butterworth (they
    differ in the decimation and the stencil). The arrays returned are read-only: they are
    shared."""

    def __init__(self) -> None:
        self._kept: dict[tuple[int, float, float, int], tuple[np.ndarray, np.ndarray]] = {}

    def __call__(self, x: np.ndarray, wn: float, ts: float, m: int = 4) -> np.ndarray:
        key = (id(x), float(wn), float(ts), int(m))
        hit = self._kept.get(key)
        if hit is not None and hit[0] is x:   # the input is held: its id is not reused
            return hit[1]
        y = lowpass(x, wn, ts, m)
        y.setflags(write=False)
        self._kept[key] = (x, y)
        return y


def central_difference(x: np.ndarray, ts: float) -> np.ndarray:
    """Eq. (22): (x[k+1] - x[k-1]) / (2 ts); the two end samples are NaN (undefined)."""
    out = np.full_like(x, np.nan, dtype=float)
    out[1:-1] = (x[2:] - x[:-2]) / (2.0 * ts)
    return out


def central_difference5(x: np.ndarray, ts: float) -> np.ndarray:
    """Fourth-order central difference (x[k-2] - 8 x[k-1] + 8 x[k+1] - x[k+2]) / (12 ts); the
    four end samples are NaN.

    Eq. (22) differentiates a sine of frequency w with the gain sin(w ts) / (w ts), so that the
    n-th derivative is short by about n (w ts)^2 / 6 (0.16 % at the prototype's 3.9 Hz mode
    for n = 2, which biases Jm up and K down by about 0.1 %); this stencil's gain
    (8 sin(w ts) - sin(2 w ts)) / (6 w ts) is short by (w ts)^4 / 30 (3e-7 there)."""
    out = np.full_like(x, np.nan, dtype=float)
    out[2:-2] = (x[:-4] - 8.0 * x[1:-3] + 8.0 * x[3:-1] - x[4:]) / (12.0 * ts)
    return out


STENCILS = {3: central_difference, 5: central_difference5}


def derivatives(x: np.ndarray, ts: float, nd: int, stencil: int = 3) -> list[np.ndarray]:
    """[x, x', ..., x^(nd)] by repeated central differences (eq. 22, or the 5-point
    `central_difference5` with `stencil=5`); NaN where undefined."""
    diff = STENCILS[stencil]
    out = [np.asarray(x, dtype=float)]
    for _ in range(nd):
        out.append(diff(out[-1], ts))
    return out


def zoh_align(tau: np.ndarray, exact: bool = False, ts: float = 1.0) -> np.ndarray:
    """The torque at the sampling instants of a zero-order-hold command.

    tau[k] is held over [t_k, t_k+1) while positions are samples at t_k; the band-limited
    torque acting at t_k is the mean of the values held on either side, (tau[k-1] + tau[k]) / 2.
    Pairing raw tau[k] with positions at t_k shifts the torque by half a sample. The paper's
    chain (eq. 22) keeps this mean.

    `exact=True` (the 5-point chain): the held torque as the 5-point second derivative sees it,
    `stencil_view(held_double_integral(tau, ts))`: an inertia driven by the held torque then
    satisfies Jm qm'' = tau exactly, whatever the frequency (the mean is short by
    (w T)^2 / 12 against the accurate stencil: 1.1 % at 20 Hz and the paper rate)."""
    tau = np.asarray(tau, dtype=float)
    if exact:
        return stencil_view(held_double_integral(tau, ts), ts)
    out = tau.copy()
    out[1:] = 0.5 * (tau[1:] + tau[:-1])
    return out


def stencil_view(S2: np.ndarray, ts: float, stencil: int = 5) -> np.ndarray:
    """A signal as the stencil's second derivative sees it, from samples S2 of its double
    integral: the derivative of positions is a weighted mean of the acceleration over the
    stencil's span, and an input that is not smooth (a held torque, a friction that switches
    between samples) must be averaged with the same weights to stay paired with it."""
    return derivatives(S2, ts, 2, stencil)[2]


def held_integrals(h: np.ndarray, ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Samples of the first and second integrals of a held signal (h[k] on [t_k, t_k+1)),
    exact between samples: S1[k+1] = S1[k] + h[k] ts, S2[k+1] = S2[k] + S1[k] ts + h[k] ts^2 / 2."""
    h = np.asarray(h, dtype=float)
    S1 = np.concatenate([[0.0], np.cumsum(h[:-1] * ts)])
    S2 = np.concatenate([[0.0], np.cumsum(S1[:-1] * ts + h[:-1] * ts ** 2 / 2)])
    return S1, S2


def held_double_integral(tau: np.ndarray, ts: float) -> np.ndarray:
    """Samples of the double integral of the held torque (tau[k] on [t_k, t_k+1)), its mean
    taken out and added back as c t^2 / 2 would be (`stencil_view` returns it exactly)."""
    tau = np.asarray(tau, dtype=float)
    c = float(np.mean(tau)) if len(tau) else 0.0
    S2 = held_integrals(tau - c, ts)[1]
    k = np.arange(len(tau)) * ts
    return S2 + c * k ** 2 / 2


def crossing_share(v0: np.ndarray, v1: np.ndarray, ts: float, rate: float = 0.0) -> np.ndarray:
    """Where in each sample interval a velocity going from v0 to v1 [rad/s] crosses zero, as
    the share theta in [0, 1] of the interval before the crossing; 1 where the sign does not
    change or a value is not finite.

    rate = 0: v taken linear between its samples. rate = FS / J > 0 [rad/s^2]: the
    acceleration, constant within the interval before the crossing (the torque is held),
    jumps by 2 rate sign(v0) at it, since the Coulomb friction turns over: v0 + a theta T = 0
    and v1 = (a + 2 rate sign(v0)) (1 - theta) T give c theta^2 + (v1 - v0 - c) theta + v0 = 0
    with c = 2 rate sign(v0) T, whose one root in [0, 1] this is (the quadratic is v0 at 0 and
    v1 at 1). At 17.5 samples a period (20 Hz at the paper's rate) the linear guess comes 0.2 sample
    late on average, and that alone leaves Jm +2.6 % (tests/unit/test_filtering.py)."""
    v0, v1 = np.asarray(v0, dtype=float), np.asarray(v1, dtype=float)
    a = np.sign(v0)
    flip = (a != np.sign(v1)) & np.isfinite(v0) & np.isfinite(v1)
    theta = np.ones(len(v0))
    d0, d1 = v0[flip], v1[flip]
    lin = d0 / (d0 - d1)
    c = 2.0 * rate * a[flip] * ts
    B = d1 - d0 - c
    disc = np.sqrt(np.maximum(B * B - 4.0 * c * d0, 0.0))
    # the root that is lin when c -> 0, in the form without cancellation: 2 v0 / (-B +- disc)
    den = -B + np.sign(-B) * disc
    with np.errstate(invalid="ignore", divide="ignore"):
        root = np.where(den != 0, 2.0 * d0 / den, lin)
    theta[flip] = np.where(c != 0, root, lin)
    return np.clip(np.nan_to_num(theta, nan=1.0), 0.0, 1.0)


def sign_integrals(v: np.ndarray, ts: float, rate: float = 0.0
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Samples of the first and second integrals of sign(v(t)): a Coulomb friction FS sign(v)
    switches where v crosses zero, between samples (`crossing_share`: v linear between its
    samples, or with the friction's kink of `rate` = FS / J). The second is NaN where v is
    (the stencil spreads it over its span; the decimation drops those rows)."""
    v = np.asarray(v, dtype=float)
    a, b = np.sign(v[:-1]), np.sign(v[1:])
    theta = crossing_share(v[:-1], v[1:], ts, rate)   # share of the step at sign a
    # the whole step at sign a (theta = 1: a ts and a ts^2 / 2), the crossings' own below
    step1, step2 = a * ts, a / 2 * ts ** 2
    k = np.flatnonzero(theta != 1)
    a, b, theta = a[k], np.where(a[k] != b[k], b[k], a[k]), theta[k]
    step1[k] = (a * theta + b * (1 - theta)) * ts
    step2[k] = (a * theta ** 2 / 2 + a * theta * (1 - theta) + b * (1 - theta) ** 2 / 2) * ts ** 2
    bad = ~(np.isfinite(v[:-1]) & np.isfinite(v[1:]))
    step1[bad], step2[bad] = 0.0, 0.0   # keep the sums finite; those samples are NaN below
    S1 = np.concatenate([[0.0], np.cumsum(step1)])
    S2 = np.concatenate([[0.0], np.cumsum(S1[:-1] * ts + step2)])
    S2[~np.isfinite(v)] = np.nan
    return S1, S2


def sign_double_integral(v: np.ndarray, ts: float, rate: float = 0.0) -> np.ndarray:
    """The second of `sign_integrals`: the position a unit Coulomb acceleration sign(v) gives."""
    return sign_integrals(v, ts, rate)[1]


def coulomb_integrals(v: np.ndarray, ts: float, rate: float = 0.0,
                      drive: Drive | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The first and second integrals of the Coulomb friction's state at the samples:
    `sign_integrals` (reversals between samples, with the kink of `rate`), or with `drive`
    (drive at the start and end of each interval [rad/s^2], viscous rate [1/s]) and
    rate > 0 the stick-slip state of `friction_state.friction_integrals`."""
    if drive is None or not rate > 0:
        return sign_integrals(v, ts, rate)
    return friction_integrals(v, drive[0], drive[1], drive[2], rate, ts)


def held_missed(held: np.ndarray, s: FilterSettings) -> np.ndarray:
    """The share of a held drive's velocity (`held` [rad/s^2] on [t_k, t_k+1)) that the chain
    misses, H1 - D(lowpass(H2)) (H1, H2 its first and second integrals; `kink_corrected`).
    Linear in `held`: a chain makes it once for the held torque and scales it by 1 / J."""
    h = np.asarray(held, dtype=float)
    h = h - np.mean(h)   # a constant's share passes the chain whole; its t^2 trips filtfilt
    return held_integrals(h, s.ts)[0] - seen_velocity(held_double_integral(h, s.ts), s)


def kink_corrected(v: np.ndarray, rate: float, s: FilterSettings, iterations: int = 3,
                   held: np.ndarray | None = None, drive: Drive | None = None,
                   inside: bool = True, missed: np.ndarray | None = None) -> np.ndarray:
    """The band-limited velocity v = D(lowpass(q)) with its zero crossings put back where the
    unfiltered velocity has them, for a Coulomb friction of `rate` = FS / J [rad/s^2].

    At a reversal the friction's acceleration jumps by 2 FS / J: the velocity has a kink, and
    the zero-phase filter, which averages across it, moves its zero crossing later by about
    2 (FS / J) m1 / |q''| (m1 the filter's first half-moment). The sign(v) column then
    switches late, and the torque error it leaves at every reversal is correlated with q'':
    Jm comes out high (+1.7 % on a heavy link, +0.6 % on arm6 axis 2 at the paper rate).
    With S = integral of sign(v), the friction's share of the velocity is -rate S, which the
    chain sees as -rate D(lowpass(integral S)); so v_true = v + rate (D(lowpass(int S)) - S),
    solved by fixed-point iteration from sign(v), the crossings placed with the kink
    (`sign_integrals` with `rate`). NaN where v is.

    `held` [rad/s^2]: the held torque over the inertia, tau[k] / J on [t_k, t_k+1) (a
    zero-order-hold drive). Its steps at every sample are the velocity's other kinks: a stiff
    velocity loop answers a reversal within a sample, and the filter averages that answer
    into the crossing too. Its share the chain misses, H1 - D(lowpass(H2)) (H1, H2 its first
    and second integrals), is added like the friction's (`held_missed`; `missed`: that share
    already made, in place of `held`). `drive`: the friction's share taken with its stick phases
    (`coulomb_integrals`). `inside` False: the crossings placed linearly between samples (a
    plant that switches its friction once a sample, `regressors.joint_motor`)."""
    v = np.asarray(v, dtype=float)
    base = np.nan_to_num(v)
    if held is not None:
        missed = held_missed(held, s)
    if missed is not None:
        base = base + np.nan_to_num(missed)
    u = base
    for _ in range(iterations):
        S1, S2 = coulomb_integrals(u, s.ts, rate if inside else 0.0, drive)
        seen = seen_velocity(S2, s)
        u = np.where(np.isfinite(seen), base + rate * (seen - S1), base)   # ends: as filtered
    u = u.copy()
    u[~np.isfinite(v)] = np.nan
    return u


def seen_velocity(P: np.ndarray, s: FilterSettings) -> np.ndarray:
    """D(lowpass(P)): the chain's velocity of positions P (NaN at the stencil's ends)."""
    return derivatives(lowpass(np.nan_to_num(P), s.wn, s.ts, s.m), s.ts, 1, s.stencil)[1]


def stencil_sign(v: np.ndarray, ts: float, stencil: int = 5, rate: float = 0.0) -> np.ndarray:
    """sign(v) as the stencil's second derivative sees it (`stencil_view` of
    `sign_double_integral`): each reversal placed where v crosses zero between samples (with
    the friction's kink of `rate` = FS / J, `crossing_share`) and weighted as the acceleration
    it causes is. Where v is NaN the result is NaN."""
    return stencil_view(sign_double_integral(v, ts, rate), ts, stencil)


def decimate_parallel(y: np.ndarray, W: np.ndarray, settings: FilterSettings
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lowpass and resample y and every column of W by Nd (scipy.signal.decimate, zero phase),
    then drop the samples spoiled by the filters at both ends and any row with NaN.

    Returns (y_d, W_d, index) where `index` holds the raw sample index of each kept row.
    """
    n = len(y)
    valid = np.all(np.isfinite(W), axis=1) & np.isfinite(y)
    first, last = max(int(np.argmax(valid)), settings.skip), n - np.argmax(valid[::-1])
    sl = slice(first, last)
    if settings.Nd > 1:
        yd = decimate(y[sl], settings.Nd)
        Wd = decimate(W[sl], settings.Nd, axis=0)
    else:
        yd, Wd = y[sl].copy(), W[sl].copy()
    return kept_rows(yd, Wd, first, settings)


def kept_rows(yd: np.ndarray, Wd: np.ndarray, first: int, settings: FilterSettings
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`decimate_parallel`'s rows of y_d, W_d decimated from the raw sample `first` on: the
    `edge` rows spoiled by the filters dropped at both ends and any row with NaN; returns
    (y_d, W_d, index) with the raw sample index of each kept row."""
    index = first + np.arange(len(yd)) * settings.Nd
    e = settings.edge
    keep = slice(e, len(yd) - e)
    yd, Wd, index = yd[keep], Wd[keep], index[keep]
    ok = np.all(np.isfinite(Wd), axis=1) & np.isfinite(yd)
    return yd[ok], Wd[ok], index[ok]


def stencil_gain(w_ts: np.ndarray, stencil: int = 5) -> np.ndarray:
    """The gain of the stencil's first derivative relative to the true one at w Ts:
    sin(x) / x (eq. 22) or (8 sin x - sin 2x) / (6 x) (5 points); 1 at 0."""
    x = np.asarray(w_ts, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        g = np.sin(x) / x if stencil == 3 else (8 * np.sin(x) - np.sin(2 * x)) / (6 * x)
    return np.where(x == 0, 1.0, g)


@lru_cache(maxsize=32)
def _mirrored_gain(n: int, stencil: int, order: int) -> np.ndarray:
    """`as_acceleration_sees`' gain g(w_k Ts)^(2 - order) at w_k Ts = pi k / n, k < n (the
    mirrored record's bins), made once per length (read-only: shared)."""
    gain = stencil_gain(np.pi * np.arange(n) / n, stencil) ** (2 - order)
    gain.setflags(write=False)
    return gain


def as_acceleration_sees(x: np.ndarray, ts: float, order: int | Sequence[int],
                         stencil: int = 5) -> np.ndarray:
    """A column that holds derivative `order` (0 or 1) of a sampled signal x as the second
    stencil derivative sees the acceleration: the stencil's second derivative of samples is the
    acceleration weighted over its span, the gain G = g(w Ts)^2 (g = `stencil_gain`), so an
    equation Jm qm'' = tau - K (qm - q) - FV qm' holds between samples only with the other
    terms weighted alike: x times g^(2 - order) (order 1: x is already a stencil derivative,
    gain g). At 20 Hz and the paper's rate, 1 - G is 0.1 % (0.4 % at 28 Hz), the size of the Jm
    excess it leaves. Zero phase: the gain applied to the mirrored record [x, x reversed] (no
    jump at the ends), whose discrete Fourier transform at w_k Ts = pi k / n is x's DCT-II
    times exp(i w_k Ts / 2): a DCT-II, the gain and the inverse transform, of half the
    mirrored record's length. NaN where x is. x may hold several signals, one a row, each
    with its `order` (a sequence): transformed together."""
    x = np.asarray(x, dtype=float)
    bad = ~np.isfinite(x)
    y = np.where(bad, 0.0, x)
    n = y.shape[-1]
    gain = (_mirrored_gain(n, stencil, order) if np.ndim(order) == 0 else
            np.stack([_mirrored_gain(n, stencil, k) for k in order]))
    out = scipy_fft.idct(scipy_fft.dct(y, type=2, axis=-1) * gain, type=2, axis=-1)
    out[bad] = np.nan
    return out
