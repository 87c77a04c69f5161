"""The band-limited raw-rate signals of one log (section 3.2) that every column of the
discrepancy regression is built from, and their common decimation."""

from __future__ import annotations

import functools
import hashlib
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
from scipy import signal

from jointbench.identification.filtering import FilterSettings, derivatives, lowpass, zoh_align
from jointbench.identification.log import Log, LogError
from jointbench.identification.saturation import clipped_samples, reach


@dataclass(frozen=True)
class Signals:
    """Band-limited raw-rate signals of one log (section 3.2), shared by every column."""

    ts: float
    g: float
    qm: np.ndarray
    qmd: np.ndarray
    qmdd: np.ndarray
    tau: np.ndarray          # measured torque, ZOH-aligned and low-passed
    tau_raw: np.ndarray      # measured torque, as logged
    q: np.ndarray | None
    qd: np.ndarray | None
    qdd: np.ndarray | None
    qs: float                # rest position assumed by the nominal gravity term
    settings: FilterSettings
    sl: slice                # raw samples that every derivative defines
    index: np.ndarray        # raw index of each decimated row (kept rows only)
    keep: np.ndarray | None = None   # decimated rows kept (None: all): clipped torque out
    # the encoders' counts, motor and link (count; 0 for the link without q)
    qm_step: float = 0.0
    q_step: float = 0.0
    # dec's results by the content of the column: the rounds rebuild the same trial columns
    # from fresh arrays (each look-ahead chain, each refit), and a decimation costs a
    # thousand times a hash. init=False: a dataclasses.replace gets an empty one.
    _decimated: OrderedDict = field(init=False, default_factory=OrderedDict, compare=False,
                                    repr=False)

    @property
    def has_link(self) -> bool:
        return self.q is not None

    def lp(self, x: np.ndarray) -> np.ndarray:
        s = self.settings
        return lowpass(x, s.wn, s.ts, s.m)

    def release(self) -> None:
        """Drop dec's kept results (a diagnosis's answer holds its rows, not its trials)."""
        self._decimated.clear()

    def dec(self, x: np.ndarray) -> np.ndarray:
        """The raw-rate column x on the decimated rows (scipy.signal.decimate, zero phase:
        its order-8 Chebyshev I at 0.8 / Nd, designed once per Nd)."""
        s = self.settings
        x = np.ascontiguousarray(np.asarray(x, dtype=float)[self.sl])
        key = (x.shape, hashlib.sha256(x.data).digest())
        kept = self._decimated
        hit = kept.get(key)
        if hit is not None:
            kept.move_to_end(key)
            return hit.copy()
        xd = _filtfilt(s.Nd, x)[::s.Nd] if s.Nd > 1 else x
        e = s.edge
        xd = xd[e:len(xd) - e]
        xd = xd if self.keep is None else xd[self.keep]
        kept[key] = xd.copy()
        while len(kept) * xd.nbytes > DECIMATED_BYTES and len(kept) > 1:
            kept.popitem(last=False)
        return xd


# The memory dec's results may hold per log, least recently used dropped first: the trial
# columns of a 60 s log at 350 Hz (about a thousand distinct ones, 20 kB each) fit whole.
DECIMATED_BYTES = 64 * 2**20


@functools.lru_cache(maxsize=8)
def _antialias(q: int) -> tuple[np.ndarray, np.ndarray, int, int]:
    """scipy.signal.decimate's zero-phase IIR filter for factor q (the same sos), its
    steady-state initial conditions, sosfiltfilt's default odd padding and the chunk over
    which its fastest pole decays by no more than sqrt(tiny) (_sosfilt)."""
    sos = signal.cheby1(8, 0.05, 0.8 / q, output="sos")
    ntaps = 2 * len(sos) + 1 - min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum()))
    r = min(float(np.abs(np.roots([1.0, *a])).max()) for a in sos[:, 4:])
    chunk = max(64, int(np.log(TINY / FLUSH) / np.log(r)))
    return sos, signal.sosfilt_zi(sos), 3 * ntaps, chunk


# A filter state below FLUSH is set to 0 between chunks (_sosfilt): the anti-alias filter's
# fast sections, fed the exact zeros of a trial column (a dead band's torque inside its
# band), decay into subnormal numbers, whose arithmetic costs tens of times a normal one.
# A state under sqrt(tiny) changes only outputs that small themselves (under 1e-100 through
# these sections' gains: tests/unit/test_decimation.py); no column of the regression comes
# near.
TINY = float(np.finfo(float).tiny)
FLUSH = float(np.sqrt(TINY))


def _sosfilt(sos: np.ndarray, x: np.ndarray, zi: np.ndarray, chunk: int) -> np.ndarray:
    """scipy.signal.sosfilt(sos, x, zi=zi)'s output, run by chunks (the recursion carries over
    exactly) with the states under FLUSH set to 0 between them: no state reaches the
    subnormal range within a chunk from above FLUSH (the chunk's length: _antialias)."""
    y = np.empty_like(x)
    for i in range(0, len(x), chunk):
        y[i:i + chunk], zi = signal.sosfilt(sos, x[i:i + chunk], zi=zi)
        zi[np.abs(zi) < FLUSH] = 0.0
    return y


