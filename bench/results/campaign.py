"""A campaign's result (`jointbench.campaign`): CampaignReport, whose `table()` and
`to_json()` are what `jointbench campaign` prints."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from jointbench.bench.campaign.gates import GateResult, gates_text
from jointbench.bench.campaign.summary import summary_text as campaign_text
from jointbench.identification.output_values import finite_json


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
