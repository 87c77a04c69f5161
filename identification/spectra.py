"""Welch spectra of one log's signals from short-time Fourier transforms taken once.

`scipy.signal.csd`, `welch` and `coherence` transform both of their signals at every call:
a frequency response from the reference (S(q_ref, out) / S(q_ref, tau_m) and the two
coherences) transforms q_ref four times, and the first mode measures two responses on the
whole record and on two half-records. `Spectra` keeps each signal's segments' transforms
(Hann window, constant detrend, the same `ShortTimeFFT` as scipy's) per segmentation, taken
in one FFT call over all segments (`segment_transforms`), and forms every spectrum from them
once with scipy's own operations in scipy's order (`ShortTimeFFT.spectrogram`'s product, the
one-sided doubling, the mean over segments): the same numbers as the functions it replaces.
Pure numerics: no I/O.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy import fft, signal

from jointbench.identification.log import Log

T = TypeVar("T")
SIGNALS = ("q_ref", "q_m", "q", "tau_m")

# (signal name, first sample, end sample, nperseg, noverlap)
_Key = tuple[str, int, int, int, int]


def segment_transforms(x: np.ndarray, sft: signal.ShortTimeFFT, noverlap: int) -> np.ndarray:
    """`sft.stft_detrend(x, "constant", p0=0, p1=(len(x) - noverlap) // sft.hop,
    k_offset=nperseg // 2)`, the transforms csd takes of x's segments (frequency by segment),
    in one FFT call over all segments instead of scipy's loop over them (`_transformed`):
    the same numbers."""
    count = (len(x) - noverlap) // sft.hop
    return _transformed(sliding_window_view(np.asarray(x, dtype=float),
                                            len(sft.win))[::sft.hop][:count], sft)


def _transformed(segs: np.ndarray, sft: signal.ShortTimeFFT) -> np.ndarray:
    """The one-sided FFTs (frequency by segment) of the segments `segs` (segment by sample),
    each with its mean taken out and times the scaled window: scipy's operations on each."""
    segs = segs - np.mean(segs, axis=-1, keepdims=True)
    return fft.rfft((segs * sft.win.conj()).T, n=sft.mfft, axis=0)


def _average(P: np.ndarray, nperseg: int) -> np.ndarray:
    """csd's one-sided doubling and mean over the segments, in its order."""
    P = np.moveaxis(P, 0, -1)
    P[..., 1:-1 if nperseg % 2 == 0 else None] *= 2
    P = np.moveaxis(P, -1, 0)
    return P.mean(axis=-1) if P.shape[-1] > 1 else np.reshape(P, P.shape[:-1])


def _shared(x: np.ndarray) -> np.ndarray:
    x.setflags(write=False)
    return x


def welch(x: np.ndarray, fs: float, nperseg: int, detrend: str = "constant"
          ) -> tuple[np.ndarray, np.ndarray]:
    """scipy.signal.welch(x, fs, nperseg=nperseg, detrend=detrend) (half overlap, Hann
    window, density) with its segments transformed in one call (`segment_transforms`): the
    same numbers with the constant detrend; with the linear one ("linear": the least-squares
    line of each segment taken out, all segments in one product with the line's projector)
    the same up to rounding."""
    nperseg = int(nperseg)
    noverlap = nperseg // 2
    sft = signal.ShortTimeFFT(signal.get_window("hann_periodic", nperseg), nperseg - noverlap,
                              fs, fft_mode="onesided", mfft=nperseg, scale_to="psd",
                              phase_shift=None)
    if detrend == "constant":
        S = segment_transforms(x, sft, noverlap)
    elif detrend == "linear":
        count = (len(x) - noverlap) // sft.hop
        segs = sliding_window_view(np.asarray(x, dtype=float), nperseg)[::sft.hop][:count]
        A = np.column_stack([np.arange(1, nperseg + 1) / nperseg, np.ones(nperseg)])
        segs = segs - (segs @ np.linalg.pinv(A).T) @ A.T
        S = fft.rfft((segs * sft.win.conj()).T, n=sft.mfft, axis=0)
    else:
        raise ValueError(f"detrend must be 'constant' or 'linear', got {detrend!r}")
    P = _average(S.real ** 2 + S.imag ** 2, nperseg)
    return sft.f, P.astype(np.result_type(float, np.complex64)).real