def _filtfilt(q: int, x: np.ndarray) -> np.ndarray:
    """scipy.signal.sosfiltfilt(sos, x) of the factor-q filter, same arithmetic but for the
    states flushed under sqrt(tiny) (_sosfilt), with the filter designed once (diagnose
    decimates thousands of trial columns)."""
    sos, zi, edge, chunk = _antialias(q)
    if len(x) <= edge:
        return signal.sosfiltfilt(sos, x)
    ext = np.concatenate((2 * x[0:1] - x[edge:0:-1], x, 2 * x[-1:] - x[-2:-(edge + 2):-1]))
    y = _sosfilt(sos, ext, zi * ext[0], chunk)
    y = _sosfilt(sos, y[::-1].copy(), zi * y[-1], chunk)
    return y[::-1][edge:-edge]


def signals(log: Log, settings: FilterSettings, limit_applied: bool = False) -> Signals:
    """Filter and differentiate the log once (eq. 22 after the Butterworth of eq. 25); the
    rows within reach of a clipped torque sample left out (`limit_applied`: _unclipped)."""
    s = settings
    n = len(log.t)
    if n < s.min_samples(2):  # before filtering: the filter itself needs a few samples
        raise LogError(f"{n} samples are too few for the diagnosis filter (Nd = {s.Nd}): at "
                       f"least {s.min_samples(2)} are needed", log.path)
    qm, qmd, qmdd = derivatives(lowpass(log.q_m, s.wn, s.ts, s.m), s.ts, 2, s.stencil)
    q = qd = qdd = None
    if log.q is not None:
        q, qd, qdd = derivatives(lowpass(log.q, s.wn, s.ts, s.m), s.ts, 2, s.stencil)
    sl = slice(max(2, s.skip), n - 2)
    m = len(range(*sl.indices(n)))
    nd = (m + s.Nd - 1) // s.Nd if s.Nd > 1 else m
    index = sl.start + np.arange(nd) * s.Nd
    index = index[s.edge:nd - s.edge]
    head = max(1, min(n // 100, 20))
    qs = float(np.mean((log.q if log.q is not None else log.q_m)[:head]))
    tau_f = lowpass(zoh_align(log.tau_m), s.wn, s.ts, s.m)
    keep = _unclipped(log, s, index, limit_applied)
    return Signals(ts=s.ts, g=log.gravity, qm=qm, qmd=qmd, qmdd=qmdd, tau=tau_f,
                   tau_raw=np.asarray(log.tau_m, float), q=q, qd=qd, qdd=qdd, qs=qs,
                   settings=s, sl=sl, index=index if keep is None else index[keep], keep=keep,
                   qm_step=count(log.q_m), q_step=count(log.q) if log.q is not None else 0.0)


def count(x: np.ndarray) -> float:
    """An encoder's count read from its log: the least step between the distinct positions
    it logged (0 where it logged one)."""
    steps = np.diff(np.unique(np.asarray(x, float)))
    return float(steps.min()) if len(steps) else 0.0


def _unclipped(log: Log, s: FilterSettings, index: np.ndarray,
               limit_applied: bool = False) -> np.ndarray | None:
    """The decimated rows out of reach of a clipped torque sample (identification.saturation,
    as identify's exclude_clipped does), or None when no sample is clipped. No share is
    refused here: what the rows left can and cannot say is the diagnosis's to state
    (bench.analysis.diagnose.verdict). `limit_applied`: the torque at the metadata's tau_max
    is the one the axis received, its rows kept (saturation.clipped_samples)."""
    clip = clipped_samples(log, limit_applied)
    if not clip.count:
        return None
    h = reach(s.wn, s.ts, s.Nd)
    spoiled = np.convolve(clip.mask.astype(float), np.ones(2 * h + 1), mode="same") > 0.5
    return ~spoiled[index]


def stack(sig: Signals, motor: np.ndarray | None, link: np.ndarray | None) -> np.ndarray:
    """One regression column: the motor-equation rows, then (with q) the link-equation rows;
    None is a zero block."""
    n = len(sig.index)
    m = sig.dec(motor) if motor is not None else np.zeros(n)
    if not sig.has_link:
        return m
    if link is None:
        li = np.zeros(n)
    elif motor is not None and np.array_equal(link, -motor):
        # a spring's column (K, Kh, D: the link equation's row is the motor's negative): the
        # decimation is linear and IEEE rounding symmetric in sign, so its -dec(x) is exactly
        # dec(-x), at a 25th of the cost (every trial of a dead band rebuilds one)
        li = -m
    else:
        li = sig.dec(link)
    return np.concatenate([m, li])
