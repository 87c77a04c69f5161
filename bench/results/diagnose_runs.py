"""`diagnose` over several runs of one axis (`jointbench diagnose A.csv B.csv ...`,
`jointbench.diagnose([a, b])`): each run diagnosed and its models cross-validated on the next
run (one it did not fit); a cause is named for the axis only where every run names it.

A cause one run names and another does not is a property of that run (its excitation, a
transient) or too weak for the other's noise: the runs do not support it, and the answer
lists it apart with the runs that named it.
"""

from __future__ import annotations

from dataclasses import dataclass

from jointbench.bench.results.diagnose import DiagnosisResult


@dataclass(frozen=True)
class RunsDiagnosis:
    """Several runs of one axis diagnosed together.

    Parameters
    ----------
    results : tuple of DiagnosisResult
        Each run's diagnosis, its models cross-validated on the next run (the last on the
        first).
    names : tuple of str
        The runs' names.
    """

    results: tuple[DiagnosisResult, ...]
    names: tuple[str, ...]

    def _causes(self) -> list[tuple[str, ...]]:
        return [tuple(c.effect for c in getattr(r.diagnosis, "causes", ()))
                for r in self.results]

    @property
    def supported(self) -> tuple[str, ...]:
        """The causes every run names, in the first run's order."""
        per_run = self._causes()
        return tuple(c for c in per_run[0] if all(c in other for other in per_run[1:]))

    @property
    def unsupported(self) -> dict[str, tuple[str, ...]]:
        """Causes some runs name and others do not: cause -> the runs that name it."""
        per_run = self._causes()
        named = {c for causes in per_run for c in causes}
        return {c: tuple(nm for nm, causes in zip(self.names, per_run) if c in causes)
                for c in sorted(named) if c not in self.supported}

    def table(self) -> str:
        """The text `jointbench diagnose A.csv B.csv ...` prints.

        Returns
        -------
        str
            Each run's summary and cross-validation, then the causes the runs support.
        """
        parts = [f"== run {nm} ==\n{r.table()}" for nm, r in zip(self.names, self.results)]
        lines = [f"== {len(self.results)} runs of one axis ==",
                 "named on every run (supported): " + (", ".join(self.supported) or "none")]
        for c, runs in self.unsupported.items():
            lines.append(f"not supported: {c}, named on {', '.join(runs)} only")
        return "\n\n".join(parts) + "\n\n" + "\n".join(lines)

    def to_json(self) -> dict:
        """The `diagnose A.csv B.csv --json` object.

        Returns
        -------
        dict
            {"runs": [{"name", each run's diagnose JSON}], "supported": [...],
            "unsupported": {cause: [runs]}}.
        """
        return {"runs": [{"name": nm, **r.to_json()} for nm, r in zip(self.names, self.results)],
                "supported": list(self.supported),
                "unsupported": {c: list(r) for c, r in self.unsupported.items()}}
