"""A campaign resumes only rows it wrote (bench/campaign/table.py, run.expected_cells): a cell
that is not a number, a status the campaign does not write, a truth or a setting that is not
the spec's, or any edit the row's digest does not match refuses the resume (exit 2, or
CampaignError from the API) naming the line, the run and the column, and leaves the table
untouched. An untouched table resumes with no run repeated.

One reference table of two 5 s runs (joint-motor model and a constant plug-in), copied and
edited per test."""

from __future__ import annotations

import csv
import io
import json
import shutil
import textwrap
from pathlib import Path

import pytest

import jointbench as jb
from jointbench.bench.campaign.settings import CampaignError
from jointbench.bench.campaign.table import DIGEST, row_digest
from jointbench.bench.cli import main


def _args(folder: Path, out: Path) -> list[str]:
    return ["campaign", "--runs", "2", "--duration", "5", "--workers", "1", "--quiet",
            "--id-models", "joint-motor", "--method", f"const={folder / 'plug.py'}:f",
            "--out", str(out)]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    folder = tmp_path_factory.mktemp("resume")
    (folder / "plug.py").write_text(textwrap.dedent("""
        def f(log):
            return {"K": (2.0e4, 50.0)}
    """))
    out = folder / "ref.csv"
    assert main(_args(folder, out)) == 0
    return folder, out


def _edit(reference, tmp_path: Path, column: str, value, *, redigest: bool = False,
          row: int = 0) -> Path:
    """A copy of the reference table with `column` of data row `row` set to `value` (a
    callable maps the old text); `redigest`: the row's digest recomputed, as someone who
    knows the rule would."""
    folder, out = reference
    lines = out.read_text().split("\n")
    header = next(csv.reader([lines[2]]))
    cells = next(csv.reader([lines[3 + row]]))
    i = header.index(column)
    cells[i] = value(cells[i]) if callable(value) else value
    if redigest:
        cells[-1] = row_digest(_spec_of(out), cells[:-1])
    buf = io.StringIO()
    csv.writer(buf, lineterminator="").writerow(cells)
    lines[3 + row] = buf.getvalue()
    edited = tmp_path / "edited.csv"
    edited.write_text("\n".join(lines))
    return edited


def _spec_of(out: Path):
    """The spec of the table's `# spec:` line, its methods included."""
    from jointbench.bench.campaign.methods import MethodsSpec
    from jointbench.bench.campaign.spec import spec_from_json

    line = out.read_text().split("\n")[1][len("# spec: "):]
    d = json.loads(line)
    base = spec_from_json(line)
    return MethodsSpec(**{f: getattr(base, f) for f in ("base", "runs", "seed", "sweep",
                                                         "values", "model_sha256")},
                       methods=tuple(d["methods"]))


def _refused(reference, edited: Path, capsys) -> str:
    before = edited.read_bytes()
    rc = main(_args(reference[0], edited))
    err = capsys.readouterr().err
    assert rc == 2, err
    assert "Traceback" not in err and edited.read_bytes() == before   # never touched
    return err


def test_an_untouched_table_resumes_with_no_run_repeated(reference, tmp_path, capsys):
    folder, out = reference
    copy = tmp_path / "copy.csv"
    shutil.copy(out, copy)
    assert main(_args(folder, copy) + ["--json"]) == 0
    timing = json.loads(capsys.readouterr().out)["timing"]
    assert timing["resumed_rows"] == 2 and timing["runs_this_invocation"] == 0
    assert copy.read_bytes() == out.read_bytes()


