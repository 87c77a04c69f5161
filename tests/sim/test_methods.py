"""Plug-in estimators in campaigns (bench/campaign/methods.py, host.py, compare.py; issue 19):
a deliberately biased copy of the joint-motor least squares scored beside the built-in,
methods that raise, hang, crash or return garbage recorded as failures while the campaign goes
on, bad --method specs refused before any run, the Python API `jb.campaign`.

Short experiments (5-10 s) and few runs keep the file fast."""

from __future__ import annotations

import json
import math
import multiprocessing
import os
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import jointbench as jb
from jointbench.bench.campaign.methods import (BadResult, blind, check_estimates, method_of,
                                               parse_method)
from jointbench.bench.campaign.settings import CampaignError
from jointbench.bench.cli import main

REPO = Path(__file__).resolve().parents[2]
BIASED = f"biased={REPO / 'examples' / 'biased_ls.py'}:estimate"
HERE = Path(__file__).resolve()


# Misbehaving methods: found by the host process through this file (FILE.py:FUNCTION).
def raises(log):
    raise RuntimeError("estimator diverged")


def sleeps(log):
    time.sleep(600)
    return {"K": 1.0}


def returns_nan(log):
    return {"K": math.nan, "Jm": 1.0}


def returns_list(log):
    return [1.0, 2.0]


def unknown_name(log):
    return {"stiffness": 2e4}


def dies(log):
    os._exit(3)


def peeks(log):
    """Reads the truth: a blind log has none."""
    return {"K": float(log.meta.get("truth_K", "nan"))}


# ---------------------------------------------------------------------------------------------
# The biased copy of the built-in (must show)


@pytest.fixture(scope="module")
def biased_table(tmp_path_factory):
    """6 runs of 10 s, joint-motor model and the biased plug-in, gated on |bias K| < 0.5 %."""
    folder = tmp_path_factory.mktemp("biased")
    out, junit = folder / "b.csv", folder / "gates.xml"
    args = ["campaign", "--runs", "6", "--duration", "10", "--workers", "1", "--quiet",
            "--id-models", "joint-motor", "--method", BIASED, "--out", str(out)]
    code = main(args + ["--require", "K.abs_bias_pct<0.5", "--junit", str(junit)])
    summary = json.loads((folder / "b.summary.json").read_text())
    times = (folder / "b.times.csv").read_text().splitlines()
    assert times[0] == "run,method,wall_s" and len(times) == 1 + 6 * 2   # both methods, 6 runs
    return args, code, summary, junit


def _method(summary: dict, name: str) -> dict:
    (m,) = [m for m in summary["comparison"][0]["methods"] if m["method"] == name]
    return m


def test_biased_plugin_shows_its_bias_and_loses_coverage(biased_table):
    _, _, summary, _ = biased_table
    built_in, biased = _method(summary, "joint-motor"), _method(summary, "biased")
    assert biased["ok"] == built_in["ok"] == 6 and biased["failed"] == 0
    for p in ("K", "Jm", "JL"):   # positive truths: estimate x 1.01 -> % error x 1.01 + 1
        b, s = biased["parameters"][p], built_in["parameters"][p]
        assert b["bias_pct"] == pytest.approx(1.01 * s["bias_pct"] + 1.0, abs=1e-9)
        assert b["std_pct"] == pytest.approx(1.01 * s["std_pct"], rel=1e-9)
        assert b["coverage_pct"] < s["coverage_pct"], p
    assert biased["sigma"] == "own" and built_in["sigma"] == "corrected"
    assert math.isfinite(biased["time_s"]) and biased["timed_runs"] == 6


def test_gate_fails_on_the_biased_copy_and_passes_on_the_built_in(biased_table, capsys):
    args, code, summary, junit = biased_table
    assert code == 3
    gates = {g["method"]: g for g in summary["gates"]}
    assert not gates["biased"]["passed"] and gates["biased"]["measured"] > 0.5
    assert gates["joint-motor"]["passed"] and gates["joint-motor"]["measured"] < 0.5
    cases = ET.parse(junit).getroot().findall("./testsuite/testcase")
    failures = {c.get("name"): c.find("failure") for c in cases}
    assert failures["joint-motor: K.abs_bias_pct<0.5"] is None
    message = failures["biased: K.abs_bias_pct<0.5"].get("message")
    assert message == f"measured {gates['biased']['measured']:.6g}, required < 0.5"
    # The same table, resumed (no run repeated), gated per method.
    assert main(args + ["--require", "joint-motor:K.abs_bias_pct<0.5, biased:time_s<1e9"]) == 0
    assert main(args + ["--require", "biased:K.abs_bias_pct<0.5"]) == 3
    err = capsys.readouterr().err
    assert "1 of 1 accuracy gates failed: biased: K.abs_bias_pct<0.5 (measured" in err


# ---------------------------------------------------------------------------------------------
# Misbehaving methods (must show)


def test_misbehaving_methods_fail_alone_and_the_campaign_goes_on(tmp_path):
    bad = {name: f"{HERE}:{name}" for name in
           ("raises", "sleeps", "returns_nan", "returns_list", "unknown_name", "dies", "peeks")}
    report = jb.campaign(runs=2, duration=5, workers=1, id_models=["joint-motor"],
                         methods=bad, method_timeout=2.0, out=tmp_path / "bad.csv",
                         require="failed==0")
    assert [r["status"] for r in report.rows] == ["ok", "ok"]      # the built-in is unharmed
    expected = {"raises": "RuntimeError: estimator diverged",
                "sleeps": "timeout: no answer within 2 s (call stopped)",
                "returns_nan": "K = nan is not finite",
                "returns_list": "returned a list, expected a dict",
                "unknown_name": "unknown parameter name(s) 'stiffness'",
                "dies": "its process died (exit code 3)",
                "peeks": "K = nan is not finite"}
    text = report.table()
    for name, reason in expected.items():
        for row in report.rows:
            assert row[f"{name}.status"] == "failed" and reason in row[f"{name}.reason"]
        assert f"{name} failed x2: {reason}" in text
    assert _method(report.summary, "joint-motor")["ok"] == 2
    assert not report.passed
    assert {r.method for r in report.gates if not r.passed} == set(bad)
    assert multiprocessing.active_children() == []     # every host stopped


