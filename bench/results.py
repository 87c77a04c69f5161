"""The results of the public API (`bench.api`): frozen dataclasses whose `table()` is the text
and whose `to_json()` is the `--json` object the matching `jointbench` command prints
(docs/cli.md, docs/schemas/). The command line builds the same objects and prints these.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from jointbench.bench.analysis.debias import DebiasResult
from jointbench.bench.analysis.diagnose import Diagnosis, summary_text
from jointbench.bench.analysis.diagnose import write as write_diagnosis
from jointbench.bench.analysis.refine import RefineResult
from jointbench.bench.campaign.gates import GateResult, gates_text
from jointbench.bench.campaign.summary import summary_text as campaign_text
from jointbench.bench.present.identify import identify_json, identify_text
from jointbench.bench.present.validate import forward_text
from jointbench.identification.identify import Identification
from jointbench.identification.log import Log
from jointbench.identification.output import finite_json
from jointbench.identification.parameters import units
from jointbench.identification.plots import plot_validation
from jointbench.identification.validate import Validation

if TYPE_CHECKING:
    import matplotlib.figure

    from jointbench.bench.analysis.diagnose.against_model import ModelDiagnosis
    from jointbench.bench.campaign.survey import Survey
    from jointbench.identification.log_import import ImportResult

__all__ = ["Estimate", "Fit", "DiagnosisResult", "CampaignReport", "SurveyResult",
           "ImportReport"]


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
        The estimate flags (identification.checks.estimate_flags).
    warnings : tuple of str
        Warnings on the log and the estimate: units, clipped torque, sanity (a mislabelled
        or too short log, a model that explains too little).
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

    def table(self) -> str:
        """The text `jointbench identify` prints.

        Returns
        -------
        str
            The filter line, the parameter tables, the direct validation, notes, flags and,
            when run, the refinement, bias-correction and validation reports.
        """
        text = identify_text(self.source, self.log, self.result, self.truth, list(self.flags),
                             self.refined, self.debiased)
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
        r = self.result
        rows = r.block == 0
        return plot_validation(r.t[rows], r.y[rows], r.y_pred[rows], r.relative_error_pct,
                               path, title=f"Direct validation, {r.model} model",
                               unit="N" if r.prismatic else "N m")


def _cross_validation_text(source: str, validate_source: str, xval: dict) -> str:
    """The cross-validation errors, one line per view and model."""
    lines = [f"\ncross-validation on {validate_source} (models identified and extended on "
             f"{source}, unchanged):"]
    for view, rows in xval.items():
        for label, vals in rows.items():
            lines.append(f"  {view:8s} {label:9s} " + ", ".join(
                f"{k} {v:.4g}" for k, v in vals.items()))
    return "\n".join(lines)


@dataclass(frozen=True)
class DiagnosisResult:
    """What the simulation gets wrong on a log, as `jointbench diagnose` reports it.

    Parameters
    ----------
    diagnosis : Diagnosis or ModelDiagnosis
        Everything the analysis found: against the log's own nominal model (Diagnosis), or
        against the user's MJCF (ModelDiagnosis, `diagnose(..., model=ROBOT.xml)`).
    cross_validation : dict or None
        The nominal and extended models on another log (`validate=OTHER`), per view.
    source : str
        The name of the diagnosed log.
    validate_source : str or None
        The name of the other log.
    """

    diagnosis: Diagnosis | ModelDiagnosis
    cross_validation: dict | None = None
    source: str = "log"
    validate_source: str | None = None

    @property
    def against_model(self) -> bool:
        """True for a diagnosis against the user's MJCF."""
        return not isinstance(self.diagnosis, Diagnosis)

    @property
    def named_cause(self) -> str:
        """The effect named as the cause ("none" when the nominal model explains the log)."""
        d = self.diagnosis
        return d.named_cause if isinstance(d, Diagnosis) else ", ".join(d.named_causes) or "none"

    @property
    def files(self) -> tuple[str, ...]:
        """The files written (empty before `write`)."""
        return self.diagnosis.files

    @property
    def warnings(self) -> tuple[str, ...]:
        """Warnings on the log (units, clipped torque left out of the fits)."""
        return tuple(getattr(self.diagnosis, "warnings", ()))

    def table(self) -> str:
        """The text `jointbench diagnose` prints.

        Returns
        -------
        str
            The ranking, the named cause and the gain (or the parameter errors against the
            model), then the cross-validation when run.
        """
        if self.against_model:
            from jointbench.bench.analysis.diagnose.model_report import summary_text as text
            return text(self.diagnosis)
        text = summary_text(self.diagnosis)
        if self.cross_validation is not None:
            text += "\n" + _cross_validation_text(self.source, str(self.validate_source),
                                                  self.cross_validation)
        return text

    def to_json(self) -> dict:
        """The `diagnose --json` object (docs/cli.md, docs/schemas/diagnose.schema.json).

        Returns
        -------
        dict
            Strict JSON (NaN as null).
        """
        if self.against_model:
            from jointbench.bench.analysis.diagnose.model_report import to_json
            return finite_json(to_json(self.diagnosis))
        doc = self.diagnosis.to_json()
        if self.cross_validation is not None:
            doc["cross_validation"] = {"file": str(self.validate_source),
                                       **self.cross_validation}
        return finite_json(doc)

    def write(self, out: str | os.PathLike,
              progress: Callable[[str], None] | None = None) -> DiagnosisResult:
        """Write figures, report.md, diagnosis.json and the models into a folder.

        Parameters
        ----------
        out : str or PathLike
            The folder (created; all or nothing; a file jointbench did not write is never
            replaced).
        progress : callable, optional
            Called with one line of progress per step.

        Returns
        -------
        DiagnosisResult
            The same result with the files written in `files`.
        """
        say = progress or (lambda msg: None)
        if self.against_model:
            from jointbench.bench.analysis.diagnose.model_report import write
            return dataclasses.replace(self, diagnosis=write(self.diagnosis, Path(out), say))
        import json
        extra = {} if self.cross_validation is None else {"cross_validation.json": json.dumps(
            finite_json({"file": str(self.validate_source), **self.cross_validation}),
            indent=2, allow_nan=False) + "\n"}
        done = write_diagnosis(self.diagnosis, Path(out), say, extra)
        return dataclasses.replace(self, diagnosis=done)


