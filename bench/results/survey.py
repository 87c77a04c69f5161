"""A survey's result (`jointbench.survey`): SurveyResult, whose `table()` and `to_json()`
are what `jointbench survey` prints."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from jointbench.bench.campaign.robot_survey import Survey


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
