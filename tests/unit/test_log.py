"""The log format of docs/log-format.md: round trip and errors that name line and column."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from jointbench.identification import log as log_module
from jointbench.identification.log import read as log_read, write as log_write
from jointbench.identification.log import (Log, LogError, atomic_write_text, parse_log, read_log,
                                unit_warnings, write_log)

GOOD = """# jointbench-log: 1
# sample_rate_hz: 100
# kp: 40.0
t,q_m,q,tau_m,q_ref
0.00,0.0,0.0,1.0,0.0
0.01,0.1,0.1,2.0,0.1
0.02,0.2,0.2,3.0,0.2
0.03,0.3,0.3,4.0,0.3
"""


def test_round_trip_is_exact(tmp_path):
    t = np.arange(50) / 350.87
    log = Log(t=t, q_m=np.sin(t), tau_m=np.cos(t) * 1e3, q=np.sin(t) * 0.9, q_ref=t,
              extra={"true_tau": t * 2}, meta={"sample_rate_hz": "350.87", "seed": "3"})
    path = tmp_path / "x.csv"
    write_log(log, path)
    back = read_log(path)
    for name in ("t", "q_m", "tau_m", "q", "q_ref"):
        np.testing.assert_allclose(getattr(back, name), getattr(log, name), rtol=1e-11)
    np.testing.assert_allclose(back.extra["true_tau"], t * 2, rtol=1e-11)
    assert back.meta["seed"] == "3" and back.sample_rate_hz == pytest.approx(350.87)
    assert not list(tmp_path.glob(".*tmp"))  # the atomic write leaves no temporary file


def test_parse_good():
    log = parse_log(GOOD, "good.csv")
    assert len(log) == 4 and log.meta_float("kp") == 40.0 and log.q is not None


@pytest.mark.parametrize("text, match", [
    (GOOD.replace("t,q_m,q,tau_m,q_ref", "t,q,tau_m,q_ref"), r"good.csv:4: column 'q_m'"),
    (GOOD.replace("0.1,0.1,2.0", "0.1,abc,2.0"), r"good.csv:6: column 'q': not a number: 'abc'"),
    (GOOD.replace("0.2,0.2,3.0", "0.2,nan,3.0"), r"good.csv:7: column 'q': non-finite"),
    (GOOD.replace("0.02,0.2", "0.01,0.2"), r"good.csv:7: column 't': t is not strictly"),
    (GOOD.replace("0.03,0.3", "0.035,0.3"), r"good.csv:8: column 't': irregular sampling"),
    (GOOD.replace("sample_rate_hz: 100", "sample_rate_hz: 350"), "contradicts t"),
    (GOOD.replace("# kp: 40.0", "# kp 40.0"), r"good.csv:3: metadata line"),
    (GOOD.replace("0.1,0.1,2.0,0.1", "0.1,0.1,2.0"), r"good.csv:6: expected 5 cells"),
    ("", "empty file"),
    ("# only: metadata\n", "no header row"),
])
def test_bad_logs_name_line_and_column(text, match):
    with pytest.raises(LogError, match=match):
        parse_log(text, "good.csv")


def test_binary_and_missing_files(tmp_path):
    binary = tmp_path / "b.csv"
    binary.write_bytes(b"\x00\x01\x02t,q_m")
    with pytest.raises(LogError, match="binary"):
        read_log(binary)
    with pytest.raises(LogError, match="no such file"):
        read_log(tmp_path / "none.csv")


# --- every malformed log gets one clear error (docs/log-format.md, issue 5) -----------------

@pytest.mark.parametrize("text, match", [
    (GOOD.replace("0.1,0.1,2.0", "0.1,,2.0"), r"good.csv:6: column 'q': empty cell"),
    (GOOD.replace("0.2,0.2,3.0", "0.2,inf,3.0"), r"good.csv:7: column 'q': non-finite"),
    (GOOD.replace("0.2,0.2,3.0", "0.2,1e999,3.0"), r"good.csv:7: column 'q': non-finite"),
    (GOOD.replace("0.00,0.0,0.0,1.0", "nan,0.0,0.0,1.0"), r"good.csv:5: column 't': non-finite"),
    (GOOD.replace("t,q_m,q,tau_m,q_ref", "t;q_m;q;tau_m;q_ref"),
     r"good.csv:4: .*separated by ';'"),
    (GOOD.replace("t,q_m,q,tau_m,q_ref\n", ""), r"good.csv:4: the first row .* must be the header"),
    (GOOD.replace("tau_m", "tau"), r"good.csv:4: column 'tau_m': required column missing .*'tau'"),
    (GOOD.replace("q_m,q,tau_m", "Q_M,q,tau_m"), r"column 'q_m': .*is 'Q_M' meant"),
    (GOOD.replace("q_m,q,tau_m", "q_m,q_m,tau_m"), r"good.csv:4: column 'q_m': duplicate"),
    (GOOD.replace("sample_rate_hz: 100", "sample_rate_hz: fast"),
     r"good.csv:2: metadata 'sample_rate_hz' must be a number"),
    (GOOD.replace("sample_rate_hz: 100", "sample_rate_hz: -100"),
     r"good.csv:2: metadata 'sample_rate_hz' must be positive"),
    (GOOD.replace("sample_rate_hz: 100", "sample_rate_hz: 350"),
     r"good.csv:2: metadata sample_rate_hz 350 contradicts t"),
    (GOOD.replace("# kp: 40.0", "# tau_max: nan"),
     r"good.csv:3: metadata 'tau_max' must be finite"),
    (GOOD.replace("# kp: 40.0", "# velocity_feedforward: maybe"), r"good.csv:3: .*true or false"),
    (GOOD.replace("# kp: 40.0", "# : 40.0"), r"good.csv:3: metadata line has no key"),
    (GOOD.replace("# kp: 40.0", "# sample_rate_hz: 99"),
     r"good.csv:3: metadata 'sample_rate_hz' given twice"),
    (GOOD.replace("jointbench-log: 1", "jointbench-log: 7"), r"good.csv:1: format version '7'"),
    (GOOD.split("0.00,")[0], r"good.csv:4: no data rows"),
    (GOOD.replace("0.02,0.2,0.2,3.0,0.2\n0.03,0.3,0.3,4.0,0.3\n", ""), r"good.csv: only 2 samples"),
    # a blank line inside the data keeps the line numbers right
    (GOOD.replace("0.02,0.2", "\n0.01,0.2"), r"good.csv:8: column 't': t is not strictly"),
    ("\n\n  \n", "empty file"),
])
def test_more_bad_logs_name_line_and_column(text, match):
    with pytest.raises(LogError, match=match):
        parse_log(text, "good.csv")


def test_line_ends_bom_and_blank_lines_are_accepted():
    text = "\ufeff" + GOOD.replace("\n", "\r\n").replace("0.02,", "\r\n0.02,")
    log = parse_log(text, "good.csv")
    np.testing.assert_array_equal(log.t, [0.0, 0.01, 0.02, 0.03])
    assert log.meta_lines["kp"] == 3


def test_metadata_errors_found_later_name_their_line():
    log = parse_log(GOOD.replace("# kp: 40.0", "# kp: 40.0\n# seed: x"), "good.csv")
    assert log.meta["seed"] == "x"  # unknown to the analyses: kept as text
    with pytest.raises(LogError, match=r"good.csv:4: metadata 'seed' must be a number"):
        log.meta_float("seed")


def test_binary_files_name_the_line(tmp_path):
    nul = tmp_path / "nul.csv"
    nul.write_bytes(GOOD.replace("0.1,0.1,2.0", "0.1,0.1\x002.0").encode())
    with pytest.raises(LogError, match=r"nul.csv:6: binary file \(NUL byte"):
        read_log(nul)
    latin = tmp_path / "latin.csv"
    latin.write_bytes(GOOD.replace("# kp: 40.0", "# operator: J\xe9r\xf4me").encode("latin-1"))
    with pytest.raises(LogError, match=r"latin.csv:3: not UTF-8 text"):
        read_log(latin)
    with pytest.raises(LogError, match=r"nul.csv:6: binary"):
        parse_log(nul.read_text(), nul)


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
def test_endless_binary_stream_is_refused_at_line_1():
    """/dev/zero has no end: a loader that reads the whole file first never returns."""
    with pytest.raises(LogError, match=r"/dev/zero:1: binary"):
        read_log("/dev/zero")


def test_size_limit_is_documented_and_configurable(tmp_path, monkeypatch):
    path = tmp_path / "big.csv"
    rows = "\n".join(f"{k / 100:.2f},{k},{k}" for k in range(2000))
    path.write_text(f"t,q_m,tau_m\n{rows}\n")
    size = path.stat().st_size
    assert len(read_log(path)) == 2000
    with pytest.raises(LogError, match=r"big.csv: the file is .* over the 1 KiB limit .*"
                                       r"JOINTBENCH_MAX_LOG_BYTES"):
        read_log(path, max_bytes=1024)
    monkeypatch.setenv(log_module.MAX_BYTES_ENV, "1K")
    with pytest.raises(LogError, match="over the 1 KiB limit"):
        read_log(path)
    monkeypatch.setenv(log_module.MAX_BYTES_ENV, str(size))
    assert len(read_log(path)) == 2000
    monkeypatch.setenv(log_module.MAX_BYTES_ENV, "lots")
    with pytest.raises(ValueError, match="JOINTBENCH_MAX_LOG_BYTES: 'lots' is not a size"):
        read_log(path)
    assert log_module.DEFAULT_MAX_BYTES == 512 * 2**20
    assert log_module.parse_size("2G") == 2 * 2**30 and log_module.parse_size("64MiB") == 2**26


def test_stream_without_size_is_cut_at_the_limit():
    """A pipe or device has no size to check first: the count of bytes read stops it."""
    body = b"t,q_m,tau_m\n" + b"".join(b"%d,0,0\n" % k for k in range(10000))
    lines = log_read._stream_lines(io.BytesIO(body), "pipe", max_bytes=1000)
    with pytest.raises(LogError, match=r"pipe:\d+: the file is larger than the 1000 bytes"):
        list(lines)


def test_overlong_line_is_refused(tmp_path):
    path = tmp_path / "long.csv"
    path.write_text("t,q_m,tau_m\n" + "1" * (log_module.MAX_LINE_BYTES + 10))
    with pytest.raises(LogError, match=r"long.csv:2: line longer than 64 KiB"):
        read_log(path)


def test_read_log_streams(tmp_path, monkeypatch):
    """The loader never reads the whole file at once (read_bytes, read_text, read())."""
    path = tmp_path / "x.csv"
    path.write_text(GOOD)
    for name in ("read_bytes", "read_text"):
        monkeypatch.setattr(Path, name, lambda *a, **k: pytest.fail("whole-file read"))
    assert len(read_log(path)) == 4


def test_directory_and_unreadable(tmp_path):
    with pytest.raises(LogError, match="is a directory"):
        read_log(tmp_path)


def test_degrees_warning():
    t = np.arange(400) / 350.87
    rad = 0.1 * np.sin(2 * np.pi * t)
    ok = Log(t=t, q_m=rad, tau_m=t, q=rad, path="rad.csv")
    assert unit_warnings(ok) == []
    wide = Log(t=t, q_m=5 * rad, tau_m=t, path="wide.csv")  # +-0.5 rad: a wide experiment
    assert unit_warnings(wide) == []
    # the same +-0.1 rad chirp written in degrees: +-5.7, a span of 1.8 turns if radians
    deg = Log(t=t, q_m=np.degrees(rad), tau_m=t, q=np.degrees(rad), path="deg.csv")
    (text,) = unit_warnings(deg)
    assert text.startswith("deg.csv: 'q_m' spans 11.46 (1.82 turns in rad)")
    assert "'q' spans" in text
    assert "look like degrees" in text
    offset = Log(t=t, q_m=rad + 90.0, tau_m=t, path="offset.csv")  # 90 "rad": 14 turns away
    assert "reaches 90.1" in unit_warnings(offset)[0]
    linear = Log(t=t, q_m=np.degrees(rad), tau_m=t, meta={"axis": "prismatic"})
    assert unit_warnings(linear) == []
    # a low-gain P loop's reference spans turns by design: the measured positions decide
    big_ref = Log(t=t, q_m=rad, tau_m=t, q=rad, q_ref=40 * rad, path="p_loop.csv")
    assert unit_warnings(big_ref) == []


def test_atomic_write_interrupted_leaves_old_content_and_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "out.csv"
    path.write_text("old\n")

    def interrupt(fd):
        raise KeyboardInterrupt

    monkeypatch.setattr(log_write.os, "fsync", interrupt)
    with pytest.raises(KeyboardInterrupt):
        atomic_write_text(path, "new\n" * 1000)
    assert path.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]
    with pytest.raises(KeyboardInterrupt):
        atomic_write_text(tmp_path / "fresh.csv", "new\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]


def test_the_encoder_step_decides_the_unit():
    """A 4096-count encoder in radians (steps of 2 pi / 4096) is radians however many turns an
    open-loop run drifts; the same counts in degrees (360 / 4096) warn even over a small
    span; an unquantised position falls back to the span."""
    from jointbench.identification.log.read import steps_per_turn

    t = np.arange(4000) / 500.0
    rng = np.random.default_rng(0)
    turns = 1.5 * 2 * np.pi * t / t[-1] + 0.2 * np.sin(2 * np.pi * 3 * t)   # 1.5 turns
    counts = np.round(turns / (2 * np.pi / 4096))
    rad = counts * (2 * np.pi / 4096)
    assert steps_per_turn(rad)[0] == "rad" and abs(steps_per_turn(rad)[1] - 4096) < 1e-3
    drift = Log(t=t, q_m=rad, tau_m=t, q=rad - np.round(rng.normal(0, 3, len(t))) * 2 * np.pi
                / 4096, path="open.csv")
    assert unit_warnings(drift) == []
    small = np.round(0.1 * np.sin(2 * np.pi * t) / (2 * np.pi / 4096))
    deg = Log(t=t, q_m=small * 360 / 4096, tau_m=t, path="deg.csv")
    assert steps_per_turn(deg.q_m)[0] == "deg"
    (text,) = unit_warnings(deg)
    assert "'q_m' moves in steps of 0.0878906, 360 / 4096" in text
    smooth = Log(t=t, q_m=turns, tau_m=t, path="smooth.csv")   # no encoder step: the span
    assert "'q_m' spans" in unit_warnings(smooth)[0]
