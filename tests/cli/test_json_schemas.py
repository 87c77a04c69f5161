"""The two faces agree: `jointbench CMD --json` prints what `jointbench.CMD(...).to_json()`
returns (the same dict after a JSON round trip), the text is `.table()`, and both answers
validate against their JSON Schema (docs/schemas/*.schema.json, draft 2020-12).

The command runs in this process (`bench.cli.main`) on small logs: a 20 s experiment, a
two-run campaign of 10 s experiments. The campaign's timings (wall time, per-method time)
and its table path are the only fields two invocations may differ in; they are dropped before
comparing.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path

import pytest

import jointbench as jb
from jointbench.bench.cli import main

jsonschema = pytest.importorskip("jsonschema")

SCHEMAS = Path(__file__).resolve().parents[2] / "docs" / "schemas"


def _schema(name: str) -> dict:
    schema = json.loads((SCHEMAS / f"{name}.schema.json").read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    return schema


def _valid(doc: dict, name: str) -> None:
    jsonschema.Draft202012Validator(_schema(name)).validate(doc)


def _roundtrip(doc: dict) -> dict:
    return json.loads(json.dumps(doc, allow_nan=False, default=float))


def _cli(capsys, *argv: str) -> tuple[int, str]:
    status = main(list(argv))
    return status, capsys.readouterr().out


@pytest.fixture(scope="module")
def logs(tmp_path_factory) -> tuple[str, str]:
    """Two 20 s prototype logs (seeds 1 and 2), written by `jointbench simulate --json`,
    whose answers validate against the simulate schema."""
    folder = tmp_path_factory.mktemp("logs")
    paths = []
    for seed in (1, 2):
        path = str(folder / f"p{seed}.csv")
        printed = io.StringIO()
        with contextlib.redirect_stdout(printed):
            assert main(["simulate", "--duration", "20", "--seed", str(seed), "--quiet",
                         "--json", "--out", path]) == 0
        _valid(json.loads(printed.getvalue()), "simulate")
        paths.append(path)
    return paths[0], paths[1]


def test_identify_json_and_text_are_the_api_s(logs, capsys):
    log, _ = logs
    status, out = _cli(capsys, "identify", log, "--json")
    assert status == 0
    cli = json.loads(out)
    fit = jb.identify(log)
    api = _roundtrip(fit.to_json())
    assert cli == api
    _valid(cli, "identify")
    _valid(api, "identify")
    status, text = _cli(capsys, "identify", log)
    assert text == fit.table() + "\n"


def test_identify_options_reach_the_api(logs, capsys):
    """Filter overrides and a validation log: the same answer through both faces."""
    log, other = logs
    status, out = _cli(capsys, "identify", log, "--fc", "25", "--decimate", "10",
                       "--validate", other, "--json")
    assert status == 0
    cli = json.loads(out)
    fit = jb.identify(log, fc_hz=25, Nd=10, validate=other)
    assert cli == _roundtrip(fit.to_json())
    _valid(cli, "identify")
    assert cli["filter"]["decimate"] == 10
    assert cli["filter"]["wn_rad_s"] == pytest.approx(2 * math.pi * 25, rel=1e-12)
    assert "validation" in cli
    status, text = _cli(capsys, "identify", log, "--fc", "25", "--decimate", "10",
                        "--validate", other)
    assert text == fit.table() + "\n"


def test_fit_parameters_are_what_the_json_reports(logs):
    """Estimate(value, sigma, sigma_hac, unit) holds the JSON's physical value, the paper's
    (white-residual) sigma and the autocorrelation-consistent one, with the unit."""
    fit = jb.identify(logs[0])
    doc = fit.to_json()
    assert set(fit.parameters) == set(doc["physical"])
    for name, e in fit.parameters.items():
        assert isinstance(e, jb.Estimate)
        assert e.value == doc["physical"][name]
        assert e.sigma == doc["physical_sigma"][name]
        assert e.sigma_hac == doc["physical_sigma_corrected"][name]
        assert e.unit == doc["units"][name]
        assert e.sigma_hac > 0 and e.sigma > 0
    assert fit.parameters["K"].unit == "N m/rad"
    assert list(fit.warnings) == doc["warnings"]
    assert list(fit.notes) == doc["notes"]


def test_diagnose_json_and_text_are_the_api_s(logs, capsys):
    log, _ = logs
    status, out = _cli(capsys, "diagnose", log, "--no-forward", "--json")
    assert status == 0
    cli = json.loads(out)
    d = jb.diagnose(log, forward=False)
    api = _roundtrip(d.to_json())
    assert cli == api
    _valid(cli, "diagnose")
    _valid(api, "diagnose")
    status, text = _cli(capsys, "diagnose", log, "--no-forward", "--quiet")
    assert text == d.table() + "\n"


def _without_timing(doc):
    """The summary without what two invocations measure differently: wall and call times,
    and the table path."""
    if isinstance(doc, dict):
        return {k: _without_timing(v) for k, v in doc.items()
                if k not in ("timing", "time_s", "table")}
    if isinstance(doc, list):
        return [_without_timing(v) for v in doc]
    return doc


def test_campaign_json_and_text_are_the_api_s(tmp_path, capsys):
    gates = "K.abs_bias_pct<50, failed==0"
    args = ["campaign", "--runs", "2", "--duration", "10", "--workers", "1", "--quiet",
            "--require", gates, "--out", str(tmp_path / "cli.csv")]
    status, out = _cli(capsys, *args, "--json")
    assert status == 0
    cli = json.loads(out)
    report = jb.campaign(runs=2, duration=10, workers=1, require=gates,
                         out=tmp_path / "api.csv")
    api = _roundtrip(report.to_json())
    assert _without_timing(cli) == _without_timing(api)
    assert cli["table"] == str(tmp_path / "cli.csv") and api["table"] == str(tmp_path / "api.csv")
    assert set(cli["timing"]) == set(api["timing"])
    assert cli["gates"] and all(g["passed"] for g in cli["gates"])
    _valid(cli, "campaign")
    _valid(api, "campaign")
    # the summary file beside the table is the printed object
    assert json.loads((tmp_path / "api.summary.json").read_text()) == api
    # the API on the CLI's finished table resumes it: no run, the same object but timing
    resumed = jb.campaign(runs=2, duration=10, workers=1, require=gates,
                          out=tmp_path / "cli.csv")
    again = _roundtrip(resumed.to_json())
    assert {**again, "timing": None} == {**cli, "timing": None}
    assert again["timing"]["resumed_rows"] == 2
    # the text: the table and timing lines, then the report's table
    status, text = _cli(capsys, *args)
    lines = text.splitlines()
    assert status == 0
    assert lines[0].startswith(f"table: {tmp_path / 'cli.csv'}")
    assert "\n".join(lines[2:]) == resumed.table()


def test_campaign_without_out_keeps_no_table():
    report = jb.campaign(runs=1, duration=6, workers=1, id_models=("joint-motor",))
    doc = _roundtrip(report.to_json())
    assert doc["table"] is None and report.table_path is None
    _valid(doc, "campaign")


def test_import_json_is_the_api_s(logs, tmp_path, capsys):
    """A jointbench log re-imported as is: the same summary both ways."""
    raw = tmp_path / "raw.csv"
    lines = [line for line in Path(logs[0]).read_text().splitlines() if not line.startswith("#")]
    raw.write_text("\n".join(lines[:3000]) + "\n")
    status, out = _cli(capsys, "import", str(raw), "--out", str(tmp_path / "a.csv"), "--json")
    assert status == 0
    cli = json.loads(out)
    report = jb.import_log(raw, tmp_path / "b.csv")
    api = _roundtrip(report.to_json())
    assert {**cli, "out": None} == {**api, "out": None}
    _valid(cli, "import")
    _valid(api, "import")


def test_survey_json_and_text_are_the_api_s(tmp_path, capsys):
    """One axis of the arm, 10 s: the same answer but for wall times and the folder."""
    args = ["survey", "--joints", "axis1", "--duration", "10", "--workers", "1", "--quiet"]
    status, out = _cli(capsys, *args, "--json", "--out", str(tmp_path / "cli"))
    assert status == 0
    cli = json.loads(out)
    sv = jb.survey("arm6", ["axis1"], duration=10, workers=1, out=tmp_path / "api")
    api = _roundtrip(sv.to_json())
    _valid(cli, "survey")
    _valid(api, "survey")

    def same(doc):
        doc = {k: v for k, v in doc.items() if k not in ("wall_s", "out", "files")}
        doc["joints"] = [{k: v for k, v in j.items() if k not in ("sim_s", "identify_s", "log")}
                         for j in doc["joints"]]
        return doc
    assert same(cli) == same(api)
    assert api["out"] == str(tmp_path / "api") and (tmp_path / "api" / "survey.csv").exists()
    # the text is the result's table but for the wall-time line and the folder's name
    status, text = _cli(capsys, *args, "--out", str(tmp_path / "api2"))
    table = sv.table().replace(str(tmp_path / "api"), str(tmp_path / "api2"))
    keep = [line for line in table.splitlines() if not line.startswith("wall time")]
    assert [line for line in text.splitlines() if not line.startswith("wall time")] == keep



def test_several_runs_json_is_the_api_s(logs, capsys):
    """`identify A B --json` equals `jb.identify([A, B]).to_json()`; the answer validates
    against identify_runs.schema.json and each run's answer against identify.schema.json; the
    pooled K lies between the two runs' K (an inverse-variance mean can lie nowhere else)."""
    a, b = logs
    status, out = _cli(capsys, "identify", a, b, "--json")
    assert status == 0
    cli = json.loads(out)
    api = _roundtrip(jb.identify([a, b]).to_json())
    assert cli == api
    _valid(cli, "identify_runs")
    for run in cli["runs"]:
        _valid(run, "identify")
    ks = [run["physical"]["K"] for run in cli["runs"]]
    assert min(ks) <= cli["pooled"]["K"]["value"] <= max(ks)


