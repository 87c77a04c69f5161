"""`jointbench import`: nothing plausible and wrong passes silently. Each case exits 2 naming
the option, file, line or column, or exits 0 with a warning naming the problem; the memory
limit JOINTBENCH_MAX_MEMORY_MB holds before or while the file is read."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from jointbench.bench.cli import main
from jointbench.bench.cli.import_memory import BASE_MB, BYTES_PER_VALUE, budget_values
from jointbench.identification.log import read_log
from jointbench.identification.log.raw import parse_raw

MAP = ["--map", "t=time,q_m=motor,q=link,tau_m=cur"]
RATE_HZ = 350.0


def raw_text(n: int = 700, time_scale: float = 1.0, header: bool = True) -> str:
    """A drive file at RATE_HZ: time [s] x time_scale, motor and link angles [rad], a torque."""
    t = np.arange(n) / RATE_HZ
    q = 0.2 * np.sin(2 * math.pi * 1.5 * t)
    tau = 50 * np.cos(2 * math.pi * 1.5 * t) + np.sin(2 * math.pi * 7 * t)
    rows = [f"{ti * time_scale:.9g},{qi * 1.001:.9g},{qi:.9g},{ci:.9g}"
            for ti, qi, ci in zip(t, q, tau)]
    return ("time,motor,link,cur\n" if header else "") + "\n".join(rows) + "\n"


@pytest.fixture
def raw(tmp_path) -> Path:
    path = tmp_path / "raw.csv"
    path.write_text(raw_text())
    return path


def run(capsys, *args) -> tuple[int, str]:
    code = main(["import", *map(str, args)])
    return code, capsys.readouterr().err


def test_the_reference_file_imports(raw, tmp_path, capsys):
    code, err = run(capsys, raw, "--out", tmp_path / "o.csv", *MAP)
    assert code == 0 and "warning" not in err
    assert read_log(tmp_path / "o.csv").sample_rate_hz == pytest.approx(RATE_HZ, rel=1e-6)


def test_seconds_declared_ms_warns_of_the_unit_slip(raw, tmp_path, capsys):
    """Time in s declared ms: 350 kHz, beyond what a drive logs; the warning names the time
    column and the unit that gives the drive's rate."""
    code, err = run(capsys, raw, "--out", tmp_path / "o.csv", *MAP, "--units", "t=ms")
    assert code == 0
    assert "350000 Hz" in err and "--units t=s" in err and "'time'" in err
    assert "a rate of 350 Hz" in err


@pytest.mark.parametrize("args, message", [
    (["--map", "t=time,q_m=motor,q_m=link,tau_m=cur"], "'q_m' is given twice"),
    ([*MAP, "--units", "t=s,t=ms"], "'t' is given twice"),
    (["--map", "t=time,q_m=motor,q=motor,tau_m=cur"], "one raw column for two log columns"),
    ([*MAP, "--meta", "torque_noise_std=0.1", "--meta", "torque_noise_std=0.2"],
     "already given"),
    ([*MAP, "--joint", "axis1", "--meta", "joint=axis2"], "already given"),
    ([*MAP, "--meta", "torque_noise_std=-0.5"], "'torque_noise_std' must be >= 0"),
    ([*MAP, "--meta", "motor_encoder_resolution_rad=-1e-5"], "must be >= 0"),
    ([*MAP, "--gear-ratio", "1e-300"], "over 1e+12 in magnitude"),
    ([*MAP, "--gear-ratio", "1e300"], "over 1e+12 in magnitude"),
    ([*MAP, "--joint", "axis1\nsample_rate_hz: 5"], "line break"),
    ([*MAP, "--meta", "note=a\rb"], "line break"),
    ([*MAP, "--delimiter", ""], "--delimiter ''"),
    ([*MAP, "--delimiter", "."], "--delimiter '.'"),
    ([*MAP, "--rate", "1e-300"], "--rate 1e-300: must lie in [10, 1e+06] Hz"),
    ([*MAP, "--gravity", "1e300"], "'gravity' = 1e+300 is outside [0, 100]"),
    ([*MAP, "--kv", "-3"], "'kv' = -3 is outside"),
    ([*MAP, "--meta", "kp=-1"], "'kp' = -1 is outside"),
])
def test_refused_options_name_the_problem(args, message, raw, tmp_path, capsys):
    out = tmp_path / "o.csv"
    code, err = run(capsys, raw, "--out", out, *args)
    assert code == 2, err
    assert message in err
    assert "Traceback" not in err and not out.exists()


