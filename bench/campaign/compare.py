"""Every method of a campaign side by side: the built-in models, their bias-corrected
estimates and the plug-in methods, per parameter the bias, spread, RMS error and +-k sigma
coverage with each method's own sigma, and per method the failures (with reasons) and the
wall time per log. What the accuracy gates (bench.campaign.gates) measure."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from jointbench.bench.campaign.methods import SCORED, method_labels
from jointbench.bench.campaign.settings import ID_MODELS, debiased_models
from jointbench.bench.campaign.spec import DEBIASED, PARAMS, CampaignSpec
from jointbench.identification.summary import parameter_stats

STATS = ("n", "bias_pct", "abs_bias_pct", "std_pct", "rmse_pct", "sigma_pct", "coverage_pct")
METHOD_STATS = ("ok", "failed", "time_s")
BUILT_IN = {"joint-motor": "least squares, eq. (13)",
            "motor-only": "least squares, eqs. (18)-(20), corrected inversion",
            "motor-only-printed": "least squares, eqs. (18)-(20) as printed"}


@dataclass(frozen=True)
class Entry:
    """Where a method's numbers are in the table: columns `prefix.P`, `prefix.P.sigma_col`."""

    name: str
    kind: str           # built-in, bias-corrected, plug-in
    source: str
    prefix: str
    params: tuple[str, ...]
    sigma_cols: tuple[tuple[str, str], ...]   # (column suffix, kind), first with data wins


def entries(spec: CampaignSpec) -> list[Entry]:
    """The campaign's methods, in table order."""
    out = [Entry(m, "built-in", BUILT_IN[m], ID_MODELS[m], PARAMS[m],
                 (("sigma_c", "corrected"), ("sigma", "paper"))) for m in spec.base.id_models]
    out += [Entry(m + DEBIASED, "bias-corrected", BUILT_IN[m] + " + closed-loop replicas",
                  ID_MODELS[m] + DEBIASED, PARAMS[m], (("sigma_c", "corrected"),))
            for m in debiased_models(spec.base)]
    sources = dict(m.split("=", 1) for m in getattr(spec, "methods", ()))
    out += [Entry(label, "plug-in", sources[label], label, SCORED, (("sigma", "own"),))
            for label in method_labels(spec)]
    return out


def _num(text: str) -> float:
    try:
        return float(text) if text else math.nan
    except ValueError:
        return math.nan


def _column(rows: list[dict[str, str]], key: str) -> np.ndarray:
    return np.array([_num(r.get(key, "")) for r in rows], dtype=float)


def _answered(entry: Entry, row: dict[str, str]) -> bool:
    if entry.kind == "plug-in":
        return row.get(f"{entry.prefix}.status") == "ok"
    return row.get(f"{entry.prefix}.{entry.params[0]}", "") != ""


def _reason(entry: Entry, row: dict[str, str]) -> str:
    own = row.get(f"{entry.prefix}.reason", "") if entry.kind == "plug-in" else ""
    return (own or row.get("reason", "") or "no estimate")[:160]


def _method(entry: Entry, sel: list[dict[str, str]], times: list[float], k: float) -> dict:
    answered = [r for r in sel if _answered(entry, r)]
    failures: dict[str, int] = {}
    for r in sel:
        if not _answered(entry, r):
            failures[_reason(entry, r)] = failures.get(_reason(entry, r), 0) + 1
    sigma_kind, params = None, {}
    for p in entry.params:
        est = _column(answered, f"{entry.prefix}.{p}")
        truth = _column(answered, f"truth.{p}")
        for col, kind in entry.sigma_cols:
            sig = _column(answered, f"{entry.prefix}.{p}.{col}")
            if np.isfinite(sig).any():
                break
        st = parameter_stats(p, est, truth, {kind: sig}, k)
        if st.n == 0:
            continue
        c = st.coverage[kind]
        if c.n:
            sigma_kind = kind
        params[p] = {"n": st.n, "bias_pct": st.bias_pct, "abs_bias_pct": abs(st.bias_pct),
                     "std_pct": st.std_pct, "rmse_pct": st.rmse_pct,
                     "sigma_pct": c.sigma_mean_pct if c.n else math.nan,
                     "coverage_pct": 100 * c.coverage if c.n else math.nan,
                     "coverage_ci95_pct": [100 * x for x in c.interval] if c.n else None}
    return {"method": entry.name, "kind": entry.kind, "source": entry.source,
            "sigma": sigma_kind, "estimates": list(entry.params), "n_runs": len(sel),
            "ok": len(answered),
            "failed": len(sel) - len(answered),
            "failures": dict(sorted(failures.items(), key=lambda kv: -kv[1])[:5]),
            "time_s": float(np.mean(times)) if times else math.nan, "timed_runs": len(times),
            "parameters": params}


