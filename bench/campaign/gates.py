"""Accuracy gates: `campaign --require "K.abs_bias_pct<0.5, Jm.coverage_pct>=90, failed==0"`.

Grammar (docs/cli.md, section 3.7):

    REQUIRE  := GATE ("," GATE)*            --require may be given several times
    GATE     := [METHOD ":"] QUANTITY OP NUMBER
    QUANTITY := PARAM "." STAT | "ok" | "failed" | "time_s"
    STAT     := n | bias_pct | abs_bias_pct | std_pct | rmse_pct | sigma_pct | coverage_pct
    OP       := < | <= | > | >= | == | !=

METHOD is a built-in model of the campaign (joint-motor, motor-only, motor-only-printed; with
--debias also joint-motor+bc, motor-only+bc) or the label of a --method. Without it a gate
holds for every method: a PARAM gate for every method that estimated PARAM (a built-in that
should have and did not fails it), `ok`, `failed` and `time_s` for all. With a sweep, every
sweep point is checked. A gate whose value is missing (no estimate, no timed run) fails.
Statistics are bench.campaign.compare's: bias_pct signed (abs_bias_pct its magnitude), in % of
the truth; coverage_pct of +-2 sigma with the method's own sigma; time_s the mean wall time per
answered log (bench.campaign.times)."""

from __future__ import annotations

import math
import operator
import re
from dataclasses import dataclass

from jointbench.bench.campaign.compare import METHOD_STATS, STATS, Entry
from jointbench.bench.campaign.methods import SCORED
from jointbench.bench.campaign.settings import CampaignError

OPS = {"<=": operator.le, ">=": operator.ge, "==": operator.eq, "!=": operator.ne,
       "<": operator.lt, ">": operator.gt}
_GATE = re.compile(r"\s*(?:(?P<method>[A-Za-z][\w+-]*)\s*:)?\s*(?P<quantity>[A-Za-z][\w.]*)"
                   r"\s*(?P<op><=|>=|==|!=|<|>)\s*(?P<number>[^\s<>=!]+)\s*\Z")


@dataclass(frozen=True)
class Gate:
    """One requirement: `method` (None: every method), `param` (None for ok, failed, time_s),
    `stat`, `op`, `threshold`."""

    method: str | None
    param: str | None
    stat: str
    op: str
    threshold: float

    @property
    def quantity(self) -> str:
        return f"{self.param}.{self.stat}" if self.param else self.stat

    def __str__(self) -> str:
        return (f"{self.method}:" if self.method else "") + \
            f"{self.quantity}{self.op}{self.threshold:g}"


@dataclass(frozen=True)
class GateResult:
    """A gate checked on one method (and sweep point): the value measured, pass or fail."""

    gate: Gate
    method: str
    where: str           # "" or the sweep point, e.g. "amplitude=0.1"
    measured: float | None
    passed: bool

    @property
    def name(self) -> str:
        return (f"{self.method}: {self.gate.quantity}{self.gate.op}{self.gate.threshold:g}"
                + (f" [{self.where}]" if self.where else ""))

    @property
    def message(self) -> str:
        shown = "no value" if self.measured is None else f"{self.measured:.6g}"
        return f"measured {shown}, required {self.gate.op} {self.gate.threshold:g}"

    def as_dict(self) -> dict:
        return {"gate": str(self.gate), "method": self.method, "where": self.where,
                "measured": self.measured, "passed": self.passed}