@dataclass(frozen=True)
class CampaignReport:
    """A finished campaign, as `jointbench campaign` reports it.

    Parameters
    ----------
    summary : dict
        The `campaign --json` object: Monte Carlo statistics per model, `comparison` of
        every method side by side, `gates`, `table`, `timing`.
    rows : tuple of dict
        The table's rows (one per run).
    gates : tuple of GateResult
        The accuracy gates checked.
    table_path : str or None
        The CSV table (None: not kept).
    wall_s : float
        Wall time of this invocation [s].
    times : dict
        Run -> method -> wall time of the call [s].
    """

    summary: dict
    rows: tuple[dict[str, str], ...]
    gates: tuple[GateResult, ...]
    table_path: str | None
    wall_s: float
    times: dict[int, dict[str, float]] = dataclasses.field(default_factory=dict)

    @property
    def passed(self) -> bool:
        """Every gate passed (True without gates)."""
        return all(g.passed for g in self.gates)

    @property
    def failed_gates(self) -> tuple[GateResult, ...]:
        """The gates that failed."""
        return tuple(g for g in self.gates if not g.passed)

    @property
    def comparison(self) -> list[dict]:
        """Per sweep point, every method's counts, time and per-parameter statistics."""
        return self.summary["comparison"]

    def table(self) -> str:
        """The statistics and gates `jointbench campaign` prints after its timing line.

        Returns
        -------
        str
            The statistics (methods side by side when plug-ins ran or gates were asked),
            then the gates.
        """
        text = campaign_text(self.summary, True if self.gates else None)
        return text + ("\n\n" + gates_text(list(self.gates)) if self.gates else "")

    def timing_line(self) -> str:
        """One line: runs done, wall time, engine, throughput and per-run costs when measured.

        Returns
        -------
        str
            The line `jointbench campaign` prints before the statistics.
        """
        t = self.summary["timing"]
        return (f"{t['runs_this_invocation']} runs in {t['wall_s']:.1f} s on {t['engine']}"
                + (f" ({t['runs_per_s']:.2f} runs/s; per run: simulation "
                   f"{t['mean_simulation_s']:.3f} s, identification "
                   f"{1e3 * t['mean_identification_s']:.1f} ms, all models)"
                   if t["runs_per_s"] and t["mean_simulation_s"]
                   and t["mean_identification_s"] else "")
                + (f"; {t['resumed_rows']} rows resumed from the table"
                   if t["resumed_rows"] else ""))

    def to_json(self) -> dict:
        """The `campaign --json` object (docs/cli.md, docs/schemas/campaign.schema.json).

        Returns
        -------
        dict
            Strict JSON (NaN as null).
        """
        return finite_json(self.summary)