@pytest.mark.parametrize("column, value, named", [
    ("jm.K", "abc", "column 'jm.K': 'abc' is not a number"),
    ("jm.K", "inf", "column 'jm.K': 'inf' is not a number"),
    ("jm.K", "1_000", "column 'jm.K': '1_000' is not a number"),
    ("jm.K", "nan", "column 'digest': the row's cells do not match it"),
    ("jm.K", "", "column 'digest': the row's cells do not match it"),
    ("jm.K", lambda v: repr(float(v) * 1.001), "column 'digest': the row's cells do not match"),
    ("const.K.sigma", "5.0", "column 'digest': the row's cells do not match it"),
    ("truth.K", "1", "column 'truth.K': '1' is not this campaign's value for run 0 "
                     "('20341.0458')"),
    ("noise", "2.0", "column 'noise': '2.0' is not this campaign's value for run 0 ('1.0')"),
    ("status", "done", "column 'status': 'done' is not a status the campaign writes"),
    ("const.status", "fine", "column 'const.status': 'fine' is not a status"),
])
def test_an_edited_row_refuses_the_resume_naming_row_and_column(reference, tmp_path, capsys,
                                                                  column, value, named):
    edited = _edit(reference, tmp_path, column, value)
    err = _refused(reference, edited, capsys)
    assert f"edited.csv:4: run 0: {named}" in err
    assert "delete this line to have the run done again" in err


@pytest.mark.parametrize("column, value, named", [
    ("truth.K", "1", "column 'truth.K': '1' is not this campaign's value"),
    ("truth.JL", lambda v: repr(float(v) * 1.01), "column 'truth.JL'"),
    ("seed", "12345", "column 'seed': '12345' is not this campaign's value"),
])
def test_a_recomputed_digest_does_not_hide_a_wrong_truth_or_setting(reference, tmp_path,
                                                                    capsys, column, value,
                                                                    named):
    edited = _edit(reference, tmp_path, column, value, redigest=True)
    err = _refused(reference, edited, capsys)
    assert f"edited.csv:4: run 0: {named}" in err


def test_the_api_refuses_an_edited_table(tmp_path):
    out = tmp_path / "api.csv"
    settings = dict(runs=2, duration=5, workers=1, id_models=["joint-motor"], out=out)
    jb.campaign(**settings)
    edited = _edit((tmp_path, out), tmp_path, "jm.K", lambda v: repr(float(v) * 0.999), row=1)
    shutil.move(edited, out)
    before = out.read_bytes()
    with pytest.raises(CampaignError, match=r"api.csv:5: run 1: column 'digest': the row's "
                                            r"cells do not match it"):
        jb.campaign(**settings)
    assert out.read_bytes() == before


def test_a_table_without_digests_is_not_resumed(reference, tmp_path, capsys):
    _, out = reference
    lines = out.read_text().split("\n")
    lines[0] = "# jointbench-campaign: 1"
    old = tmp_path / "edited.csv"
    old.write_text("\n".join(lines))
    err = _refused(reference, old, capsys)
    assert "edited.csv:1: a campaign table of an earlier format (rows without a digest)" in err


def test_every_written_row_carries_its_digest(reference):
    from jointbench.bench.campaign.table import read_table

    folder, out = reference
    spec = _spec_of(out)
    header = out.read_text().split("\n")[2].split(",")
    assert header[-1] == DIGEST
    _, rows = read_table(out)
    for row in rows:
        cells = [row[c] for c in header]
        assert row[DIGEST] == row_digest(spec, cells[:-1])


def test_scattered_runs_with_an_effect_resume_and_check_their_own_truth(tmp_path, capsys):
    """Each run's truth is its own scattered model's (with the hidden effect): the rows the
    campaign wrote pass the check; another run's truth in a row does not."""
    out = tmp_path / "sc.csv"
    args = ["campaign", "--runs", "2", "--duration", "5", "--workers", "1", "--quiet",
            "--id-models", "joint-motor", "--scatter", "0.1", "--effect", "backlash=0.002",
            "--out", str(out)]
    assert main(args) == 0
    capsys.readouterr()
    assert main(args + ["--json"]) == 0
    assert json.loads(capsys.readouterr().out)["timing"]["runs_this_invocation"] == 0
    lines = out.read_text().split("\n")
    header = next(csv.reader([lines[2]]))
    first, second = (next(csv.reader([line])) for line in lines[3:5])
    i = header.index("truth.K")
    assert first[i] != second[i]                 # two scatter draws
    first[i] = second[i]                         # run 1's truth in run 0's row
    buf = io.StringIO()
    csv.writer(buf, lineterminator="").writerow(first)
    lines[3] = buf.getvalue()
    out.write_text("\n".join(lines))
    assert main(args) == 2
    err = capsys.readouterr().err
    assert f"sc.csv:4: run 0: column 'truth.K': '{second[i]}' is not this campaign's value" in err
