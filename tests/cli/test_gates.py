"""Accuracy gates (bench/campaign/gates.py) and their JUnit report (bench/campaign/junit.py):
the grammar, which methods a gate applies to, missing values, sweep points, the XML, and bad
gates or report paths refused (exit 2) before any run. Pure, except the two CLI checks, which
stop before simulating anything."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import pytest

from jointbench.bench.campaign.compare import entries
from jointbench.bench.campaign.gates import (Gate, check_gates, evaluate, gates_text,
                                             parse_gate, parse_gates)
from jointbench.bench.campaign.junit import check_junit_path, junit_xml, write_junit
from jointbench.bench.campaign.methods import Method, with_methods
from jointbench.bench.campaign.settings import CampaignError, RunSettings
from jointbench.bench.campaign.spec import CampaignSpec
from jointbench.bench.cli import main


def test_grammar():
    assert parse_gate("K.bias_pct<0.5") == Gate(None, "K", "bias_pct", "<", 0.5)
    assert parse_gate(" mine : Jm.coverage_pct >= 90 ") == Gate("mine", "Jm", "coverage_pct",
                                                                 ">=", 90.0)
    assert parse_gate("joint-motor+bc:JL.rmse_pct<=1e-1") == Gate(
        "joint-motor+bc", "JL", "rmse_pct", "<=", 0.1)
    assert parse_gate("failed==0") == Gate(None, None, "failed", "==", 0.0)
    assert parse_gate("x:time_s<2") == Gate("x", None, "time_s", "<", 2.0)
    assert parse_gate("K.bias_pct>-1").threshold == -1.0
    gates = parse_gates(["K.abs_bias_pct<0.5, Jm.coverage_pct>=90, failed==0", "ok!=0"])
    assert [str(g) for g in gates] == ["K.abs_bias_pct<0.5", "Jm.coverage_pct>=90", "failed==0",
                                       "ok!=0"]
    assert parse_gates(None) == []


@pytest.mark.parametrize("text, message", [
    ("K.bias_pct", "expected [METHOD:]PARAM.STAT OP NUMBER"),
    ("K.bias_pct=<1", "expected"),
    ("K.bias_pct<one", "'one' is not a number"),
    ("K.bias_pct<nan", "the threshold must be finite"),
    ("X1.bias_pct<1", "unknown parameter 'X1'"),
    ("K.mean<1", "unknown statistic 'mean'"),
    ("failures==0", "unknown quantity 'failures'"),
    ("a:b:K.n>1", "expected"),
])
def test_malformed_gates(text, message):
    with pytest.raises(CampaignError) as err:
        parse_gate(text)
    assert message in str(err.value)


def test_gates_must_name_methods_of_the_campaign():
    spec = with_methods(CampaignSpec(base=RunSettings(id_models=("motor-only-printed",))),
                        [Method("mine", "math:fabs")])
    check_gates(parse_gates("mine:MX.n>0, motor-only-printed:K.n>0, K.n>0"), entries(spec))
    with pytest.raises(CampaignError, match="no method 'joint-motor' in this campaign"):
        check_gates(parse_gates("joint-motor:K.n>0"), entries(spec))
    with pytest.raises(CampaignError, match="motor-only-printed does not estimate MX"):
        check_gates(parse_gates("motor-only-printed:MX.n>0"), entries(spec))


def _m(name, kind="plug-in", params=None, ok=10, failed=0, time_s=0.01, timed=10,
       estimates=("K", "Jm")):
    return {"method": name, "kind": kind, "ok": ok, "failed": failed, "time_s": time_s,
            "timed_runs": timed, "estimates": list(estimates), "parameters": params or {}}


COMPARISON = [{"methods": [
    _m("joint-motor", "built-in", {"K": {"n": 10, "bias_pct": -0.3, "abs_bias_pct": 0.3,
                                         "coverage_pct": 40.0},
                                   "Jm": {"n": 10, "bias_pct": 0.2, "abs_bias_pct": 0.2,
                                          "coverage_pct": math.nan}}),
    _m("motor-only", "built-in", {}, ok=0, failed=10, timed=0),      # failed every run
    _m("mine", "plug-in", {"K": {"n": 10, "bias_pct": 0.7, "abs_bias_pct": 0.7,
                                 "coverage_pct": 95.0}}),
    _m("never", "plug-in", {}, ok=0, failed=10, timed=0),
]}]


def _by(results):
    return {(r.method, f"{r.gate.quantity}{r.gate.op}{r.gate.threshold:g}"): r for r in results}


def test_evaluate_applies_unqualified_gates_to_every_method_that_estimates():
    r = _by(evaluate(parse_gates("K.abs_bias_pct<0.5"), COMPARISON))
    # the built-in that failed fails the gate (no value); the plug-in that never returned K
    # is not asked about K (its `failed` says what happened)
    assert set(r) == {(m, "K.abs_bias_pct<0.5") for m in ("joint-motor", "motor-only", "mine")}
    assert r["joint-motor", "K.abs_bias_pct<0.5"].passed
    assert not r["mine", "K.abs_bias_pct<0.5"].passed
    assert r["mine", "K.abs_bias_pct<0.5"].measured == 0.7
    missing = r["motor-only", "K.abs_bias_pct<0.5"]
    assert not missing.passed and missing.measured is None
    assert missing.message == "measured no value, required < 0.5"


def test_evaluate_method_level_and_missing_values():
    r = _by(evaluate(parse_gates("failed==0, never:time_s<1, Jm.coverage_pct>=90, "
                                 "mine:K.coverage_pct>=90, mine:Jm.n>0"), COMPARISON))
    assert [r[m, "failed==0"].passed for m in ("joint-motor", "motor-only", "mine", "never")] \
        == [True, False, True, False]
    assert r["never", "failed==0"].measured == 10
    assert not r["never", "time_s<1"].passed and r["never", "time_s<1"].measured is None
    assert not r["joint-motor", "Jm.coverage_pct>=90"].passed     # NaN: no sigma, no value
    assert r["mine", "K.coverage_pct>=90"].passed
    assert not r["mine", "Jm.n>0"].passed


def test_gate_on_nothing_fails_and_sweep_points_are_named():
    (r,) = evaluate(parse_gates("MY.n>0"), COMPARISON)
    assert not r.passed and r.method == "(no method)"
    sweep = [{"sweep": {"amplitude": a}, "methods": [_m("mine", params={"K": {
        "n": 5, "abs_bias_pct": b}})]} for a, b in ((0.05, 0.2), (0.2, 0.9))]
    res = evaluate(parse_gates("K.abs_bias_pct<0.5"), sweep)
    assert [(x.where, x.passed) for x in res] == [("amplitude=0.05", True),
                                                  ("amplitude=0.2", False)]
    text = gates_text(res)
    assert text.splitlines()[0] == "accuracy gates: 1 of 2 failed"
    assert text.splitlines()[2].split() == ["FAIL", "mine:", "K.abs_bias_pct<0.5",
                                            "[amplitude=0.2]", "measured", "0.9,", "required",
                                            "<", "0.5"]


def test_junit_report(tmp_path):
    results = evaluate(parse_gates("K.abs_bias_pct<0.5, failed==0"), COMPARISON)
    path = tmp_path / "gates.xml"
    write_junit(path, results, {"table": "t.csv"}, 12.5)
    root = ET.parse(path).getroot()
    assert root.tag == "testsuites" and root.get("name") == "jointbench campaign"
    suite = root.find("testsuite")
    failed = sum(not r.passed for r in results)
    assert (suite.get("tests"), suite.get("failures")) == (str(len(results)), str(failed))
    cases = suite.findall("testcase")
    assert [c.get("name") for c in cases] == [r.name for r in results]
    assert [c.find("failure") is not None for c in cases] == [not r.passed for r in results]
    assert suite.find("properties/property").get("value") == "t.csv"
    # rewriting our own report is allowed; another file is never overwritten
    check_junit_path(path)
    other = tmp_path / "other.xml"
    other.write_text("<results/>")
    with pytest.raises(CampaignError, match="refusing to overwrite"):
        check_junit_path(other)
    with pytest.raises(CampaignError, match="does not exist"):
        check_junit_path(tmp_path / "no" / "g.xml")
    assert junit_xml([], {}, 0.0).startswith("<?xml")


@pytest.mark.parametrize("extra, message", [
    (["--require", "K.bias_pct<<1"], "--require 'K.bias_pct<<1': expected"),
    (["--require", "mine:K.n>1"], "no method 'mine' in this campaign"),
    (["--junit", "g.xml"], "--junit needs --require"),
    (["--require", "K.n>0", "--junit", "nowhere/g.xml"], "folder nowhere does not exist"),
])
def test_bad_gates_are_exit_2_before_any_run(tmp_path, monkeypatch, capsys, extra, message):
    monkeypatch.chdir(tmp_path)
    code = main(["campaign", "--runs", "1", "--workers", "1", "--quiet", "--out", "t.csv",
                 *extra])
    assert code == 2 and not (tmp_path / "t.csv").exists()
    assert message in capsys.readouterr().err
