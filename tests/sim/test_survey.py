"""`jointbench survey` (issue 18): every axis in turn, identified with the defaults, one table
against the truth. Two axes of arm6 at the mission's 60 s, seed 1 (about 1.5 s of simulation
and identification in this process)."""

from __future__ import annotations

import csv
import io
import json
import math
from contextlib import redirect_stdout

import pytest

from jointbench.bench.cli import main
from jointbench.bench.output_files import MANIFEST
from jointbench.bench.sim.axes import build_experiment_model

ARGS = ["survey", "--model", "arm6", "--joints", "axis1,4", "--duration", "60", "--seed", "1",
        "--quiet"]
AXES = ("axis1", "axis4")


def _strict(text: str) -> dict:
    def refuse(name):
        raise ValueError(f"not strict JSON: {name}")
    return json.loads(text, parse_constant=refuse)


def _run(argv: list[str]) -> tuple[int, str]:
    buf = io.StringIO()
    with redirect_stdout(buf):
        status = main(argv)
    return status, buf.getvalue()


@pytest.fixture(scope="module")
def surveyed(tmp_path_factory):
    out = tmp_path_factory.mktemp("survey") / "out"
    status, text = _run(ARGS + ["--workers", "1", "--json", "--out", str(out)])
    return status, _strict(text), out


def _table(out) -> list[dict[str, str]]:
    lines = [ln for ln in (out / "survey.csv").read_text().splitlines() if not ln.startswith("#")]
    return list(csv.DictReader(lines))


def test_json_answer_and_files(surveyed):
    status, doc, out = surveyed
    assert status == 0
    assert [j["joint"] for j in doc["joints"]] == list(AXES)   # "4" is the 4th axis
    assert doc["failed"] == [] and doc["sample_rate_hz"] == 350.87 and doc["seed"] == 1
    for name in ("survey.csv", "survey.png", "logs/axis1.csv", "logs/axis4.csv", MANIFEST):
        assert (out / name).is_file(), name
    assert sorted(doc["files"]) == sorted(str(out / n) for n in
                                          ("survey.csv", "survey.png", "logs/axis1.csv",
                                           "logs/axis4.csv"))
    manifest = json.loads((out / MANIFEST).read_text())
    assert manifest["complete"] and "survey.png" in manifest["files"]


def test_table_against_the_truth(surveyed):
    """The truth is the compiled model's (models.truth), f1 its sqrt(K (1/Jm + 1/JL)) / 2 pi;
    the estimates meet issue 17's bar. Tolerances: K, Jm, JL within 0.5 % (the issue's bar;
    measured at seed 1: 0.23 % at most on these axes) and 3 corrected sigma (as
    tests/sim/test_first_mode.py); the frictions within 3 corrected sigma (measured: 1.96 at
    most, FVm of axis1; their errors in % are larger, FVm -4.7 %, since a 60 s chirp
    excites the motor's viscous term weakly); f1 within 2 % (test_first_mode's bound;
    measured +0.66 % at most)."""
    _, doc, out = surveyed
    rows = _table(out)
    for joint in AXES:
        truth = build_experiment_model("arm6", joint).truth
        got = {r["parameter"]: r for r in rows if r["joint"] == joint}
        assert list(got) == ["f1", "K", "Jm", "JL", "FVm", "FSm", "FV", "FS"]
        f1 = math.sqrt(truth.K * (1 / truth.Jm + 1 / truth.JL)) / (2 * math.pi)
        assert float(got["f1"]["truth"]) == pytest.approx(f1, rel=1e-8)
        assert abs(float(got["f1"]["error_pct"])) < 2
        for name, row in got.items():
            value, true = float(row["estimate"]), float(row["truth"])
            if name != "f1":
                assert true == pytest.approx(getattr(truth, name), rel=1e-8), (joint, name)
            err = 100 * (value - true) / abs(true)
            assert float(row["error_pct"]) == pytest.approx(err, rel=1e-9)
            js = doc["joints"][AXES.index(joint)]
            if name == "f1":
                assert js["first_mode"]["f1_hz"] == value
                continue
            p = js["parameters"][name]
            assert (p["value"], p["truth"]) == (value, true)   # the JSON is the table
            z = (value - true) / float(row["sigma_corrected"])
            assert abs(z) < 3, (joint, name, z)
            if name in ("K", "Jm", "JL"):
                assert abs(err) < 0.5, (joint, name, err)
        assert doc["joints"][AXES.index(joint)]["within_bar"]
    assert doc["accuracy"]["within"] == 2