class Spectra:
    """Welch's estimates (`csd`, `welch`, `coherence`) of the log's columns `SIGNALS` over
    the samples [start, stop), segments of `nperseg` overlapping by `noverlap` (None: half),
    density scaling, one-sided, Hann window, constant detrend: scipy.signal's defaults, with
    each signal's short-time transforms computed once per segmentation. `hold_hz` and
    `decimation`: the logged record's rate and the factor `log` was decimated by when it is
    a decimated copy of it (`first_mode.analysis_log`)."""

    def __init__(self, log: Log, hold_hz: float | None = None, decimation: int = 1):
        self.log = log
        self.fs = log.sample_rate_hz
        # the rate the torque was held at (its zero-order hold) and the factor `log` was
        # decimated by: `log` may be a decimated copy of the logged record
        self.hold_hz = float(hold_hz) if hold_hz is not None else self.fs
        self.decimation = int(decimation)
        self._stft: dict[_Key, np.ndarray] = {}
        self._sft: dict[tuple[int, int], signal.ShortTimeFFT] = {}
        self._memo: dict[str, object] = {}
        self._spectra: dict[tuple, np.ndarray] = {}   # csd and welch results, read-only

    def memo(self, name: str, compute: Callable[[], T]) -> T:
        """compute() once for this log under `name` (a figure derived from its spectra)."""
        if name not in self._memo:
            self._memo[name] = compute()
        return self._memo[name]

    def _transform(self, key: _Key) -> np.ndarray:
        if key not in self._stft:
            name, start, stop, nperseg, noverlap = key
            x = np.asarray(getattr(self.log, name))[start:stop]
            self._stft[key] = segment_transforms(x, self._sft_for(nperseg, noverlap), noverlap)
        return self._stft[key]

    def _sft_for(self, nperseg: int, noverlap: int) -> signal.ShortTimeFFT:
        """csd's own ShortTimeFFT for this segmentation, built once."""
        if (nperseg, noverlap) not in self._sft:
            self._sft[(nperseg, noverlap)] = signal.ShortTimeFFT(
                signal.get_window("hann_periodic", nperseg), nperseg - noverlap, self.fs,
                fft_mode="onesided", mfft=nperseg, scale_to="psd", phase_shift=None)
        return self._sft[(nperseg, noverlap)]

    def _key(self, name: str, sl: slice, nperseg: int, noverlap: int | None) -> _Key:
        if name not in SIGNALS or getattr(self.log, name) is None:
            raise ValueError(f"no signal {name!r} in the log")
        start, stop, _ = sl.indices(len(self.log))
        return (name, start, stop, int(nperseg),
                int(noverlap) if noverlap is not None else int(nperseg) // 2)

    def frequencies(self, nperseg: int) -> np.ndarray:
        """The bins [Hz] of segments of `nperseg` samples (scipy.signal.csd's first output)."""
        return self._sft_for(int(nperseg), int(nperseg) // 2).f

    def csd(self, x: str, y: str, nperseg: int, noverlap: int | None = None,
            sl: slice = slice(None)) -> np.ndarray:
        """scipy.signal.csd(log.x[sl], log.y[sl], fs, nperseg=..., noverlap=...)[1] of two
        distinct arrays (scipy's csd of one array with itself, `y is x`, is its `welch`)."""
        kx, ky = self._key(x, sl, nperseg, noverlap), self._key(y, sl, nperseg, noverlap)
        key = ("csd", kx, ky)
        if key not in self._spectra:
            Sx, Sy = self._transform(kx), self._transform(ky)
            self._spectra[key] = _shared(_average(Sy * Sx.conj(), kx[3]).astype(
                np.result_type(float, np.complex64)))
        return self._spectra[key]

    def welch(self, x: str, nperseg: int, noverlap: int | None = None,
              sl: slice = slice(None)) -> np.ndarray:
        """scipy.signal.welch(log.x[sl], fs, nperseg=..., noverlap=...)[1]."""
        k = self._key(x, sl, nperseg, noverlap)
        key = ("welch", k)
        if key not in self._spectra:
            Sx = self._transform(k)
            P = _average(Sx.real ** 2 + Sx.imag ** 2, k[3])
            self._spectra[key] = _shared(P.astype(np.result_type(float, np.complex64)).real)
        return self._spectra[key]

    def coherence(self, x: str, y: str, nperseg: int, noverlap: int | None = None,
                  sl: slice = slice(None)) -> np.ndarray:
        """scipy.signal.coherence(log.x[sl], log.y[sl], fs, nperseg=..., noverlap=...)[1]."""
        Pxx = self.welch(x, nperseg, noverlap, sl)
        Pyy = self.welch(y, nperseg, noverlap, sl)
        Pxy = self.csd(x, y, nperseg, noverlap, sl)
        return np.abs(Pxy) ** 2 / Pxx / Pyy
