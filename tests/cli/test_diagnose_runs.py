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


def _fake(*effects, xval=None):
    causes = tuple(SimpleNamespace(effect=e) for e in effects)
    doc = {"causes": [{"effect": e, "t": 5.0, "heldout_pct": 50.0, "p_heldout": 1e-6,
                       "parameters": {}} for e in effects], "candidates": []}
    return SimpleNamespace(diagnosis=SimpleNamespace(causes=causes), cross_validation=xval,
                           table=lambda: "", to_json=lambda: doc)


def _xval(nominal, extended):
    return {"inverse": {"nominal": {"motor": nominal, "link": nominal},
                        "extended": {"motor": extended, "link": extended}}, "forward": {}}


def test_a_cause_is_supported_only_where_the_other_run_confirms_it():
    """Named on both runs, but one run's extended model predicts the other run worse than
    its nominal: the runs do not support it."""
    good = RunsDiagnosis((_fake("backlash", xval=_xval(3.0, 1.0)),
                          _fake("backlash", xval=_xval(3.0, 1.5))), ("a", "b"))
    assert good.supported == ("backlash",) and good.confirms() == (True, True)
    bad = RunsDiagnosis((_fake("backlash", xval=_xval(3.0, 1.0)),
                         _fake("backlash", xval=_xval(3.0, 3.2))), ("a", "b"))
    assert bad.confirms() == (True, False)
    assert bad.supported == () and bad.unsupported == {"backlash": ("a", "b")}
    assert "NOT better" in bad.table()


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