def compare(spec: CampaignSpec, rows: list[dict[str, str]],
            times: dict[int, dict[str, float]] | None = None, k: float = 2.0) -> list[dict]:
    """Per sweep point: {"sweep": {...} (with a sweep), "methods": [per method its counts,
    failures, mean wall time per answered log (`times`, bench.campaign.times) and per parameter
    n, bias_pct, abs_bias_pct, std_pct, rmse_pct, sigma_pct, coverage_pct]}."""
    times = times or {}
    out = []
    for point in range(max(1, len(spec.values))):
        sel = [r for r in rows if int(r["run"]) // spec.runs == point]
        group: dict = {}
        if spec.sweep is not None:
            group["sweep"] = {spec.sweep: spec.values[point]}
        group["methods"] = [
            _method(e, sel, [times[int(r["run"])][e.name] for r in sel
                             if e.name in times.get(int(r["run"]), {})], k)
            for e in entries(spec)]
        out.append(group)
    return out


def _shown(source: str) -> str:
    """A plug-in's FILE.py:FUNCTION relative to the current folder when under it."""
    path, sep, attr = source.rpartition(":")
    if sep and path.endswith(".py") and os.path.isabs(path):
        rel = os.path.relpath(path)
        return f"{rel}:{attr}" if not rel.startswith("..") else source
    return source


def _f(x, fmt: str, width: int) -> str:
    return f"{x:>{width}{fmt}}" if x is not None and math.isfinite(x) else f"{'-':>{width}}"


def compare_text(comparison: list[dict], k: float = 2.0) -> str:
    """The comparison as fixed-width text: a line per method, then a line per parameter and
    method (bias, std and RMS error in % of truth, mean sigma in % of truth, coverage)."""
    lines = []
    for group in comparison:
        title = ", ".join(f"{n} = {v:g}" for n, v in group.get("sweep", {}).items())
        ms = group["methods"]
        w = max([6] + [len(m["method"]) for m in ms])
        lines += ["", "## Methods side by side" + (f" ({title})" if title else "")
                  + f": +-{k:g} sigma coverage with each method's own sigma (nominal 95.4 %)",
                  f"{'method':<{w}} {'kind':<14} {'sigma':<9} {'ok':>4} {'failed':>6} "
                  f"{'ms/log':>8}  source"]
        for m in ms:
            t = m["time_s"] * 1e3 if m["timed_runs"] else math.nan
            lines.append(f"{m['method']:<{w}} {m['kind']:<14} {m['sigma'] or '-':<9} "
                         f"{m['ok']:>4} {m['failed']:>6} {_f(t, '.1f', 8)}  {_shown(m['source'])}")
        for m in ms:
            for reason, count in m["failures"].items():
                lines.append(f"  {m['method']} failed x{count}: {reason}")
        head = (f"{'param':<6} {'method':<{w}} {'n':>4} {'bias %':>8} {'std %':>7} "
                f"{'rmse %':>7} | {'sigma %':>8} {'cover %':>7} {'95 % CI':>11}")
        lines += ["", head, "-" * len(head)]
        for p in SCORED:
            first = True
            for m in ms:
                s = m["parameters"].get(p)
                if s is None:
                    continue
                ci = s["coverage_ci95_pct"]
                ci_text = f"{ci[0]:.1f}-{ci[1]:.1f}" if ci else "-"
                lines.append(f"{p if first else '':<6} {m['method']:<{w}} {s['n']:>4} "
                             f"{_f(s['bias_pct'], '.3f', 8)} {_f(s['std_pct'], '.3f', 7)} "
                             f"{_f(s['rmse_pct'], '.3f', 7)} | {_f(s['sigma_pct'], '.4f', 8)} "
                             f"{_f(s['coverage_pct'], '.1f', 7)} {ci_text:>11}")
                first = False
    return "\n".join(lines[1:])