def test_several_files_import_json_is_the_api_s(logs, tmp_path, capsys):
    """`import A B --out DIR --json` prints a list of the import objects, the API's
    `[r.to_json() for r in import_log([a, b], DIR)]`, but for the folder; the list validates
    against import_many.schema.json and each object against import.schema.json."""
    raws = []
    for i, log in enumerate(logs):
        lines = [ln for ln in Path(log).read_text().splitlines() if not ln.startswith("#")]
        raws.append(tmp_path / f"raw{i}.csv")
        raws[-1].write_text("\n".join(lines[:2000]) + "\n")
    status, out = _cli(capsys, "import", *map(str, raws), "--out", str(tmp_path / "cli"),
                       "--json")
    assert status == 0
    cli = json.loads(out)
    api = [_roundtrip(r.to_json()) for r in jb.import_log(raws, tmp_path / "api")]
    assert [d["out"] for d in cli] == [str(tmp_path / "cli" / f"raw{i}.csv") for i in (0, 1)]
    assert [{**d, "out": None} for d in cli] == [{**d, "out": None} for d in api]
    _valid(cli, "import_many")
    _valid(api, "import_many")
    for doc in cli:
        _valid(doc, "import")


@pytest.mark.slow
def test_several_runs_diagnose_json_is_the_api_s(logs, capsys):
    """`diagnose A B --json` equals `jb.diagnose([A, B]).to_json()`; it validates against
    diagnose_runs.schema.json and each run's object against diagnose.schema.json; each run is
    cross-validated on the other, and the evidence holds every run's own test of each cause
    any run names."""
    a, b = logs
    status, out = _cli(capsys, "diagnose", a, b, "--no-forward", "--json")
    assert status == 0
    cli = json.loads(out)
    api = _roundtrip(jb.diagnose([a, b], forward=False).to_json())
    assert cli == api
    _valid(cli, "diagnose_runs")
    for run, other in zip(cli["runs"], (b, a)):
        _valid(run, "diagnose")
        assert run["cross_validation"]["file"] == other
    named = {c for run in cli["runs"] for c in run["named_causes"]}
    assert set(cli["evidence"]) == named
    for cause, rows in cli["evidence"].items():
        assert [r["run"] for r in rows] == [a, b]
        assert [r["named"] for r in rows] == [cause in run["named_causes"]
                                              for run in cli["runs"]]