def parse_gate(text: str) -> Gate:
    """One GATE; CampaignError naming the gate and what is wrong."""
    m = _GATE.match(text)
    if not m:
        raise CampaignError(f"--require {text.strip()!r}: expected [METHOD:]PARAM.STAT OP NUMBER "
                            "or [METHOD:]ok|failed|time_s OP NUMBER, e.g. K.abs_bias_pct<0.5")
    quantity, op = m["quantity"], m["op"]
    try:
        threshold = float(m["number"])
    except ValueError:
        raise CampaignError(f"--require {text.strip()!r}: {m['number']!r} is not a number") \
            from None
    if not math.isfinite(threshold):
        raise CampaignError(f"--require {text.strip()!r}: the threshold must be finite")
    if "." in quantity:
        param, stat = quantity.split(".", 1)
        if param not in SCORED:
            raise CampaignError(f"--require {text.strip()!r}: unknown parameter {param!r} "
                                f"(scored: {', '.join(SCORED)})")
        if stat not in STATS:
            raise CampaignError(f"--require {text.strip()!r}: unknown statistic {stat!r} "
                                f"(one of {', '.join(STATS)})")
        return Gate(m["method"], param, stat, op, threshold)
    if quantity not in METHOD_STATS:
        raise CampaignError(f"--require {text.strip()!r}: unknown quantity {quantity!r} "
                            f"(PARAM.STAT or one of {', '.join(METHOD_STATS)})")
    return Gate(m["method"], None, quantity, op, threshold)


def parse_gates(texts: list[str] | tuple[str, ...] | str | None) -> list[Gate]:
    """Every GATE of the --require texts (comma separated in each)."""
    if not texts:
        return []
    if isinstance(texts, str):
        texts = [texts]
    gates = [parse_gate(part) for text in texts for part in text.split(",") if part.strip()]
    if not gates:
        raise CampaignError("--require: no gate given")
    return gates


def check_gates(gates: list[Gate], entries: list[Entry]) -> None:
    """Before any run: every METHOD named is one of the campaign's, estimating PARAM."""
    known = {e.name: e for e in entries}
    for g in gates:
        if g.method is None:
            continue
        if g.method not in known:
            raise CampaignError(f"--require {g}: no method {g.method!r} in this campaign "
                                f"(methods: {', '.join(known)})")
        if g.param is not None and g.param not in known[g.method].params:
            raise CampaignError(f"--require {g}: {g.method} does not estimate {g.param} "
                                f"(it estimates {', '.join(known[g.method].params)})")


def _measure(gate: Gate, method: dict) -> float | None:
    if gate.param is None:
        value = method[gate.stat] if gate.stat != "time_s" or method["timed_runs"] else None
    else:
        value = method["parameters"].get(gate.param, {}).get(gate.stat)
    return None if value is None or not math.isfinite(value) else float(value)


def _applies(gate: Gate, method: dict) -> bool:
    if gate.method is not None:
        return method["method"] == gate.method
    if gate.param is None:
        return True
    return (gate.param in method["parameters"]
            or (method["kind"] != "plug-in" and gate.param in method["estimates"]))


def evaluate(gates: list[Gate], comparison: list[dict]) -> list[GateResult]:
    """Every gate on every method it applies to, at every sweep point (bench.campaign.compare).
    A gate that applies to no method fails once, with no value."""
    out = []
    for gate in gates:
        found = False
        for group in comparison:
            where = ", ".join(f"{k}={v:g}" for k, v in group.get("sweep", {}).items())
            for method in group["methods"]:
                if not _applies(gate, method):
                    continue
                found = True
                value = _measure(gate, method)
                ok = value is not None and OPS[gate.op](value, gate.threshold)
                out.append(GateResult(gate, method["method"], where, value, ok))
        if not found:
            out.append(GateResult(gate, gate.method or "(no method)", "", None, False))
    return out


def gates_text(results: list[GateResult]) -> str:
    """`accuracy gates: F of N failed`, then a PASS / FAIL line per gate and method."""
    failed = sum(not r.passed for r in results)
    lines = [f"accuracy gates: {failed} of {len(results)} failed" if failed
             else f"accuracy gates: all {len(results)} passed"]
    width = max(len(r.name) for r in results) if results else 0
    for r in results:
        lines.append(f"  {'PASS' if r.passed else 'FAIL'} {r.name:<{width}}  {r.message}")
    return "\n".join(lines)
