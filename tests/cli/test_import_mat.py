"""`jointbench import` of what labs record: a MATLAB .mat file (written here with
scipy.io.savemat) with the lab rig's signals, imported with an expression map
(q = theta - alpha, tau_m = g_u u, a sign flip), unmapped columns kept, several files in one
call, and errors that name the file and the variable with nothing written."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import io as sio

from jointbench.testing.simulator import LAB_RIG, simulate_lab_rig

import jointbench as jb
from jointbench.bench.cli import main
from jointbench.identification.log import LogError, read_log

G = LAB_RIG.volt_to_torque


def _save(path: Path, seed: int = 3, **override) -> "jb.Log":
    log = simulate_lab_rig(seed=seed, duration=4.0)
    data = {"time": log.t[:, None], "theta": log.extra["theta"][:, None],   # n x 1, as MATLAB
            "alpha": log.extra["alpha"], "volts": log.extra["u"], "cur": -log.extra["u"],
            "r": log.q_ref, "Kp": 1.0, "label": "lab rig"}
    data.update(override)
    sio.savemat(path, data)
    return log


MAP = {"t": "time", "q_m": "theta", "q": "theta-alpha", "tau_m": f"{G!r}*volts", "q_ref": "r"}


def test_mat_with_expressions_is_the_log(tmp_path):
    log = _save(tmp_path / "run.mat")
    rep = jb.import_log(tmp_path / "run.mat", tmp_path / "run.csv", columns=MAP)
    back = read_log(tmp_path / "run.csv")
    assert np.allclose(back.q_m, log.q_m, atol=1e-12)
    assert np.allclose(back.q, log.q, atol=1e-12)
    assert np.allclose(back.tau_m, log.tau_m, rtol=1e-9, atol=1e-15)
    # unmapped columns kept as they are (the sign-flipped current, the raw volts)
    assert set(back.extra) >= {"alpha", "cur", "volts"}
    assert any("Kp (a scalar)" in s for s in rep.result.steps)


def test_sign_flip_and_scale(tmp_path):
    log = _save(tmp_path / "run.mat")
    rep = jb.import_log(tmp_path / "run.mat", columns={**MAP, "tau_m": f"-{G!r} * cur"})
    assert np.allclose(rep.log.tau_m, log.tau_m, rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("mapping, says", [
    ({**MAP, "q": "theta-beta"}, "no column 'beta'"),
    ({**MAP, "q": "theta**2"}, "only columns, numbers"),
    ({**MAP, "q": "theta/(alpha-alpha)"}, "not finite"),
])
def test_bad_expression_names_the_file_and_the_map(tmp_path, mapping, says):
    _save(tmp_path / "run.mat")
    with pytest.raises(LogError, match=says) as err:
        jb.import_log(tmp_path / "run.mat", tmp_path / "out.csv", columns=mapping)
    assert "run.mat" in str(err.value) and "--map q=" in str(err.value)
    assert not (tmp_path / "out.csv").exists()


def test_mapped_variable_of_another_length_is_named(tmp_path):
    _save(tmp_path / "run.mat", r=np.zeros(7))
    with pytest.raises(LogError, match="variable 'r' cannot be a column: 7 samples"):
        jb.import_log(tmp_path / "run.mat", columns=MAP)


def test_several_files_all_or_nothing(tmp_path):
    _save(tmp_path / "a.mat", seed=1)
    _save(tmp_path / "b.mat", seed=2)
    out = tmp_path / "logs"
    reps = jb.import_log([tmp_path / "a.mat", tmp_path / "b.mat"], out, columns=MAP)
    assert [r.out.name for r in reps] == ["a.csv", "b.csv"]
    assert read_log(out / "b.csv").q is not None
    # one file that cannot be converted: nothing written
    _save(tmp_path / "c.mat", seed=3, alpha=np.zeros(5))
    with pytest.raises(LogError, match="c.mat"):
        jb.import_log([tmp_path / "a.mat", tmp_path / "c.mat"], tmp_path / "none",
                      columns=MAP)
    assert not (tmp_path / "none").exists()


def test_cli_imports_a_mat_file_with_an_expression_map(tmp_path, capsys):
    _save(tmp_path / "run.mat")
    status = main(["import", str(tmp_path / "run.mat"), "--out", str(tmp_path / "run.csv"),
                   "--map", ",".join(f"{k}={v}" for k, v in MAP.items()),
                   "--meta", "controller=P", "--meta", f"pid_kp={G}", "--tau-max", f"{10 * G}",
                   "--gravity", "0"])
    assert status == 0
    log = read_log(tmp_path / "run.csv")
    assert log.meta["controller"] == "P" and "alpha" in log.extra
    assert main(["import", str(tmp_path / "nope.mat"), "--out", str(tmp_path / "x.csv")]) == 2
    assert "nope.mat" in capsys.readouterr().err


def test_v73_without_h5py_names_the_extra(tmp_path, monkeypatch):
    path = tmp_path / "v73.mat"
    path.write_bytes(b"MATLAB 7.3 MAT-file".ljust(512, b" ") + b"\x89HDF\r\n\x1a\n" + b"\0" * 64)
    monkeypatch.setitem(sys.modules, "h5py", None)
    with pytest.raises(LogError, match=r"\[mat73\]") as err:
        jb.import_log(path, columns=MAP)
    assert "v73.mat" in str(err.value)


def test_v73_through_h5py(tmp_path):
    """A v7.3 file is HDF5 behind a 512-byte MATLAB header; MATLAB stores an n-vector as a
    1 x n dataset (column-major), which the reader transposes back."""
    h5py = pytest.importorskip("h5py")
    log = simulate_lab_rig(seed=5, duration=2.0)
    path = tmp_path / "v73.mat"
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, x in (("time", log.t), ("theta", log.extra["theta"]),
                        ("alpha", log.extra["alpha"]), ("volts", log.extra["u"]),
                        ("r", log.q_ref)):
            f.create_dataset(name, data=np.asarray(x)[None, :])
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64".ljust(116, b" "))
    rep = jb.import_log(path, columns=MAP)
    assert np.allclose(rep.log.q, log.q, atol=1e-12)
    assert np.allclose(rep.log.tau_m, log.tau_m, rtol=1e-9, atol=1e-15)


def test_voltage_drive_constants_make_the_torque_and_name_the_back_emf(tmp_path):
    """The lab rig's drive given by its catalogue constants: tau_m = eta N Kt / R u (the log's
    own), the back-EMF damping eta N^2 Kt Ke / R written and reported inside FVm."""
    log = _save(tmp_path / "run.mat")
    r = LAB_RIG
    rep = jb.import_log(tmp_path / "run.mat", tmp_path / "run.csv",
                        columns={**MAP, "tau_m": "volts"}, units={"tau_m": "V"},
                        gear_ratio=r.N, motor_side=("tau_m",),
                        drive={"Kt": r.Kt, "R": r.R, "Ke": r.Ke,
                               "eta": r.eta_gear * r.eta_motor},
                        meta={"gravity": "0"})
    assert np.allclose(rep.log.tau_m, log.tau_m, rtol=1e-9, atol=1e-15)
    b = float(rep.log.meta["back_emf_damping"])
    assert b == pytest.approx(r.back_emf_damping, rel=1e-9)
    with pytest.raises(LogError, match="--units tau_m=V"):
        jb.import_log(tmp_path / "run.mat", columns=MAP, drive={"Kt": 1, "R": 1, "Ke": 1})
    with pytest.raises(LogError, match="--drive needs Ke"):
        jb.import_log(tmp_path / "run.mat", columns=MAP, units={"tau_m": "V"},
                      drive={"Kt": 1, "R": 1})



def test_identify_reports_the_mechanical_fvm_of_a_voltage_drive():
    from dataclasses import replace
    log = simulate_lab_rig(seed=3, duration=20.0)
    b = LAB_RIG.back_emf_damping
    log = replace(log, meta={**log.meta, "back_emf_damping": f"{b:.10g}"})
    text = jb.identify(log).table()
    assert "holds the voltage drive's back-EMF damping" in text
    assert "mechanical viscous friction" in text
