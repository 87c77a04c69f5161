"""Several runs of one axis identified together (`jointbench identify A.csv B.csv ...`,
`jointbench.identify([logA, logB])`): each run's fit, the run-to-run spread beside each run's
sigma, and the pooled estimate.

Pooling, per parameter, over the n runs' values x_i with standard deviations s_i (the
autocorrelation-consistent sigma_hac where computed, else the white-residual sigma):

    w_i = 1 / s_i^2,   x = sum w_i x_i / sum w_i,   s_int = 1 / sqrt(sum w_i)
    R   = sqrt(sum w_i (x_i - x)^2 / (n - 1))                (Birge ratio)
    s   = s_int max(1, R)

R compares the runs' scatter with their own sigmas: R near 1, the runs agree within them; R
well over 1, something varies between runs that no single run's sigma holds (remounting,
temperature, wear, the excitation), and the pooled sigma grows with it, to about the
run-to-run standard deviation / sqrt(n) for equal sigmas: it covers the spread. A run whose
value lies more than OUTLIER_Z of its own sigma from the runs' median is named: its sigma is
a lower bound for the hardware.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from jointbench.bench.results.identify import LOWER_BOUND, Fit

OUTLIER_Z = 3.0     # a run this many of its own sigmas from the runs' median is named
REPORTED = ("K", "Jm", "JL", "J", "FVm", "FSm", "FV", "FS")   # the table's order


@dataclass(frozen=True)
class Pooled:
    """One parameter over the runs: `value` and `sigma` pooled (module docstring),
    `sigma_internal` (from the runs' sigmas alone), `birge` R, `spread` the runs' standard
    deviation (ddof 1; NaN for one run), `run_sigma` the median of the runs' sigmas, `unit`,
    `outliers` the names of the runs more than OUTLIER_Z of their own sigma from the median."""

    value: float
    sigma: float
    sigma_internal: float
    birge: float
    spread: float
    run_sigma: float
    unit: str
    outliers: tuple[str, ...] = ()


def _sigma(e) -> float:
    return e.sigma_hac if math.isfinite(e.sigma_hac) and e.sigma_hac > 0 else e.sigma


def pool(values: list[float], sigmas: list[float], names: list[str], unit: str = "") -> Pooled:
    """The pooled estimate of one parameter (module docstring). ValueError for no run or a
    sigma that is not positive and finite."""
    x, s = np.asarray(values, float), np.asarray(sigmas, float)
    if len(x) == 0:
        raise ValueError("pool needs at least one run")
    if not np.all(np.isfinite(s) & (s > 0)):
        raise ValueError(f"every run needs a positive finite sigma, got {list(s)}")
    w = 1.0 / s ** 2
    mean = float(np.sum(w * x) / np.sum(w))
    internal = float(1.0 / math.sqrt(np.sum(w)))
    n = len(x)
    birge = float(math.sqrt(np.sum(w * (x - mean) ** 2) / (n - 1))) if n > 1 else math.nan
    sigma = internal * max(1.0, birge) if n > 1 else internal
    median = float(np.median(x))
    outliers = tuple(nm for nm, xi, si in zip(names, x, s) if abs(xi - median) > OUTLIER_Z * si)
    return Pooled(mean, sigma, internal, birge, float(np.std(x, ddof=1)) if n > 1 else math.nan,
                  float(np.median(s)), unit, outliers if n > 1 else ())


@dataclass(frozen=True)
class RunsFit:
    """Several runs of one axis identified together (`jointbench identify A.csv B.csv`).

    Parameters
    ----------
    fits : tuple of Fit
        Each run's identification, in the order given.
    names : tuple of str
        The runs' names (their file names, numbered when two are equal).
    pooled : dict of str to Pooled
        Per parameter every run identified: the pooled value and sigma, the Birge ratio,
        the run-to-run standard deviation and the runs set apart (module docstring).
    """

    fits: tuple[Fit, ...]
    names: tuple[str, ...]
    pooled: dict[str, Pooled]

    @classmethod
    def of(cls, fits: list[Fit], names: list[str]) -> "RunsFit":
        """Pool the runs' fits.

        Parameters
        ----------
        fits : list of Fit
            Each run's identification.
        names : list of str
            Their names.

        Returns
        -------
        RunsFit
            The runs and, per parameter with a finite positive sigma in every run, the
            pooled estimate.
        """
        common = [k for k in fits[0].parameters if all(k in f.parameters for f in fits)]
        pooled = {}
        for k in common:
            est = [f.parameters[k] for f in fits]
            sig = [_sigma(e) for e in est]
            if all(math.isfinite(v) and v > 0 for v in sig):
                pooled[k] = pool([e.value for e in est], sig, names, est[0].unit)
        return cls(tuple(fits), tuple(names), pooled)

    @property
    def notes(self) -> tuple[str, ...]:
        """What the pooled table says in words: the runs whose sigma is a lower bound."""
        out = []
        for k, p in self.pooled.items():
            if p.outliers:
                out.append(f"{k}: run(s) {', '.join(p.outliers)} lie more than {OUTLIER_Z:g} "
                           f"of their own sigma from the runs' median: a run's sigma is a "
                           f"lower bound for the hardware (run-to-run spread {p.spread:.4g}, "
                           f"{p.spread / p.run_sigma:.2g} times a run's sigma)")
        if len(self.fits) == 1:
            out.append(LOWER_BOUND)
        return tuple(out)

    def table(self) -> str:
        """The text `jointbench identify A.csv B.csv ...` prints.

        Returns
        -------
        str
            Each run's table, then the runs side by side and the pooled estimate.
        """
        parts = [f"== run {nm} ==\n{f.table(one_run=False)}"
                 for nm, f in zip(self.names, self.fits)]
        keys = [k for k in REPORTED if k in self.pooled] + \
            [k for k in self.pooled if k not in REPORTED]
        head = ["parameter"] + list(self.names) + ["run sigma", "run-to-run sd", "ratio",
                                                   "pooled", "pooled sigma", "Birge R", "unit"]
        rows = []
        for k in keys:
            p = self.pooled[k]
            vals = [f"{f.parameters[k].value:.6g}" for f in self.fits]
            rows.append([k] + vals + [f"{p.run_sigma:.3g}", f"{p.spread:.3g}",
                                      f"{p.spread / p.run_sigma:.2g}", f"{p.value:.6g}",
                                      f"{p.sigma:.3g}", f"{p.birge:.2g}", p.unit])
        widths = [max(len(str(r[i])) for r in [head] + rows) for i in range(len(head))]
        line = lambda r: "  ".join(str(c).rjust(w) for c, w in zip(r, widths))  # noqa: E731
        pooled = [f"== {len(self.fits)} runs of one axis, pooled (inverse-variance mean, sigma "
                  "widened by the Birge ratio R when the runs scatter beyond their own sigmas) "
                  "==", line(head), "-" * len(line(head))] + [line(r) for r in rows]
        pooled += [f"note: {n}" for n in self.notes]
        return "\n\n".join(parts) + "\n\n" + "\n".join(pooled)

    def to_json(self) -> dict:
        """The `identify A.csv B.csv --json` object.

        Returns
        -------
        dict
            {"runs": [{"name", each run's identify JSON}], "pooled": {parameter: {...}},
            "notes": [...]} (NaN as null).
        """
        from jointbench.identification.output_values import finite_json

        return finite_json({
            "runs": [{"name": nm, **f.to_json()} for nm, f in zip(self.names, self.fits)],
            "pooled": {k: {"value": p.value, "sigma": p.sigma,
                           "sigma_internal": p.sigma_internal, "birge_ratio": p.birge,
                           "run_to_run_sd": p.spread, "run_sigma_median": p.run_sigma,
                           "unit": p.unit, "outliers": list(p.outliers)}
                       for k, p in self.pooled.items()},
            "notes": list(self.notes)})
