"""One campaign from spec to report: the output checks before any run, the runs on an engine
(bench.campaign.executors), the summary with its timing and gates, the JUnit report and the
summary files beside the table. `jointbench.campaign` and `jointbench campaign` both end here.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from jointbench.bench.campaign.executors import make_executor
from jointbench.bench.campaign.gates import Gate, evaluate
from jointbench.bench.campaign.junit import check_junit_path, write_junit
from jointbench.bench.campaign.methods import DEFAULT_TIMEOUT_S, Method
from jointbench.bench.campaign.run import expected_of, run_campaign
from jointbench.bench.campaign.settings import CampaignError
from jointbench.bench.campaign.spec import CampaignSpec
from jointbench.bench.campaign.summary import summary_paths
from jointbench.bench.campaign.table import CampaignTable
from jointbench.bench.output_files import check_file, write_text
from jointbench.bench.results.campaign import CampaignReport
from jointbench.identification.output_values import finite_json

# progress(total runs, runs already in the table, engine) -> the per-run callback (ok) or None
ProgressFactory = Callable[[int, int, str], Callable[[bool], None] | None]


def check_outputs(spec: CampaignSpec, out: Path | None, junit: Path | None,
                  gates: Sequence[Gate], workers: int | None) -> None:
    """Before any run: the JUnit report has gates and its own file, the table is neither the
    model nor an MJCF file, the table and its summaries can be written (bench.output_files: a
    campaign table or absent, the summaries ours or absent) (the memory each local worker needs is
    checked by run_campaign, before any run). Raises CampaignError, OutputError."""
    if junit is not None:
        if not gates:
            raise CampaignError("--junit needs --require: the report holds the gates")
        if out is not None and junit.resolve() == out.resolve():
            raise CampaignError(f"--junit {junit}: the same file as --out")
        check_junit_path(junit)
    model = Path(spec.base.model)
    if out is not None:
        if out.suffix.lower() == ".xml" or (model.exists() and out.resolve() == model.resolve()):
            raise CampaignError(f"--out {out}: refusing to overwrite the model file")
        for path in (out, *summary_paths(out)):
            check_file(path)


def _timing(result, executor) -> dict:
    """The summary's `timing` object: engine, workers, runs done and resumed, wall time,
    throughput and mean costs per run (None when not measured)."""
    return {
        "engine": executor.description, "workers": executor.workers,
        "runs_this_invocation": result.new, "resumed_rows": result.resumed,
        "wall_s": result.wall_s,
        "runs_per_s": result.new / result.wall_s if result.wall_s > 0 and result.new else None,
        "mean_simulation_s": float(np.mean(result.sim_s)) if result.sim_s else None,
        "mean_identification_s": float(np.mean(result.identify_s)) if result.identify_s else None,
    }


def run_report(spec: CampaignSpec, methods: Sequence[Method], gates: Sequence[Gate],
               out: str | os.PathLike | None, *, workers: int | None = None,
               scheduler: str | None = None, method_timeout: float = DEFAULT_TIMEOUT_S,
               junit: str | os.PathLike | None = None,
               progress: ProgressFactory | None = None) -> CampaignReport:
    """Run (or resume, when `out` holds the same campaign) `spec` and report it: the table
    goes to `out` with its summaries beside it (`summary_paths`), or to a temporary file
    when `out` is None; the gates are evaluated on the comparison and, with `junit`, written
    as a JUnit report. Raises CampaignError (a ValueError) for bad input, before any run."""
    table = Path(out) if out is not None else None
    junit_path = Path(junit) if junit is not None else None
    check_outputs(spec, table, junit_path, gates, workers)
    executor = make_executor(workers, scheduler)
    try:
        with tempfile.TemporaryDirectory(prefix="jointbench-campaign-") as tmp:
            path = table if table is not None else Path(tmp) / "campaign.csv"
            done = 0
            if path.exists():
                tab = CampaignTable(path, spec, expected=expected_of(spec))  # before any work
                done = len(tab.rows)
                tab.close()
            update = progress(spec.total, done, executor.description) if progress else None
            result = run_campaign(spec, path, executor, progress=update, methods=methods,
                                  method_timeout=method_timeout)
    finally:
        executor.close()
    summary = dict(result.summary)
    summary["table"] = str(table) if table is not None else None
    summary["timing"] = _timing(result, executor)
    results = evaluate(gates, summary["comparison"]) if gates else []
    if gates:
        summary["gates"] = [r.as_dict() for r in results]
    if junit_path is not None:
        write_junit(junit_path, results, {"table": str(table), "runs": str(summary["runs"]),
                                          "spec": json.dumps(summary["spec"], sort_keys=True)},
                    result.wall_s)
    report = CampaignReport(summary, tuple(result.rows), tuple(results),
                            str(table) if table is not None else None, result.wall_s,
                            result.times)
    if table is not None:
        json_path, md_path = summary_paths(table)
        write_text(json_path, json.dumps(finite_json(summary), indent=1, allow_nan=False) + "\n")
        write_text(md_path, f"# Campaign {table.name}\n\n{report.timing_line()}\n\n```\n"
                            f"{report.table()}\n```\n")
    return report
