"""An import's result (`jointbench.import_log`): ImportReport, whose `table()` and
`to_json()` are what `jointbench import` prints."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from jointbench.identification.log import Log

if TYPE_CHECKING:
    from jointbench.identification.log.raw import ImportResult


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
