"""Monte Carlo statistics of a campaign: per parameter the bias, the empirical standard
deviation, the mean reported sigma and the coverage of the +-k sigma interval.

Pure numerics over arrays of estimates X^_i, truths X_i and reported sigmas s_i (one entry per
run; NaN where a run has no value). With e_i = X^_i - X_i:

    bias = mean(e),  std = std(e, ddof=1),  coverage_k = #{|e_i| <= k s_i} / n,

the last with its Wilson score interval. If the reported sigma is calibrated, std ~ mean(s)
and the +-2 sigma coverage is about 95.4 % (the paper's sigma assumes white residuals; after
filtering and decimation they are not, and its sigma comes out too small: coverage below).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from jointbench.identification.output_values import ZERO_TRUTH

NOMINAL_2SIGMA = 0.9545  # P(|z| <= 2) for a standard normal z


def wilson_interval(successes: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (95 % by default); (nan, nan) if n = 0."""
    if n <= 0:
        return (math.nan, math.nan)
    p = successes / n
    den = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return (max(0.0, centre - half), min(1.0, centre + half))


@dataclass(frozen=True)
class Coverage:
    """Calibration of one kind of reported sigma: `n` runs with a finite sigma, the mean
    sigma (absolute and % of truth), the fraction inside +-k sigma and its 95 % interval, and
    the ratio empirical std / RMS sigma (1 when calibrated)."""

    n: int
    sigma_mean: float
    sigma_mean_pct: float
    coverage: float
    interval: tuple[float, float]
    std_over_sigma: float

    def as_dict(self) -> dict:
        return {"n": self.n, "sigma_mean": self.sigma_mean, "sigma_mean_pct": self.sigma_mean_pct,
                "coverage": self.coverage, "coverage_ci95": list(self.interval),
                "std_over_sigma": self.std_over_sigma}


@dataclass(frozen=True)
class ParameterStats:
    """Monte Carlo statistics of one parameter over the runs that estimated it."""

    name: str
    n: int
    truth_mean: float
    bias: float
    bias_pct: float
    std: float
    std_pct: float
    rmse_pct: float
    k: float
    coverage: dict[str, Coverage] = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {"name": self.name, "n": self.n, "truth_mean": self.truth_mean, "bias": self.bias,
                "bias_pct": self.bias_pct, "std": self.std, "std_pct": self.std_pct,
                "rmse_pct": self.rmse_pct, "k": self.k,
                "coverage": {kind: c.as_dict() for kind, c in self.coverage.items()}}


def coverage(errors: np.ndarray, sigma: np.ndarray, k: float = 2.0,
             truth: np.ndarray | None = None) -> Coverage:
    """Coverage of |e| <= k sigma over the entries where e and sigma are finite."""
    e = np.asarray(errors, dtype=float)
    s = np.asarray(sigma, dtype=float)
    ok = np.isfinite(e) & np.isfinite(s)
    n = int(ok.sum())
    if n == 0:
        return Coverage(0, math.nan, math.nan, math.nan, (math.nan, math.nan), math.nan)
    inside = int(np.sum(np.abs(e[ok]) <= k * s[ok]))
    rms_sigma = float(np.sqrt(np.mean(s[ok] ** 2)))
    std = float(np.std(e[ok], ddof=1)) if n > 1 else math.nan
    t = np.abs(np.asarray(truth, dtype=float)[ok]) if truth is not None else np.zeros(0)
    nonzero = t > ZERO_TRUTH
    pct = float(np.mean(100.0 * s[ok][nonzero] / t[nonzero])) if nonzero.any() else math.nan
    return Coverage(n=n, sigma_mean=float(np.mean(s[ok])), sigma_mean_pct=pct,
                    coverage=inside / n, interval=wilson_interval(inside, n),
                    std_over_sigma=std / rms_sigma if rms_sigma > 0 else math.nan)


def parameter_stats(name: str, estimate: np.ndarray, truth: np.ndarray,
                    sigmas: dict[str, np.ndarray] | None = None, k: float = 2.0
                    ) -> ParameterStats:
    """Bias, spread and, for each kind of reported sigma in `sigmas`, its coverage."""
    x = np.asarray(estimate, dtype=float)
    t = np.asarray(truth, dtype=float)
    if x.shape != t.shape:
        raise ValueError(f"{name}: {x.shape} estimates but {t.shape} truths")
    ok = np.isfinite(x) & np.isfinite(t)
    n = int(ok.sum())
    e = np.where(ok, x - t, np.nan)
    if n == 0:
        nan = math.nan
        return ParameterStats(name, 0, nan, nan, nan, nan, nan, nan, k,
                              {kind: coverage(e, s, k) for kind, s in (sigmas or {}).items()})
    # In % of the truth only where the truth is not zero (a vertical axis' MX, MY): the
    # rest would be inf and nan, and numpy's warnings.
    nonzero = np.abs(t[ok]) > ZERO_TRUTH
    rel = 100.0 * e[ok][nonzero] / np.abs(t[ok][nonzero])
    std = float(np.std(e[ok], ddof=1)) if n > 1 else math.nan
    std_pct = float(np.std(rel, ddof=1)) if len(rel) > 1 else math.nan
    mean_pct = float(np.mean(rel)) if len(rel) else math.nan
    rmse_pct = float(np.sqrt(np.mean(rel ** 2))) if len(rel) else math.nan
    cov = {kind: coverage(e, np.asarray(s, dtype=float), k, t)
           for kind, s in (sigmas or {}).items()}
    return ParameterStats(name=name, n=n, truth_mean=float(np.mean(t[ok])),
                          bias=float(np.mean(e[ok])), bias_pct=mean_pct,
                          std=std, std_pct=std_pct, rmse_pct=rmse_pct,
                          k=k, coverage=cov)


def _pct(x: float, width: int, digits: int) -> str:
    """A fixed-point cell, '-' when not finite (no runs, one run's std, a zero truth)."""
    return f"{x:>{width}.{digits}f}" if math.isfinite(x) else f"{'-':>{width}}"


def stats_table(stats: list[ParameterStats], kinds: tuple[str, ...]) -> str:
    """A fixed-width table: one line per parameter, bias and spread in % of truth, then per
    kind of sigma its mean (% of truth), std / sigma and the +-k sigma coverage with its 95 %
    interval."""
    head = f"{'param':<6} {'n':>4} {'bias %':>8} {'std %':>7}"
    for kind in kinds:
        head += f" | {kind + ' %':>10} {'std/sig':>7} {'cover':>6} {'95 % CI':>13}"
    lines = [head, "-" * len(head)]
    for s in stats:
        zero = s.n > 0 and math.isnan(s.bias_pct)  # truth 0: no % of it; absolute below
        line = f"{s.name:<6} {s.n:>4} " + (f"{'truth 0':>16}" if zero else
                                           f"{_pct(s.bias_pct, 8, 3)} {_pct(s.std_pct, 7, 3)}")
        for kind in kinds:
            c = s.coverage.get(kind)
            if c is None or c.n == 0:
                line += f" | {'-':>10} {'-':>7} {'-':>6} {'-':>13}"
            else:
                ci = f"{100 * c.interval[0]:.1f}-{100 * c.interval[1]:.1f}"
                line += (f" | {_pct(c.sigma_mean_pct, 10, 4)} {_pct(c.std_over_sigma, 7, 2)} "
                         f"{100 * c.coverage:>5.1f}% {ci:>13}")
        if zero:
            line += f"  (absolute: bias {s.bias:+.4g}, std {s.std:.4g})"
        lines.append(line)
    return "\n".join(lines)
