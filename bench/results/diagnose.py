"""A diagnosis' result (`jointbench.diagnose`): DiagnosisResult, whose `table()`,
`to_json()` and `write()` are what `jointbench diagnose` prints and writes."""

from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from jointbench.bench.analysis.diagnose import Diagnosis, summary_text
from jointbench.bench.analysis.diagnose import write as write_diagnosis
from jointbench.bench.api_args import path_like
from jointbench.identification.output_values import finite_json

if TYPE_CHECKING:
    from jointbench.bench.analysis.diagnose.against_model import ModelDiagnosis


def _cross_validation_text(source: str, validate_source: str, xval: dict) -> str:
    """The cross-validation errors, one line per view and model."""
    lines = [f"\ncross-validation on {validate_source} (models identified and extended on "
             f"{source}, unchanged):"]
    for view, rows in xval.items():
        if isinstance(rows, str):      # a note: why a view did not run
            lines.append(f"  {view.replace('_', ' ')}: {rows}")
            continue
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
        return self.diagnosis.named_cause

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
        path_like("out", out)
        say = progress or (lambda msg: None)
        if self.against_model:
            from jointbench.bench.analysis.diagnose.model_report import write
            return dataclasses.replace(self, diagnosis=write(self.diagnosis, Path(out), say))
        extra = {} if self.cross_validation is None else {"cross_validation.json": json.dumps(
            finite_json({"file": str(self.validate_source), **self.cross_validation}),
            indent=2, allow_nan=False) + "\n"}
        done = write_diagnosis(self.diagnosis, Path(out), say, extra)
        return dataclasses.replace(self, diagnosis=done)
