"""`diagnose` over several runs of one axis: each run diagnosed and cross-validated on a run
it did not fit; a cause named for the axis only where every run names it."""

from __future__ import annotations

import json
import sys
from types import SimpleNamespace

import pytest

import jointbench as jb
from jointbench.bench.cli import main
from jointbench.bench.results.diagnose_runs import RunsDiagnosis
from jointbench.identification.log import write_log
from jointbench.testing.simulator import simulate_lab_rig


def _fake(*effects):
    causes = tuple(SimpleNamespace(effect=e) for e in effects)
    return SimpleNamespace(diagnosis=SimpleNamespace(causes=causes))


def test_a_cause_is_supported_only_where_every_run_names_it():
    runs = RunsDiagnosis((_fake("backlash", "offset"), _fake("backlash"),
                          _fake("torque_lag", "backlash")), ("a", "b", "c"))
    assert runs.supported == ("backlash",)
    assert runs.unsupported == {"offset": ("a",), "torque_lag": ("c",)}


@pytest.mark.slow
def test_two_lab_rig_runs_cross_validated(tmp_path, capsys):
    paths = []
    for seed in (51, 52):
        paths.append(str(tmp_path / f"run{seed}.csv"))
        write_log(simulate_lab_rig(seed=seed, duration=20.0), paths[-1])
    runs = jb.diagnose(paths, forward=False)
    assert len(runs.results) == 2
    for r, other in zip(runs.results, reversed(paths)):
        assert r.validate_source == other and r.cross_validation is not None
    assert runs.supported == () and runs.unsupported == {}   # no hidden effect: none named
    assert main(["diagnose", *paths, "--no-forward", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in doc["runs"]] == paths and doc["supported"] == []
    assert main(["diagnose", *paths, "--out", str(tmp_path / "x")]) == 2
