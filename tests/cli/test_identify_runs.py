"""Several runs of one axis: `jointbench identify A.csv B.csv` and `jointbench.identify([a, b])`
fit each run and pool them (bench.results.runs); a run set apart by a changed stiffness is
named, the pooled sigma covers the spread, and one measured run says its sigma is a lower
bound for the hardware."""

from __future__ import annotations

import json
import sys
from dataclasses import replace

import pytest

from jointbench.testing.simulator import LAB_RIG, simulate_lab_rig

import jointbench as jb
from jointbench.bench.cli import main
from jointbench.bench.results.identify import LOWER_BOUND
from jointbench.bench.results.runs import RunsFit
from jointbench.identification.log import write_log


def _measured(log):
    """The log as a lab has it: no truth in the metadata."""
    return replace(log, meta={k: v for k, v in log.meta.items() if not k.startswith("truth_")})


@pytest.fixture(scope="module")
def runs():
    a = simulate_lab_rig(seed=41, duration=20.0)
    b = simulate_lab_rig(seed=42, duration=20.0)
    c = simulate_lab_rig(replace(LAB_RIG, K=1.04 * LAB_RIG.K), seed=43, duration=20.0)
    return [_measured(x) for x in (a, b, c)]


@pytest.mark.slow
def test_api_pools_runs_and_names_the_one_apart(runs):
    res = jb.identify(runs)
    assert isinstance(res, RunsFit) and len(res.fits) == 3
    p = res.pooled["K"]
    values = [f.parameters["K"].value for f in res.fits]
    # the changed run moved K by 4 %, about 40 of a run's sigma: named, and the pooled sigma
    # widens to the runs' standard error instead of the runs' own
    assert values[2] / values[0] == pytest.approx(1.04, abs=0.01)
    assert p.spread > 10 * p.run_sigma
    assert p.sigma >= 0.9 * p.spread / len(values) ** 0.5
    assert any("K:" in n and "lower bound" in n for n in res.notes)
    text = res.table()
    assert "run-to-run sd" in text and "pooled sigma" in text
    doc = res.to_json()
    assert doc["pooled"]["K"]["outliers"]


def test_one_measured_run_says_its_sigma_is_a_lower_bound(runs):
    assert LOWER_BOUND in jb.identify(runs[0]).table()


@pytest.mark.slow
def test_cli_takes_several_files(runs, tmp_path, capsys):
    paths = []
    for i, log in enumerate(runs[:2]):
        paths.append(str(tmp_path / f"run{i}.csv"))
        write_log(log, paths[-1])
    assert main(["identify", *paths, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in doc["runs"]] == paths
    assert doc["pooled"]["K"]["sigma"] > 0
    assert main(["identify", *paths]) == 0
    assert "2 runs of one axis, pooled" in capsys.readouterr().out
