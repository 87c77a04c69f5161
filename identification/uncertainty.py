"""Autocorrelation-consistent covariance of the least-squares estimate (beside the paper's).

The paper's statistics (section 3.1) take the residuals of y = W X + rho as white with one
variance: sigma^2 = ||rho||^2 / (r - Np), C = sigma^2 (W^T W)^-1. After the lowpass
filtering and the decimation of section 3.2 they are not: the decimation's anti-alias filter
leaves them coloured, and the model errors (Coulomb stick phases at velocity reversals,
central-difference distortion) come in bursts that follow the chirp. The sandwich

    C_hac = r / (r - Np) * B^-1 S B^-1,   B = W^T W,   S = sum_l k(l / b) Gamma_l,
    Gamma_l = sum_t v_(t+l) v_t^T (Gamma_-l = Gamma_l^T),   v_t = W_t^T rho_t,

estimates the covariance of X^ whatever the residuals' spectrum and variance profile
(heteroscedasticity and autocorrelation consistent, HAC: Newey and West 1987, Andrews 1991).
Here:

- the scores v_t are prewhitened by a VAR(1), v_t = A v_(t-1) + e_t, and S is recoloured,
  S = (I - A)^-1 S_e (I - A)^-T (Andrews and Monahan 1992); A's singular values are capped at
  0.97 as they advise, so that a near unit root cannot blow S up;
- the kernel k is the quadratic spectral kernel (or Bartlett, Newey-West), with the bandwidth
  b chosen from the data by Andrews' (1991) AR(1) plug-in rule;
- rows that share a sampling instant (the motor and link equations of eq. 13 stacked as two
  blocks) add their scores into one v_t, so the covariance between the blocks, at every lag,
  is counted once and consistently;
- the factor r / (r - Np) is the paper's degrees-of-freedom correction: with white residuals
  of one variance and b -> 0, C_hac tends to the paper's C.

Pure numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KERNELS = ("qs", "bartlett")
AR_CAP = 0.97  # Andrews and Monahan (1992): cap on the prewhitening VAR(1)'s singular values


@dataclass(frozen=True)
class HACResult:
    """The sandwich covariance of X^ and how it was obtained.

    `cov` is in the parameters' own units; `bandwidth` the kernel bandwidth b in samples of
    the score series; `n_times` the length of that series; `ar1` the mean lag-one
    autocorrelation of the score components (before prewhitening); `inflation` the ratio
    sqrt(diag C_hac / diag C_paper) when the paper's C was given, else NaN.
    """

    cov: np.ndarray
    kernel: str
    bandwidth: float
    prewhitened: bool
    n_times: int
    ar1: float
    inflation: np.ndarray

    @property
    def sigma(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov))


def kernel_weights(lags: np.ndarray, bandwidth: float, kernel: str = "qs") -> np.ndarray:
    """k(l / b) for the Bartlett kernel (1 - |x| on |x| < 1) or the quadratic spectral kernel
    k(x) = 25 / (12 pi^2 x^2) (sin(6 pi x / 5) / (6 pi x / 5) - cos(6 pi x / 5)), k(0) = 1
    (Andrews 1991, eq. 2.7)."""
    if kernel not in KERNELS:
        raise ValueError(f"unknown kernel {kernel!r} (choices: {', '.join(KERNELS)})")
    x = np.abs(np.asarray(lags, dtype=float)) / max(bandwidth, 1e-12)
    if kernel == "bartlett":
        return np.clip(1.0 - x, 0.0, None)
    z = 6.0 * np.pi * x / 5.0
    with np.errstate(divide="ignore", invalid="ignore"):
        k = 25.0 / (12.0 * np.pi ** 2 * x ** 2) * (np.sin(z) / z - np.cos(z))
    return np.where(x < 1e-8, 1.0, k)


def autocovariances(v: np.ndarray, max_lag: int) -> np.ndarray:
    """Gamma_l = sum_t v_(t+l) v_t^T for l = 0..max_lag (sums, not means), by FFT:
    an array of shape (max_lag + 1, p, p)."""
    v = np.asarray(v, dtype=float)
    n, p = v.shape
    max_lag = int(min(max_lag, n - 1))
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    F = np.fft.rfft(v, n=nfft, axis=0)
    G = np.fft.irfft(F[:, :, None] * np.conj(F[:, None, :]), n=nfft, axis=0)
    return G[: max_lag + 1]


def kernel_sum(v: np.ndarray, k: np.ndarray) -> np.ndarray:
    """S = k_0 Gamma_0 + sum_(l >= 1) k_l (Gamma_l + Gamma_l^T) (`autocovariances`, lags
    0 ... len(k) - 1) in the frequency domain: with F_a the FFT of score a zero-padded to
    N >= 2 n samples (no lag wraps around) and K the FFT of the lag weights k_|l| laid out
    circularly (real: they are even), S_ab = (1 / N) sum_f K_f Re(F_a(f) conj(F_b(f))), one
    FFT per score and one for the weights in place of one inverse FFT per pair of scores."""
    v = np.asarray(v, dtype=float)
    n, p = v.shape
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    w = np.zeros(nfft)
    w[:len(k)] = k
    w[nfft - len(k) + 1:] = k[:0:-1]
    K = np.fft.rfft(w).real
    K[1:(nfft + 1) // 2] *= 2.0   # the negative frequencies, conjugate to the positive ones
    F = np.fft.rfft(v, n=nfft, axis=0)
    return ((F.real * K[:, None]).T @ F.real + (F.imag * K[:, None]).T @ F.imag) / nfft


def andrews_bandwidth(v: np.ndarray, kernel: str = "qs") -> float:
    """Andrews' (1991) plug-in bandwidth from AR(1) fits of each score component a,
    rho_a and innovation variance s_a^2 (unit weights; section 6 of the paper):

        bartlett: b = 1.1447 (alpha1 n)^(1/3),
                  alpha1 = sum 4 rho^2 s^4 / ((1 - rho)^6 (1 + rho)^2) / sum s^4 / (1 - rho)^4
        qs:       b = 1.3221 (alpha2 n)^(1/5),
                  alpha2 = sum 4 rho^2 s^4 / (1 - rho)^8 / sum s^4 / (1 - rho)^4

    capped at n - 1. rho_a is clipped to +-0.97 so that a near unit root cannot make b
    infinite."""
    v = np.asarray(v, dtype=float)
    n = len(v)
    if n < 3:
        return 0.0
    x0, x1 = v[:-1], v[1:]
    den = np.sum(x0 * x0, axis=0)
    ok = den > 0
    if not ok.any():
        return 0.0
    rho = np.clip(np.sum(x1[:, ok] * x0[:, ok], axis=0) / den[ok], -AR_CAP, AR_CAP)
    s2 = np.mean((x1[:, ok] - rho * x0[:, ok]) ** 2, axis=0)
    s4 = s2 ** 2
    norm = np.sum(s4 / (1 - rho) ** 4)
    if norm <= 0:
        return 0.0
    if kernel == "bartlett":
        alpha = np.sum(4 * rho ** 2 * s4 / ((1 - rho) ** 6 * (1 + rho) ** 2)) / norm
        b = 1.1447 * (alpha * n) ** (1.0 / 3.0)
    elif kernel == "qs":
        alpha = np.sum(4 * rho ** 2 * s4 / (1 - rho) ** 8) / norm
        b = 1.3221 * (alpha * n) ** 0.2
    else:
        raise ValueError(f"unknown kernel {kernel!r} (choices: {', '.join(KERNELS)})")
    return float(min(b, n - 1))


def long_run_covariance(v: np.ndarray, kernel: str = "qs", bandwidth: float | None = None,
                        prewhiten: bool = True) -> tuple[np.ndarray, float]:
    """S = sum_l k(l / b) Gamma_l, the long-run covariance of sum_t v_t (times n: sums, not
    means), with optional VAR(1) prewhitening and recolouring. Returns (S, b)."""
    v = np.asarray(v, dtype=float)
    n, p = v.shape
    A = None
    if prewhiten and n > 2 * p + 2:
        x0, x1 = v[:-1], v[1:]
        M = x0.T @ x0
        if np.linalg.matrix_rank(M) == p:
            A = np.linalg.solve(M, x0.T @ x1).T  # v_t = A v_(t-1) + e_t
            U, sv, Vt = np.linalg.svd(A)
            A = (U * np.minimum(sv, AR_CAP)) @ Vt
            v = x1 - x0 @ A.T
    b = andrews_bandwidth(v, kernel) if bandwidth is None else float(bandwidth)
    max_lag = len(v) - 1 if kernel == "qs" else int(np.floor(b))
    S = kernel_sum(v, kernel_weights(np.arange(min(max_lag, len(v) - 1) + 1), b, kernel))
    if A is not None:
        R = np.linalg.inv(np.eye(p) - A)
        S = R @ S @ R.T * (n / (n - 1))  # one score lost to the VAR(1)
    return 0.5 * (S + S.T), b


def score_series(W: np.ndarray, rho: np.ndarray, time: np.ndarray | None = None
                 ) -> np.ndarray:
    """v_t = sum over the rows i at instant t of W_i^T rho_i, in time order. Without `time`
    every row is its own instant (one equation block)."""
    W = np.asarray(W, dtype=float)
    rows = W * np.asarray(rho, dtype=float)[:, None]
    if time is None:
        return rows
    time = np.asarray(time)
    if time.shape != (len(W),):
        raise ValueError(f"time has shape {time.shape}, expected ({len(W)},): one instant per row")
    uniq, inv = np.unique(time, return_inverse=True)
    # each instant's rows summed in row order, a column at a time (np.add.at's sums)
    return np.column_stack([np.bincount(inv, weights=c, minlength=len(uniq)) for c in rows.T])


def hac_covariance(W: np.ndarray, rho: np.ndarray, time: np.ndarray | None = None,
                   kernel: str = "qs", bandwidth: float | None = None, prewhiten: bool = True,
                   cov_paper: np.ndarray | None = None,
                   instruments: np.ndarray | None = None) -> HACResult:
    """The sandwich covariance of the least-squares X^ = argmin ||y - W X|| with residual rho
    (module docstring). W and rho are the rows actually solved (already weighted for a
    weighted least squares). `time` labels the rows' sampling instants (rows with the same
    label belong to one instant; labels in time order). Raises ValueError on shape mismatch
    or a rank-deficient W. With `instruments` Z (the shape of W, weighted alike) the sandwich
    of the instrumental-variable estimate: bread (Z^T W)^-1, scores Z_i rho_i."""
    W = np.asarray(W, dtype=float)
    rho = np.asarray(rho, dtype=float)
    if W.ndim != 2 or rho.shape != (W.shape[0],):
        raise ValueError(f"W is {W.shape} and rho {rho.shape}: one residual per row expected")
    r, p = W.shape
    if r <= p:
        raise ValueError(f"{r} equations for {p} parameters: no covariance")
    scale = np.linalg.norm(W, axis=0)
    if np.any(scale == 0):
        raise ValueError("W has a zero column: drop the unidentifiable parameters first")
    Ws = W / scale  # unit-norm columns: the bandwidth rule weighs every parameter alike
    Zs = Ws
    if instruments is not None:
        Z = np.asarray(instruments, dtype=float)
        zn = np.linalg.norm(Z, axis=0)
        Zs = Z / np.where(zn > 0, zn, 1.0)
    v = score_series(Zs, rho, time)
    S, b = long_run_covariance(v, kernel, bandwidth, prewhiten)
    Binv = np.linalg.inv(Zs.T @ Ws)
    cov_s = (r / (r - p)) * Binv @ S @ (Binv if instruments is None else Binv.T)
    cov = cov_s / np.outer(scale, scale)
    cov = 0.5 * (cov + cov.T)
    vv = v - v.mean(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ar1 = float(np.nanmean(np.sum(vv[1:] * vv[:-1], axis=0) / np.sum(vv * vv, axis=0)))
        inflation = (np.sqrt(np.diag(cov) / np.diag(cov_paper)) if cov_paper is not None
                     else np.full(p, np.nan))
    return HACResult(cov=cov, kernel=kernel, bandwidth=b, prewhitened=prewhiten,
                     n_times=len(v), ar1=ar1, inflation=inflation)
