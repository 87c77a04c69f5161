"""A campaign's Monte Carlo summary: per sweep point, per identification model, per parameter, the
bias, empirical std, mean reported sigma and +-k sigma coverage (identification.summary), as
JSON-able data and as fixed-width text."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from jointbench.bench.campaign.compare import compare, compare_text
from jointbench.bench.campaign.settings import ID_MODELS, debiased_models
from jointbench.bench.campaign.spec import DEBIASED, PARAMS, CampaignSpec
from jointbench.identification.summary import (NOMINAL_2SIGMA, Coverage, ParameterStats,
                                               parameter_stats, stats_table)

SIGMA_KINDS = {"sigma": "paper", "sigma_c": "corrected"}
DEBIASED_SIGMA_KINDS = {"sigma_c": "corrected", "sigma_r": "replicas"}


def _num(row: dict[str, str], key: str) -> float:
    """The number in column `key` of a table row; NaN when empty or not a number."""
    v = row.get(key, "")
    try:
        return float(v) if v else math.nan
    except ValueError:
        return math.nan


def _model_stats(sel: list[dict[str, str]], pre: str, params: tuple[str, ...],
                 sigma_kinds: dict[str, str], k: float) -> list[dict]:
    """Per parameter the statistics of the columns `pre.p` against `truth.p`, each sigma column
    `pre.p.col` as the coverage of kind `sigma_kinds[col]`."""
    stats = []
    for p in params:
        est = np.array([_num(r, f"{pre}.{p}") for r in sel])
        truth = np.array([_num(r, f"truth.{p}") for r in sel])
        sig = {kind: np.array([_num(r, f"{pre}.{p}.{col}") for r in sel])
               for col, kind in sigma_kinds.items()}
        stats.append(parameter_stats(p, est, truth, sig, k).as_dict())
    return stats


def summarize(spec: CampaignSpec, rows: list[dict[str, str]], k: float = 2.0,
              times: dict[int, dict[str, float]] | None = None) -> dict:
    """The campaign's Monte Carlo statistics (JSON-able): per sweep point, per identification
    model, per parameter: bias, empirical std, mean sigma (paper and corrected) and coverage;
    and `comparison`, every method side by side (bench.campaign.compare; `times`: run ->
    method -> wall time of the runs done now)."""
    failures: dict[str, int] = {}
    for r in rows:
        if r["status"] != "ok":
            key = r["reason"][:160]
            failures[key] = failures.get(key, 0) + 1
    groups = []
    points = range(max(1, len(spec.values)))
    for point in points:
        sel = [r for r in rows if int(r["run"]) // spec.runs == point]
        group = {"n_runs": len(sel), "ok": sum(r["status"] == "ok" for r in sel)}
        if spec.sweep is not None:
            group["sweep"] = {spec.sweep: spec.values[point]}
        models = {}
        for m in spec.base.id_models:
            models[m] = _model_stats(sel, ID_MODELS[m], PARAMS[m], SIGMA_KINDS, k)
        for m in debiased_models(spec.base):
            models[f"{m} (bias-corrected)"] = _model_stats(sel, ID_MODELS[m] + DEBIASED,
                                                           PARAMS[m], DEBIASED_SIGMA_KINDS, k)
        group["models"] = models
        groups.append(group)
    return {"spec": json.loads(spec.to_json()), "runs": len(rows),
            "ok": sum(r["status"] == "ok" for r in rows),
            "failed": sum(r["status"] != "ok" for r in rows),
            "failures": dict(sorted(failures.items(), key=lambda kv: -kv[1])[:10]),
            "k_sigma": k, "nominal_coverage": NOMINAL_2SIGMA if k == 2.0 else None,
            "groups": groups, "comparison": compare(spec, rows, times, k)}


def _stats_of(group_model: list[dict]) -> list[ParameterStats]:
    """The ParameterStats back from their JSON form (summarize's per-model lists)."""
    out = []
    for d in group_model:
        cov = {kind: Coverage(n=c["n"], sigma_mean=c["sigma_mean"],
                              sigma_mean_pct=c["sigma_mean_pct"], coverage=c["coverage"],
                              interval=tuple(c["coverage_ci95"]),
                              std_over_sigma=c["std_over_sigma"])
               for kind, c in d["coverage"].items()}
        out.append(ParameterStats(d["name"], d["n"], d["truth_mean"], d["bias"], d["bias_pct"],
                                  d["std"], d["std_pct"], d["rmse_pct"], d["k"], cov))
    return out


def summary_text(summary: dict, side_by_side: bool | None = None) -> str:
    """The summary as fixed-width tables (printed, and the body of the Markdown file); the
    methods side by side when `side_by_side` (None: when plug-in methods ran)."""
    lines = [f"runs: {summary['runs']}, ok: {summary['ok']}, failed: {summary['failed']}"]
    for reason, count in summary["failures"].items():
        lines.append(f"  failed x{count}: {reason}")
    lines.append("Columns: bias and empirical std of (estimate - truth) in % of truth; per kind "
                 "of reported sigma: its mean in % of truth, empirical std / RMS sigma "
                 f"(1 = calibrated), and the +-{summary['k_sigma']:g} sigma coverage with its "
                 "95 % interval (nominal 95.4 %).")
    for group in summary["groups"]:
        title = ", ".join(f"{k} = {v:g}" for k, v in group.get("sweep", {}).items())
        for m, stats in group["models"].items():
            kinds = tuple(kind for kind in ("paper", "corrected", "replicas")
                          if any(s["coverage"].get(kind, {}).get("n", 0) > 0 for s in stats))
            lines.append("")
            lines.append(f"## {m}" + (f" ({title})" if title else "")
                         + f": {group['ok']} of {group['n_runs']} runs ok")
            lines.append(stats_table(_stats_of(stats), kinds or ("paper",)))
    comparison = summary.get("comparison", [])
    if side_by_side is None:
        side_by_side = any(m["kind"] == "plug-in" for g in comparison for m in g["methods"])
    if side_by_side and comparison:
        lines += ["", compare_text(comparison, summary["k_sigma"])]
    return "\n".join(lines)


def summary_paths(table: Path) -> tuple[Path, Path]:
    """The summary files beside a table: TABLE.summary.json and TABLE.summary.md."""
    stem = table.with_suffix("") if table.suffix.lower() == ".csv" else table
    return Path(f"{stem}.summary.json"), Path(f"{stem}.summary.md")