@pytest.mark.parametrize("cell, shown", [("1_000", "1_000"), ("\u0661.5", "\u0661.5"),
                                         ("1e300", None)])
def test_cells_read_as_the_log_reader_reads_them(cell, shown, raw, tmp_path, capsys):
    """A digit separator and Arabic-Indic digits are refused as the reader refuses them; a
    cell past the reader's 1e12 is refused at import, naming the line, not after "log checks
    passed"."""
    lines = raw.read_text().splitlines()
    cells = lines[5].split(",")
    cells[1] = cell
    lines[5] = ",".join(cells)
    raw.write_text("\n".join(lines) + "\n")
    code, err = run(capsys, raw, "--out", tmp_path / "o.csv", *MAP)
    assert code == 2
    assert ":6:" in err and "'motor'" in err
    assert (f"not a number: '{shown}'" in err) if shown else "over 1e+12" in err


def test_a_file_without_header_is_named_as_such(tmp_path, capsys):
    path = tmp_path / "noheader.csv"
    path.write_text(raw_text(header=False))
    code, err = run(capsys, path, "--out", tmp_path / "o.csv", *MAP)
    assert code == 2
    assert "first row must be the header" in err and "duplicate" not in err


def test_parse_raw_holds_8_bytes_a_value():
    """The table streams into float arrays (not lists of Python floats): its data is
    rows x columns float64, its line numbers int64."""
    text = raw_text(50)
    table = parse_raw(enumerate(text.splitlines(), start=1), "raw.csv")
    assert table.data.dtype == np.float64 and table.data.shape == (50, 4)
    assert table.lines.dtype == np.int64 and table.lines[0] == 2


def test_import_refuses_a_file_over_the_memory_limit_before_reading_it(tmp_path, capsys,
                                                                       monkeypatch):
    """8 M rows under a 500 MB limit: the file's size says so before it is read. The file is
    sparse past its head (a read of it would find NUL bytes and refuse another way)."""
    monkeypatch.setenv("JOINTBENCH_MAX_MEMORY_MB", "500")
    head = raw_text(2000)
    per_row = len(head) / 2001
    path = tmp_path / "huge.csv"
    with open(path, "w") as f:
        f.write(head)
        f.truncate(int(8e6 * per_row))
    code, err = run(capsys, path, "--out", tmp_path / "o.csv", *MAP)
    assert code == 2
    assert "over the 500 MB memory limit" in err and "JOINTBENCH_MAX_MEMORY_MB" in err
    estimate = float(err.split("holds about ")[1].split(" values")[0])
    assert estimate == pytest.approx(8e6 * 4, rel=0.05)


def test_import_from_a_pipe_stops_at_the_memory_limit(tmp_path):
    """A pipe has no size: the values are counted as they are read, and the import stops when
    they pass what the limit allows."""
    limit = BASE_MB + 1.0      # room for 1 MB of values: 16384 values, 4096 rows of 4
    rows = 3 * budget_values(limit) // 4   # 3 times as many rows
    text = raw_text(rows)
    proc = subprocess.run([sys.executable, "-m", "jointbench.bench.cli", "import",
                           "/dev/stdin", "--out", str(tmp_path / "o.csv"), *MAP], input=text,
                          text=True, capture_output=True, timeout=120,
                          env={**os.environ, "JOINTBENCH_MAX_MEMORY_MB": str(limit)})
    assert proc.returncode == 2, proc.stderr
    assert f"the input passes {budget_values(limit):,} values" in proc.stderr
    assert f"{BYTES_PER_VALUE} bytes each" in proc.stderr
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize("key", ["torque_noise_std", "motor_encoder_resolution_rad",
                                 "link_encoder_resolution_rad"])
def test_the_reader_refuses_a_negative_sensor_value(key, tmp_path, capsys):
    """A negative noise level or encoder step (a replica spread of 0 under --debias) is
    refused by the reader too, naming the key and its line."""
    path = tmp_path / "o.csv"
    assert run(capsys, _raw(tmp_path), "--out", path, *MAP)[0] == 0
    text = path.read_text().replace("# source:", f"# {key}: -0.5\n# source:", 1)
    path.write_text(text)
    line = text.splitlines().index(f"# {key}: -0.5") + 1
    code, err = run_identify(capsys, path)
    assert code == 2
    assert f"o.csv:{line}: metadata '{key}' must be >= 0" in err


def _raw(tmp_path: Path) -> Path:
    path = tmp_path / "raw.csv"
    path.write_text(raw_text())
    return path


def run_identify(capsys, path: Path) -> tuple[int, str]:
    code = main(["identify", str(path)])
    return code, capsys.readouterr().err
