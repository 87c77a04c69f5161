"""`jointbench import`: a raw drive file (own column names, motor-side encoder counts, current
in A, ms time stamps) converted into a log identifies as the native log; EMPS goes through the
same path; what cannot be converted is refused with exit 2 naming the file, line and column."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from jointbench.bench.cli import main
from jointbench.identification.identify import identify
from jointbench.identification.log import read_log, write_log
from jointbench.identification.log.raw import ImportSpec, convert, parse_raw

N, KT, CPR = 100.0, 0.5, 2**17  # prototype gear ratio, torque constant [N m/A], counts per turn
T0_MS = 12.5
RAW_ARGS = ["--map", "t=time_ms,q_m=motor_counts,q=link_deg,tau_m=current_A,q_ref=ref_counts",
            "--units", "t=ms,q_m=counts,q=deg,tau_m=A,q_ref=counts", "--gear-ratio", "100",
            "--counts-per-turn", str(CPR), "--torque-constant", str(KT),
            "--kp", "5.83678819", "--kv", "5188.797305", "--ki", "30285.91083",
            "--tau-max", "3000", "--joint", "axis1"]
DATA = Path(__file__).parents[1] / "data" / "emps"
GTAU = 35.15065188  # EMPS drive gain [N/V] (tests/data/emps/README.md)


def write_raw(log, path: Path) -> None:
    """The native log in a drive's layout: ms stamps with an offset, motor counts (integers:
    the log's q_m is quantised to 2 pi / (CPR N)), link degrees, amperes, reference counts;
    17 significant digits, ';' separated, a comment line first."""
    counts = log.q_m * N * CPR / (2 * math.pi)
    assert np.allclose(counts, np.round(counts), atol=1e-3)  # the encoder's own counts
    table = np.column_stack([T0_MS + 1e3 * log.t, np.round(counts), np.rad2deg(log.q),
                             log.tau_m / (N * KT), log.q_ref * N * CPR / (2 * math.pi)])
    with open(path, "w") as f:
        f.write("# drive export\ntime_ms;motor_counts;link_deg;current_A;ref_counts\n")
        np.savetxt(f, table, delimiter=";", fmt="%.17g")


@pytest.fixture(scope="module")
def native(prototype_log, tmp_path_factory):
    path = tmp_path_factory.mktemp("import") / "native.csv"
    write_log(prototype_log, path)
    return read_log(path)


@pytest.mark.slow
def test_raw_drive_file_identifies_as_the_native_log(native, tmp_path, capsys):
    raw, out = tmp_path / "raw.csv", tmp_path / "log.csv"
    write_raw(native, raw)
    assert main(["import", str(raw), "--out", str(out), *RAW_ARGS]) == 0
    text = capsys.readouterr().out
    assert "q_m <- motor_counts [counts] x 2 pi / 131072 counts per turn / N = 100" in text
    assert "uniform sampling: 21053 samples" in text and "replayable" in text
    log = read_log(out)
    assert log.sample_rate_hz == pytest.approx(350.87, rel=1e-8)
    assert log.meta["motor_encoder_resolution_rad"] == "4.793689962e-07"
    for name in ("q_m", "q", "tau_m", "q_ref"):
        assert np.allclose(getattr(log, name), getattr(native, name), rtol=1e-10, atol=1e-13)
    # a raw file cannot say how a simulator integrated it, and the identification reads none
    # of the simulator's metadata: the imported log identifies as the native one
    for model in ("joint-motor", "motor-only"):
        a, b = identify(native, model).physical, identify(log, model).physical
        assert set(a) == set(b)
        for k in a:  # the bar: 0.1 %; measured: identical
            assert b[k] == pytest.approx(a[k], rel=1e-3), (model, k)


def test_emps_through_import(tmp_path):
    """EMPS's published layout (t, qm, qg, vir: voltage times the drive gain gtau) imported as
    a prismatic axis gives the shipped log and its identification."""
    ref = read_log(DATA / "emps_estimation.csv")
    raw = tmp_path / "DATA_EMPS.csv"
    np.savetxt(raw, np.column_stack([ref.t, ref.q_m, ref.q_ref, ref.tau_m / GTAU]),
               delimiter=",", fmt="%.17g", header="t,qm,qg,vir", comments="")
    out = tmp_path / "emps.csv"
    args = ["import", str(raw), "--out", str(out), "--map", "t=t,q_m=qm,q_ref=qg,tau_m=vir",
            "--units", "tau_m=V", "--torque-constant", str(GTAU), "--prismatic",
            "--kp", "160.18", "--kv", "8557.426201", "--ki", "0", "--tau-max", "351.506519",
            "--velocity-feedforward", "false", "--gravity", "0", "--json"]
    assert main(args) == 0
    log = read_log(out)
    assert log.prismatic and log.gravity == 0 and not log.meta_bool("velocity_feedforward", True)
    assert np.allclose(log.tau_m, ref.tau_m, rtol=1e-12)
    assert np.array_equal(log.q_m, ref.q_m) and np.array_equal(log.t, ref.t)
    a, b = identify(ref, "rigid").physical, identify(log, "rigid").physical
    for k in a:
        assert b[k] == pytest.approx(a[k], rel=1e-9)


def table(text: str):
    return parse_raw(enumerate(text.splitlines(), start=1), "raw.csv")


def test_non_uniform_sampling_names_the_row():
    raw = table("time,pos,cur\n0,0,0\n1,0.1,1\n2,0.2,2\n3.5,0.3,3\n4.5,0.3,3\n")
    spec = ImportSpec(columns={"t": "time", "q_m": "pos", "tau_m": "cur"})
    with pytest.raises(ValueError, match=r"raw.csv:5: column 'time': non-uniform sampling: "
                                         r"step 1.5 s against the median 1 s"):
        convert(raw, spec)
    # the drive's fixed rate accepts rounded stamps, and still refuses a dropped sample
    raw = table("t,q_m,tau_m\n0,0,1\n3,0,2\n6,1,3\n8,1,3\n11,2,2\n")
    ok = convert(raw, ImportSpec(columns={"t": "t", "q_m": "q_m", "tau_m": "tau_m"},
                                 units={"t": "ms"}, rate_hz=350.0))
    assert ok.log.t[-1] == pytest.approx(4 / 350.0)
    raw = table("t,q_m,tau_m\n0,0,1\n3,0,2\n6,1,3\n11,2,2\n")
    with pytest.raises(ValueError, match=r"raw.csv:5: column 't': time is .* periods away"):
        convert(raw, ImportSpec(columns={"t": "t", "q_m": "q_m", "tau_m": "tau_m"},
                                units={"t": "ms"}, rate_hz=350.0))


@pytest.mark.parametrize("args, message", [
    (["--map", "t=time,q_m=pos"], "--map gives no column for 'tau_m'"),
    (["--map", "t=time,q_m=enc,tau_m=cur"], "--map q_m=enc: no column 'enc'"),
    (["--map", "t=time,q_m=pos,tau_m=cur", "--units", "q_m=counts"], "needs --counts-per-turn"),
    (["--map", "t=time,q_m=pos,tau_m=cur", "--units", "tau_m=A"], "needs --torque-constant"),
    (["--map", "t=time,q_m=pos,tau_m=cur", "--units", "t=h"], "--units t=h: not a unit of t"),
    (["--map", "t=time,q_m=pos,tau_m=cur", "--kp", "x"], "argument --kp"),
    (["--map", "t=time;q_m=pos"], "--map: 't=time;q_m=pos' must read COL=RAW"),
    (["--map", "t=time,q_m=pos,tau_m=cur", "--units", "q_m=mm"], "a length on a revolute axis"),
    (["--map", "t=time,q_m=pos,tau_m=cur", "--units", "q_m=deg", "--prismatic"],
     "an angle on a prismatic axis needs"),
    (["--map", "t=time,q_m=pos,tau_m=cur", "--units", "tau_m=N"], "a force on a revolute axis"),
    (["--map", "t=time,q_m=pos,tau_m=cur", "--units", "tau_m=Nm", "--prismatic"],
     "a motor torque on a prismatic axis needs --gear-ratio"),
])
def test_bad_options_exit_2(tmp_path, capsys, args, message):
    raw = tmp_path / "raw.csv"
    raw.write_text("time,pos,cur\n0,0,0\n1,0.1,1\n2,0.2,2\n3,0.3,3\n")
    with pytest.raises(SystemExit) if args[-2] == "--kp" else _nothing():
        assert main(["import", str(raw), "--out", str(tmp_path / "o.csv"), *args]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "o.csv").exists()


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_bad_cell_and_input_protection(tmp_path, capsys):
    raw = tmp_path / "raw.csv"
    raw.write_text("# export\ntime,pos,cur\n0,0,0\n1,abc,1\n")
    assert main(["import", str(raw), "--out", str(tmp_path / "o.csv"),
                 "--map", "t=time,q_m=pos,tau_m=cur"]) == 2
    assert f"{raw}:4: column 'pos': not a number: 'abc'" in capsys.readouterr().err
    before = raw.read_bytes()
    assert main(["import", str(raw), "--out", str(raw)]) == 2
    assert "is the input file" in capsys.readouterr().err
    other = tmp_path / "measured.csv"
    other.write_text("t,q_m,tau_m\n0,0,0\n")
    assert main(["import", str(raw), "--out", str(other)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert raw.read_bytes() == before


def test_prismatic_ball_screw_in_counts():
    """A linear axis measured by a motor encoder behind a screw: counts -> motor rad -> m with
    N = 2 pi / lead (motor rad per m); the force from the current."""
    lead = 0.01  # m per motor turn
    raw = table("t,enc,i\n0,0,1\n0.001,1000,2\n0.002,2000,3\n0.003,4096,2\n")
    log = convert(raw, ImportSpec(columns={"t": "t", "q_m": "enc", "tau_m": "i"},
                                  units={"q_m": "counts", "tau_m": "A"},
                                  gear_ratio=2 * np.pi / lead, counts_per_turn=4096,
                                  torque_constant=0.2, meta={"axis": "prismatic"})).log
    assert log.prismatic
    assert np.allclose(log.q_m, np.array([0, 1000, 2000, 4096]) / 4096 * lead)
    assert np.allclose(log.tau_m, np.array([1, 2, 3, 2]) * 0.2 * 2 * np.pi / lead)
    # carriage-side lengths and forces are left as they are, the gear ratio notwithstanding
    raw = table("t,x,f\n0,0,1\n0.001,1,2\n0.002,2,3\n")
    log = convert(raw, ImportSpec(columns={"t": "t", "q_m": "x", "tau_m": "f"},
                                  units={"q_m": "mm"}, gear_ratio=2 * np.pi / lead,
                                  meta={"axis": "prismatic"})).log
    assert np.allclose(log.q_m, [0, 1e-3, 2e-3]) and np.allclose(log.tau_m, [1, 2, 3])


def test_motor_side_gains_and_metadata(tmp_path):
    raw = table("t,q_m,tau_m\n0,0,1\n0.01,0.5,2\n0.02,1,3\n0.03,1.5,2\n")
    spec = ImportSpec(columns={"t": "t", "q_m": "q_m", "tau_m": "tau_m"},
                      units={"q_m": "deg"}, gear_ratio=10.0,
                      meta={"kp": "5", "kv": "2", "ki": "3", "tau_max": "4",
                            "velocity_feedforward": "no"}, gains_side="motor")
    log = convert(raw, spec).log
    assert log.meta["kv"] == "200" and log.meta["ki"] == "300" and log.meta["tau_max"] == "40"
    assert log.meta["kp"] == "5" and log.meta["velocity_feedforward"] == "false"
    assert np.allclose(log.q_m, np.deg2rad([0, 0.05, 0.1, 0.15]))
    assert np.allclose(log.tau_m, [10, 20, 30, 20])
    assert log.sample_rate_hz == pytest.approx(100.0)