def test_same_survey_on_two_workers_and_logs_are_simulate_s(surveyed, tmp_path):
    """Same seed, same table and logs, bit for bit, whatever the number of workers; each log
    is `simulate --model arm6 --joint J --seed 1`'s."""
    _, _, out = surveyed
    status, text = _run(ARGS + ["--workers", "2", "--out", str(tmp_path / "two")])
    assert status == 0 and "K, Jm, JL within 0.5 % of the truth: 2 of 2 axes" in text
    for name in ("survey.csv", "logs/axis1.csv", "logs/axis4.csv"):
        assert (tmp_path / "two" / name).read_bytes() == (out / name).read_bytes(), name
    status, _ = _run(["simulate", "--model", "arm6", "--joint", "axis4", "--duration", "60",
                      "--seed", "1", "--quiet", "--out", str(tmp_path / "a4.csv")])
    assert status == 0
    assert (tmp_path / "a4.csv").read_bytes() == (out / "logs" / "axis4.csv").read_bytes()


def test_output_guard_and_bad_input(tmp_path, capsys):
    """A file of that name jointbench did not write is never replaced (exit 2 before any
    simulation); an unknown axis, model or a too short run: exit 2 naming it."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "survey.csv").write_text("my own notes\n")
    status, _ = _run(ARGS + ["--out", str(out)])
    assert status == 2 and (out / "survey.csv").read_text() == "my own notes\n"
    assert not (out / "logs").exists()
    assert "refusing to overwrite" in capsys.readouterr().err
    for argv, word in ((["--joints", "axis9"], "axis9"), (["--model", "nope.xml"], "nope.xml"),
                       (["--duration", "3"], "--duration"), (["--workers", "0"], "--workers")):
        status, _ = _run(["survey", "--out", str(tmp_path / "x"), "--quiet"] + argv)
        assert status == 2, argv
        assert word in capsys.readouterr().err
        assert not (tmp_path / "x").exists()


def test_a_failed_axis_is_reported_and_the_others_written(tmp_path, monkeypatch, capsys):
    """An axis whose simulation fails: its reason in the table, the JSON and on stderr,
    exit 1; the other axis is identified and written."""
    import jointbench.bench.campaign.robot_survey as survey

    real = survey.run_experiment

    def fails_on_axis4(model, joint, **kw):
        if joint == "axis4":
            raise RuntimeError("diverged at t = 1.5 s\nsecond line")
        return real(model, joint, **kw)

    monkeypatch.setattr(survey, "run_experiment", fails_on_axis4)
    out = tmp_path / "out"
    status, text = _run(["survey", "--joints", "axis1,axis4", "--duration", "20", "--seed",
                         "1", "--workers", "1", "--quiet", "--json", "--out", str(out)])
    assert status == 1
    doc = _strict(text)
    assert doc["failed"] == ["axis4"] and doc["joints"][0]["status"] == "ok"
    assert "diverged at t = 1.5 s" in doc["joints"][1]["reason"]
    rows = _table(out)
    assert [r["parameter"] for r in rows if r["joint"] == "axis4"] == [""]
    assert "RuntimeError: diverged at t = 1.5 s second line" in rows[-1]["note"]
    assert (out / "logs" / "axis1.csv").is_file() and not (out / "logs" / "axis4.csv").exists()
    assert "jointbench survey: error: axis4: simulation: RuntimeError" in capsys.readouterr().err