@dataclass(frozen=True)
class SurveyResult:
    """Every axis of a robot identified in turn, as `jointbench survey` reports it.

    Parameters
    ----------
    survey : Survey
        Per axis: the estimates against the truth, the filter, the first mode, the log.
    out : Path or None
        The folder written (survey.csv, survey.png, logs/); None when not written.
    """

    survey: Survey
    out: Path | None = None

    @property
    def failed(self) -> tuple:
        """The axes that failed (each with its reason)."""
        return tuple(self.survey.failed)

    def table(self) -> str:
        """The text `jointbench survey` prints.

        Returns
        -------
        str
            One table of every axis against the truth.
        """
        from jointbench.bench.present.survey import survey_text
        return survey_text(self.survey, self.out)

    def to_json(self) -> dict:
        """The `survey --json` object (docs/cli.md, docs/schemas/survey.schema.json).

        Returns
        -------
        dict
            Strict JSON (NaN as null).
        """
        from jointbench.bench.present.survey import survey_json
        return survey_json(self.survey, self.out)


@dataclass(frozen=True)
class ImportReport:
    """A measured file converted into a log, as `jointbench import` reports it.

    Parameters
    ----------
    result : ImportResult
        The converted log, the steps done, the checks run, the warnings.
    out : Path or None
        The log file written (None: not written).
    """

    result: ImportResult
    out: Path | None = None

    @property
    def log(self) -> Log:
        """The converted log."""
        return self.result.log

    @property
    def warnings(self) -> tuple[str, ...]:
        """What the conversion warns about (not errors)."""
        return tuple(self.result.warnings)

    def table(self) -> str:
        """The text `jointbench import` prints.

        Returns
        -------
        str
            The conversion steps, the checks and what was written.
        """
        log, r = self.result.log, self.result
        return "\n".join(["conversion:", *(f"  {s}" for s in r.steps), "checks:",
                          *(f"  {c}" for c in r.checks),
                          f"wrote {self.out}: {len(log)} samples over {log.t[-1]:.4g} s at "
                          f"{log.sample_rate_hz:.6g} Hz, columns {', '.join(log.columns())}"])

    def to_json(self) -> dict:
        """The `import --json` object (docs/schemas/import.schema.json).

        Returns
        -------
        dict
            The file written, samples, rate, duration, columns, metadata, steps, checks and
            warnings.
        """
        log, r = self.result.log, self.result
        return {"out": str(self.out), "samples": len(log), "rate_hz": log.sample_rate_hz,
                "duration_s": float(log.t[-1]), "columns": list(log.columns()),
                "meta": log.meta, "steps": list(r.steps), "checks": list(r.checks),
                "warnings": list(r.warnings)}
