"""The log format of CONTRACT section 1: round trip and errors that name line and column."""

from __future__ import annotations

import numpy as np
import pytest

from identification.log import Log, LogError, parse_log, read_log, write_log

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