def test_plugin_on_worker_processes_gives_the_serial_table(tmp_path):
    args = ["campaign", "--runs", "2", "--duration", "5", "--quiet", "--id-models",
            "joint-motor", "--method", BIASED]
    assert main(args + ["--workers", "1", "--out", str(tmp_path / "a.csv")]) == 0
    assert main(args + ["--workers", "2", "--out", str(tmp_path / "b.csv")]) == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_api_callable_runs_in_this_process_with_one_worker():
    report = jb.campaign(runs=1, duration=5, workers=1, id_models=["joint-motor"],
                         methods={"const": lambda log: {"K": (2.0e4, 50.0)}},
                         require="const:K.n==1")
    assert report.passed and report.rows[0]["const.K"] == "20000.0"
    assert report.to_json()["gates"][0]["measured"] == 1
    slow = jb.campaign(runs=1, duration=5, workers=1, id_models=["joint-motor"],
                       methods={"slow": lambda log: time.sleep(3)}, method_timeout=0.2)
    assert slow.rows[0]["slow.reason"] == ("timeout: no answer within 0.2 s (the call could not "
                                           "be stopped: it runs on in a background thread)")
    with pytest.raises(CampaignError, match="cannot be sent to worker processes"):
        jb.campaign(runs=1, duration=5, workers=2, methods={"c": lambda log: {"K": 1.0}})
    with pytest.raises(CampaignError, match="unknown setting.s. noize"):
        jb.campaign(runs=1, noize=2.0)
    with pytest.raises(CampaignError, match="needs a label"):
        jb.campaign(runs=1, duration=5, workers=1, methods=[lambda log: {"K": 1.0}])


# ---------------------------------------------------------------------------------------------
# Bad input, before any run


@pytest.mark.parametrize("spec, message", [
    ("no_such_module_xyz:f", "cannot import no_such_module_xyz: ModuleNotFoundError"),
    (f"{HERE}:nothing", "has no attribute 'nothing'"),
    (f"{HERE}:REPO", "REPO is a PosixPath, not callable"),
    ("missing_file.py:f", "no such file missing_file.py"),
    ("estimate", "expected MODULE:FUNCTION or FILE.py:FUNCTION"),
    (f"9lives={HERE}:raises", "label '9lives' must start with a letter"),
    (f"joint-motor={HERE}:raises", "label 'joint-motor' is taken"),
])
def test_bad_method_spec_is_exit_2_before_any_run(tmp_path, capsys, spec, message):
    out = tmp_path / "never.csv"
    code = main(["campaign", "--runs", "1", "--duration", "5", "--workers", "1", "--quiet",
                 "--method", spec, "--out", str(out)])
    assert code == 2 and not out.exists()
    err = capsys.readouterr().err
    assert err.startswith("jointbench campaign: error: --method") and message in err
    assert "Traceback" not in err


def test_same_label_twice_is_refused(tmp_path):
    code = main(["campaign", "--runs", "1", "--workers", "1", "--method", f"{HERE}:raises",
                 "--method", f"{HERE}:raises", "--out", str(tmp_path / "x.csv")])
    assert code == 2 and not (tmp_path / "x.csv").exists()


def test_method_of_finds_module_functions_by_name():
    m = method_of(check_estimates)
    assert m.ref == "jointbench.bench.campaign.methods:check_estimates" and m.fn is None
    assert parse_method("x=jointbench.bench.campaign.methods:blind").label == "x"


# ---------------------------------------------------------------------------------------------
# A method's answer


def test_check_estimates_accepts_values_and_pairs():
    est, sig = check_estimates({"K": 2e4, "Jm": (175, 0.5), "JL": [47.0, None], "J": 222})
    assert est == {"K": 2e4, "Jm": 175.0, "JL": 47.0, "J": 222.0} and sig == {"Jm": 0.5}


@pytest.mark.parametrize("value, message", [
    (None, "returned a NoneType"), ({}, "returned no estimates"),
    ({"K": "2e4"}, "K is a str, not a number"), ({"K": True}, "K is a bool"),
    ({"K": math.inf}, "K = inf is not finite"), ({"K": (1.0, -1.0)}, "negative"),
    ({"K": (1.0, 2.0, 3.0)}, "expected (value, sigma), got 3 items"),
    ({"k": 1.0}, "unknown parameter name(s) 'k'"),
    ({"K": (1.0, math.nan)}, "sigma of K = nan is not finite"),
])
def test_check_estimates_rejects_garbage(value, message):
    with pytest.raises(BadResult, match=None) as err:
        check_estimates(value)
    assert message in str(err.value)


def test_blind_log_has_no_truth():
    log = jb.simulate("prototype", duration=5.0, seed=3)
    seen = blind(log)
    assert log.truth() and not seen.truth()
    assert not any(k.startswith("truth_") for k in seen.meta)
    assert seen.meta["kp"] == log.meta["kp"] and (seen.q_m == log.q_m).all()
