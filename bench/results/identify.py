"""An identification's result (`jointbench.identify`): Estimate per physical parameter and
Fit, whose `table()` and `to_json()` are what `jointbench identify` prints."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

from jointbench.bench.analysis.debias import DebiasResult
from jointbench.bench.api_args import output_path
from jointbench.bench.analysis.refine import RefineResult
from jointbench.bench.present.identify import identify_json, identify_text
from jointbench.bench.present.cross_validation import forward_text
from jointbench.identification.identify import Identification
from jointbench.identification.log import Log
from jointbench.identification.output_values import finite_json
from jointbench.identification.parameters import units
from jointbench.identification.plots import plot_validation
from jointbench.identification.cross_validation import Validation

if TYPE_CHECKING:
    import matplotlib.figure


LOWER_BOUND = ("one run: its sigmas are this run's alone, a lower bound for the hardware (the "
               "run-to-run spread of a real rig, remounting, temperature, wear, is not in them; "
               "identify several runs, `jointbench identify A.csv B.csv ...`, to measure it)")


@dataclass(frozen=True)
class Estimate:
    """One identified physical parameter.

    Parameters
    ----------
    value : float
        The estimate, SI units on the joint side (`unit`).
    sigma : float
        Its standard deviation as the paper computes it, for white residuals:
        sigma^2 = ||rho||^2 / (r - Np) [(W^T W)^-1]_ii (eq. 13's least squares).
    sigma_hac : float
        Its autocorrelation-consistent standard deviation (HAC sandwich, VAR(1)
        prewhitened: identification.uncertainty); NaN when not computed. The filtered,
        decimated residuals are coloured, so this is the one to quote.
    unit : str
        The unit of `value`, e.g. "N m/rad" (revolute) or "N/m" (prismatic).

    Examples
    --------
    >>> e = Estimate(20000.0, 30.0, 45.0, "N m/rad")
    >>> float(e), e.rel_sigma_hac_pct
    (20000.0, 0.225)
    """

    value: float
    sigma: float
    sigma_hac: float
    unit: str

    def __float__(self) -> float:
        return float(self.value)

    @property
    def rel_sigma_hac_pct(self) -> float:
        """100 sigma_hac / |value| (NaN for a zero value)."""
        return 100 * self.sigma_hac / abs(self.value) if self.value else math.nan


@dataclass(frozen=True)
class Fit:
    """An identification of a log, as `jointbench identify` reports it.

    Parameters
    ----------
    log : Log
        The identified log.
    result : Identification
        The estimator's answer (identification.identify).
    truth : dict of str to float or None
        The log's ground truth (None for measured data).
    flags : tuple of dict
        The estimate flags (identification.checks.fit.estimate_flags).
    warnings : tuple of str
        Warnings on the log and the estimate: units, clipped torque, sanity (a mislabelled
        or too short log, a model that explains too little), the band against the first
        mode; the JSON's `warnings`.
    source : str
        The name of the log in the table's first line (the file name as given).
    refined : RefineResult or None
        The closed-loop output-error refinement, when asked (`refine=True`).
    debiased : DebiasResult or None
        The bias correction, when asked (`debias=B`).
    validation : Validation or None
        The identified model on another log (`validate=OTHER`), inverse view.
    forward : dict or None
        The same, forward (closed-loop replay) view; None when either log cannot be replayed.
    validate_source : str or None
        The name of the other log.
    """

    log: Log
    result: Identification
    truth: dict[str, float] | None
    flags: tuple[dict, ...]
    warnings: tuple[str, ...]
    source: str = "log"
    refined: RefineResult | None = None
    debiased: DebiasResult | None = None
    validation: Validation | None = None
    forward: dict | None = None
    validate_source: str | None = None

    @property
    def model(self) -> str:
        """The identification model used (joint-motor, motor-only, rigid, ...)."""
        return self.result.model

    @property
    def parameters(self) -> dict[str, Estimate]:
        """The physical parameters (SI, joint side) with both standard deviations: the JSON's
        `physical`, `physical_sigma` and `physical_sigma_corrected` entries."""
        r = self.result
        unit = units(r.prismatic)
        return {n: Estimate(float(v), float(r.physical_sigma.get(n, math.nan)),
                            float(r.physical_sigma_corrected.get(n, math.nan)), unit.get(n, ""))
                for n, v in r.physical.items()}

    @property
    def notes(self) -> tuple[str, ...]:
        """What the estimator chose and why (band, filter, model fallback)."""
        return tuple(self.result.notes)

    def table(self, *, one_run: bool = True) -> str:
        """The text `jointbench identify` prints.

        Parameters
        ----------
        one_run : bool
            False: a run among several (bench.results.runs), whose table leaves the
            single-run note to the pooled one.

        Returns
        -------
        str
            The filter line, the parameter tables, the direct validation, notes, flags and,
            when run, the refinement, bias-correction and validation reports.
        """
        text = identify_text(self.source, self.log, self.result, self.truth, list(self.flags),
                             self.refined, self.debiased)
        from jointbench.identification.voltage_drive import fvm_note
        if "FVm" in self.result.physical:
            note = fvm_note(float(self.result.physical["FVm"]), self.log.meta)
            if note:
                text += f"\nnote: {note}"
        if one_run and self.truth is None:   # measured data: nothing but this run behind a sigma
            text += f"\nnote: {LOWER_BOUND}"
        if self.validation is not None:
            text += "\n" + self.validation.text(units(self.log.prismatic)["offset"])
            text += "\n" + forward_text(self.forward, self.validate_source)
        return text

    def to_json(self) -> dict:
        """The `identify --json` object (docs/cli.md, docs/schemas/identify.schema.json).

        Returns
        -------
        dict
            Strict JSON (NaN as null).
        """
        answer = identify_json(self.result, self.truth, list(self.flags), list(self.warnings),
                               self.refined, self.debiased)
        if self.validation is not None:
            answer["validation"] = {**self.validation.to_json(), "forward": self.forward}
        return finite_json(answer)

    def plot(self, path: str | os.PathLike | None = None) -> matplotlib.figure.Figure:
        """The direct validation (paper's Figure 2): measured and predicted torque.

        Parameters
        ----------
        path : str or PathLike, optional
            Where to save the figure (atomically); not saved when None.

        Returns
        -------
        matplotlib.figure.Figure
            The figure (pyplot is used: pick the backend first).
        """
        output_path("path", path)
        r = self.result
        rows = r.block == 0
        return plot_validation(r.t[rows], r.y[rows], r.y_pred[rows], r.relative_error_pct,
                               path, title=f"Direct validation, {r.model} model",
                               unit="N" if r.prismatic else "N m")
