"""`diagnose` over several runs of one axis (`jointbench diagnose A.csv B.csv ...`,
`jointbench.diagnose([a, b])`): each run diagnosed and its models cross-validated on the next
run (one it did not fit); a cause is named for the axis only where every run names it and
no run's extended model predicts the run it did not fit worse than its nominal.

A cause one run names and another does not is a property of that run (its excitation, a
transient) or too weak for the other's noise: the runs do not support it, and the answer
lists it apart with the runs that named it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from jointbench.bench.results.diagnose import DiagnosisResult
from jointbench.identification.output_values import finite_json


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

    def confirms(self) -> tuple[bool | None, ...]:
        """Per run: does its extended model predict the run it did not fit better than its
        nominal does?

        Returns
        -------
        tuple of bool or None
            True when the extended model's error on the other run is smaller in the inverse
            view (the RMS over its equations of the relative errors) and, where both
            replayed, in the forward view's torque; None without an extended model or a
            cross-validation.
        """
        out: list[bool | None] = []
        for r in self.results:
            xv = getattr(r, "cross_validation", None) or {}
            inv = xv.get("inverse", {})
            if "extended" not in inv or "nominal" not in inv:
                out.append(None)
                continue
            better = _rms(inv["extended"]) < _rms(inv["nominal"])
            fwd = xv.get("forward", {})
            if "extended" in fwd and "nominal" in fwd:
                better = better and fwd["extended"]["tau_rel_pct"] < fwd["nominal"]["tau_rel_pct"]
            out.append(bool(better))
        return tuple(out)

    @property
    def supported(self) -> tuple[str, ...]:
        """The causes every run names, in the first run's order, when no run's extended
        model predicts the run it did not fit worse than its nominal (`confirms`)."""
        per_run = self._causes()
        if any(c is False for c in self.confirms()):
            return ()
        return tuple(c for c in per_run[0] if all(c in other for other in per_run[1:]))

    @property
    def unsupported(self) -> dict[str, tuple[str, ...]]:
        """Causes some runs name and the runs do not support (named on some runs only, or
        an extended model the cross-validation does not confirm): cause -> the runs that
        name it."""
        per_run = self._causes()
        named = {c for causes in per_run for c in causes}
        return {c: tuple(nm for nm, causes in zip(self.names, per_run) if c in causes)
                for c in sorted(named) if c not in self.supported}

    def evidence(self) -> dict[str, list[dict]]:
        """Each run's own test of every cause any run names.

        Returns
        -------
        dict of str to list of dict
            cause -> per run {"run", "named", "t", "heldout_pct", "p_heldout",
            "parameters"}: where the run names the cause, its named cause's held-out test
            (its own round), else its first-round candidate's; None where the run could not
            test it.
        """
        docs = [r.to_json() for r in self.results]
        out: dict[str, list[dict]] = {}
        for c in sorted({e for causes in self._causes() for e in causes}):
            rows = []
            for nm, doc in zip(self.names, docs):
                named = [x for x in doc.get("causes", []) if x.get("effect") == c]
                cand = [x for x in doc.get("candidates", []) if x.get("effect") == c]
                src = named[0] if named else cand[0] if cand else {}
                rows.append({"run": nm, "named": bool(named), "t": src.get("t"),
                             "heldout_pct": src.get("heldout_pct"),
                             "p_heldout": src.get("p_heldout"),
                             "parameters": src.get("parameters", {})})
            out[c] = rows
        return out

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
            lines.append(f"not supported: {c}, named on {', '.join(runs)}"
                         + ("" if len(runs) == len(self.names) else " only"))
        for nm, other, ok in zip(self.names, self.names[1:] + self.names[:1], self.confirms()):
            if ok is not None:
                lines.append(f"cross-validation: the extended model of {nm} predicts {other} "
                             + ("better" if ok else "NOT better") + " than its nominal")
        for c, rows in self.evidence().items():
            lines.append(f"{c}, each run's own test: " + "; ".join(
                f"{r['run']}: {'named' if r['named'] else 'not named'}"
                + (f", t = {r['t']:.3g}" if r["t"] is not None else ", not tested")
                for r in rows))
        return "\n\n".join(parts) + "\n\n" + "\n".join(lines)

    def to_json(self) -> dict:
        """The `diagnose A.csv B.csv --json` object.

        Returns
        -------
        dict
            {"runs": [{"name", each run's diagnose JSON}], "supported": [...],
            "unsupported": {cause: [runs]}, "evidence": {cause: [per run: "run", "named",
            "t", "heldout_pct", "p_heldout", "parameters"]}, "cross_validated": [per run:
            "run", "on", "confirms"]} (docs/schemas/diagnose_runs.schema.json).
        """
        return finite_json(
            {"runs": [{"name": nm, **r.to_json()} for nm, r in zip(self.names, self.results)],
             "supported": list(self.supported),
             "unsupported": {c: list(r) for c, r in self.unsupported.items()},
             "evidence": self.evidence(),
             "cross_validated": [{"run": nm, "on": other, "confirms": ok} for nm, other, ok
                                 in zip(self.names, self.names[1:] + self.names[:1],
                                        self.confirms())]})


def _rms(errors: dict) -> float:
    """The RMS of a view's relative errors over its equations (motor, link)."""
    return math.sqrt(sum(v ** 2 for v in errors.values()) / len(errors))
