"""One output rule everywhere: survey's sub-folders (links followed), the API's `write_log` and
`Fit.plot`, and every log read back by the reader before it counts as written. A foreign file
is never replaced: the CLI exits 2 and the API raises, for the same reason."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest

import jointbench as jb
from jointbench.bench.cli import main
from jointbench.bench.output_files import OutputError, OutputFolder
from jointbench.identification.log import LogError, read_log

FOREIGN = "a user's own file\n"


@pytest.fixture(scope="module")
def short_log():
    return jb.simulate("prototype", duration=10.0, seed=3)


def _foreign(path: Path) -> Path:
    path.write_text(FOREIGN)
    return path


def test_survey_refuses_a_symlinked_logs_folder(tmp_path, capsys):
    """`survey --out DIR` with DIR/logs a link to the user's folder: refused before any run,
    the user's axis1.csv untouched (the check follows the link)."""
    user = tmp_path / "user"
    user.mkdir()
    mine = _foreign(user / "axis1.csv")
    out = tmp_path / "sv"
    out.mkdir()
    os.symlink(user, out / "logs")
    code = main(["survey", "--model", "prototype", "--duration", "10", "--out", str(out),
                 "--workers", "1", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert "symbolic link" in err and "logs" in err
    assert mine.read_text() == FOREIGN
    assert sorted(p.name for p in user.iterdir()) == ["axis1.csv"]


def test_output_folder_refuses_a_file_where_its_sub_folder_goes(tmp_path):
    out = tmp_path / "sv"
    out.mkdir()
    _foreign(out / "logs")
    with pytest.raises(OutputError, match="not a folder"):
        OutputFolder(out, ("survey.csv", "logs/*"))
    assert (out / "logs").read_text() == FOREIGN


def test_output_folder_checks_links_again_when_writing(tmp_path):
    """A link put in place during the computation is refused before a file is written."""
    user = tmp_path / "user"
    user.mkdir()
    out = tmp_path / "sv"
    folder = OutputFolder(out, ("survey.csv", "logs/*"))
    out.mkdir()
    os.symlink(user, out / "logs")
    with pytest.raises(OutputError, match="symbolic link"):
        with folder.writing() as path:
            (path / "logs" / "axis1.csv").write_text("never")
    assert list(user.iterdir()) == []


@pytest.mark.parametrize("surface", ["cli", "api"])
def test_write_log_never_replaces_a_foreign_file(surface, short_log, tmp_path, capsys):
    """`simulate --out foreign.txt` exits 2; `jb.write_log(log, "foreign.txt")` raises, for
    the same reason; the file is untouched either way."""
    target = _foreign(tmp_path / "foreign.txt")
    if surface == "cli":
        assert main(["simulate", "--model", "prototype", "--duration", "10",
                     "--out", str(target)]) == 2
        message = capsys.readouterr().err
    else:
        with pytest.raises(OutputError) as err:
            jb.write_log(short_log, target)
        message = str(err.value)
    assert "refusing to overwrite" in message and "foreign.txt" in message
    assert target.read_text() == FOREIGN


def test_fit_plot_never_replaces_a_foreign_file(short_log, tmp_path):
    target = _foreign(tmp_path / "foreign.png")
    fit = jb.identify(short_log)
    with pytest.raises(OutputError, match="refusing to overwrite"):
        fit.plot(target)
    assert target.read_text() == FOREIGN
    fit.plot(tmp_path / "fit.png")            # a new file: written
    assert (tmp_path / "fit.png").stat().st_size > 0


def test_write_log_replaces_its_own_log(short_log, tmp_path):
    path = tmp_path / "log.csv"
    jb.write_log(short_log, path)
    jb.write_log(short_log, path)             # ours: replaced
    back = read_log(path)
    # 12 significant digits written: relative error at most 5e-12
    np.testing.assert_allclose(back.tau_m, short_log.tau_m, rtol=5e-12, atol=0)


@pytest.mark.parametrize("change, message", [
    ({"meta": {"joint": "axis1\nsample_rate_hz: 5"}}, "line break"),
    ({"meta": {"bad:key": "1"}}, "cannot be written"),
    ({"q_m": "nan"}, "holds nan at sample 0"),
    ({"tau_m": "short"}, "1-D arrays of one length"),
    # the reader refuses a metadata rate 10 % off t: read back before the file counts
    ({"meta": {"sample_rate_hz": "385"}}, "would not read back"),
])
def test_write_log_refuses_what_the_reader_would_refuse(change, message, short_log, tmp_path):
    """A line break in the metadata, NaN samples, columns of different lengths and anything
    else the reader refuses: LogError naming it, and no file left behind."""
    kw = {}
    for key, value in change.items():
        if key == "meta":
            kw["meta"] = {**short_log.meta, **value}
        elif value == "nan":
            kw[key] = np.full_like(short_log.q_m, np.nan)
        else:
            kw[key] = short_log.tau_m[:-1]
    log = dataclasses.replace(short_log, **kw)
    path = tmp_path / "out.csv"
    with pytest.raises(LogError, match=message):
        jb.write_log(log, path)
    assert list(tmp_path.iterdir()) == []
