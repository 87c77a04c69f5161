"""Bad data and faults (issue 5): data that does not excite the model, unphysical estimates,
the motor-only inversion near zero, diverging simulations, broken models, signals, and
outputs that never overwrite inputs nor stay half-written. Hypothesis fuzzes the loader and
the commands: no input makes them crash or print a traceback."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointbench.bench.cli import main
from jointbench.bench.sim.controller import Gains
from jointbench.bench.sim.defaults import DEFAULT_SUBSTEPS
from jointbench.bench.sim.experiment import SimulationError, run_experiment
from jointbench.bench.sim.reference import Chirp
from jointbench.identification.checks import fit as checks
from jointbench.identification.estimate import NotIdentifiable, least_squares
from jointbench.identification.identify import identify
from jointbench.identification.log import Log, LogError, parse_log, read_log, write_log
from jointbench.identification.regressors import Regressor
from jointbench.identification.physical import InversionError, invert_motor_only, table3
from jointbench.models import model_path

RATE = 350.87


def cli(args: list[str], capsys) -> tuple[int, str, str]:
    """Run the command line in-process: (status, stdout, stderr)."""
    try:
        rc = main(args)
    except SystemExit as stop:  # argparse's own usage errors
        rc = stop.code
    out, err = capsys.readouterr()
    return rc, out, err


def synthetic_log(qm: np.ndarray, tau: np.ndarray, q: np.ndarray | None = None,
                  path: str | None = None) -> Log:
    t = np.arange(len(qm)) / RATE
    return Log(t=t, q_m=qm, tau_m=tau, q=q, meta={"sample_rate_hz": f"{RATE}"}, path=path)


def multisine(n: int, freqs=(0.5, 1.7, 3.1), amps=(0.1, 0.05, 0.02)):
    """q, q', q'' of a sum of sines (exact derivatives)."""
    t = np.arange(n) / RATE
    w = 2 * np.pi * np.asarray(freqs)
    a = np.asarray(amps)
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
    return (a * s).sum(1), (a * w * c).sum(1), -(a * w ** 2 * s).sum(1)


# --- Estimation: data that does not excite the model ----------------------------------------

@pytest.mark.parametrize("model", ["joint-motor", "motor-only", "rigid", "auto"])
def test_constant_data_names_what_cannot_be_identified(tmp_path, capsys, model):
    n = 6000
    path = tmp_path / "still.csv"
    write_log(synthetic_log(np.full(n, 0.3), np.full(n, 12.0), np.full(n, 0.29)), path)
    rc, out, err = cli(["identify", str(path), "--model", model], capsys)
    assert rc == 2 and out == ""
    assert re.search(r"still.csv: q_m is constant \(0.3\) over all 6000 samples: the motor "
                     r"does not move, so no parameter of the [a-z-]+ model can be identified", err)


def test_too_few_samples_for_the_filter(tmp_path, capsys):
    path = tmp_path / "short.csv"
    path.write_text(valid_text(120, 0))   # the generic band (Nd = 10) needs 170 samples
    rc, out, err = cli(["identify", str(path), "--model", "rigid"], capsys)
    assert rc == 2 and out == ""
    assert re.search(r"short.csv: 120 samples are too few for this filter and decimation "
                     r"\(Nd = 10, .*at least \d+ are needed", err)


def test_identify_api_raises_not_identifiable():
    n = 6000
    still = synthetic_log(np.zeros(n), np.linspace(0, 1, n), path="still.csv")
    with pytest.raises(NotIdentifiable, match=r"still.csv: q_m is constant"):
        identify(still, "rigid")
    qm, _, _ = multisine(n)
    flat = synthetic_log(qm, np.full(n, 5.0), path="flat.csv")
    with pytest.raises(NotIdentifiable, match=r"flat.csv: tau_m is constant \(5\)"):
        identify(flat, "rigid")
    with pytest.raises(NotIdentifiable, match=r"q is constant .* use --model motor-only"):
        identify(synthetic_log(qm, qm, np.zeros(n), path="clamped.csv"), "joint-motor")


@pytest.fixture(scope="module")
def sine_run():
    """A 1 Hz sine reference instead of the chirp (prototype, default sensors, 20 s)."""
    probe = run_experiment("prototype", duration=5.0, seed=1)
    chirp = Chirp(duration=20.0, f0=1.0, f1=1.0 + 1e-9, amplitude=0.1,
                  center=float(probe.log.q_m[0]))
    return run_experiment("prototype", duration=20.0, seed=1, chirp=chirp)


def test_single_sine_does_not_identify_the_flexible_models(sine_run, tmp_path, capsys):
    """One frequency (with the friction harmonics) cannot separate Jm, K and JL: the answer
    names them and the reason, no numbers. Measured lines: 1.06 (a chirp gives 10-15)."""
    lines, peak, _ = checks.excited_lines(sine_run.log, identify_settings(sine_run.log))
    assert lines < 1.5 and peak == pytest.approx(1.0, abs=0.1)
    path = tmp_path / "sine.csv"
    write_log(sine_run.log, path)
    for model, need in (("joint-motor", 2), ("motor-only", 3)):
        rc, out, err = cli(["identify", str(path), "--model", model], capsys)
        assert rc == 2 and out == ""
        assert "sine.csv: the motion excites about 1.1 frequency line(s)" in err
        assert f"the {model} model needs at least {need}" in err
        assert "Jm, FVm, K in the motor equation" in err or "X1 ... X6" in err
    # the rigid model (J, FV: one frequency is enough) is what auto falls back to
    rc, out, err = cli(["identify", str(path), "--json"], capsys)
    answer = json.loads(out)
    assert rc == 0 and answer["model"] == "rigid"
    assert any("joint-motor model rejected" in note for note in answer["notes"])


def identify_settings(log: Log):
    from jointbench.identification.filter_choice import settings_for
    return settings_for(log)[0]


def test_chirp_excites_many_lines(prototype_log):
    lines, _, band = checks.excited_lines(prototype_log, identify_settings(prototype_log))
    assert lines > 5 and band == pytest.approx(5.40, abs=0.01)


def test_too_small_an_amplitude_is_refused(tmp_path, capsys):
    """A 1e-6 rad chirp: the motion is the torque noise's (37.5 N m); the rigid model explains
    almost nothing of the torque, so no number is printed. The link does not move at all: the
    spring passes it K 1e-6 rad = 0.02 N m, far inside its Coulomb friction FS = 8.46 N m,
    which holds it (its true travel, 2.5e-7 rad, is under the link encoder's quantum), so the
    joint-motor model is refused for its constant q."""
    res = run_experiment("prototype", duration=20.0, seed=2, amplitude=1e-6)
    path = tmp_path / "tiny.csv"
    write_log(res.log, path)
    rc, out, err = cli(["identify", str(path), "--model", "rigid"], capsys)
    assert rc == 2 and out == ""
    assert re.search(r"tiny.csv: the rigid model explains only [0-9.]+ % of the "
                     r"torque's variation .*too small an amplitude", err)
    assert "relative standard deviations: " in err
    rc, out, err = cli(["identify", str(path), "--model", "joint-motor"], capsys)
    assert rc == 2 and out == ""
    assert re.search(r"tiny.csv: q is constant .*the link does not move, so the joint-motor "
                     r"model's link equation identifies nothing", err)


def test_poorly_conditioned_directions_are_named():
    rng = np.random.default_rng(0)
    a, b, c = rng.normal(size=(3, 500))
    W = np.column_stack([a, b, a + b + 1e-6 * c, c])
    out = checks.poorly_excited(W, ("A", "B", "C", "D"))
    assert len(out) == 1
    (name, why), = out.items()
    assert name in "ABC" and "singular value ratio" in why and "combination" in why
    assert checks.poorly_excited(np.column_stack([a, b, c]), ("A", "B", "C")) == {}


def test_check_excitation_refits_without_the_dropped_parameter():
    rng = np.random.default_rng(1)
    a, b, c = rng.normal(size=(3, 400))
    W = np.column_stack([a, b, a + 1e-7 * c])
    y = 2 * a - b + 0.01 * rng.normal(size=400)
    reg = Regressor("rigid", ("J", "FV", "FS"), y, W, np.zeros(400, int), np.arange(400), None)
    log = synthetic_log(np.zeros(3), np.zeros(3), path="x.csv")
    ls = checks.check_excitation(log, reg, least_squares(W, y, reg.names))
    dropped = [n for n in ("J", "FS") if n in ls.unidentifiable]
    assert len(dropped) == 1 and "poorly excited" in ls.reasons[dropped[0]]
    kept = [i for i, n in enumerate(reg.names) if n not in dropped]
    alone = least_squares(W[:, kept], y, tuple(reg.names[i] for i in kept))
    np.testing.assert_allclose(ls.X[kept], alone.X, rtol=1e-12)


def test_rigid_transmission_leaves_the_link_equation_without_scale(tmp_path, capsys):
    """q == q_m: K's column (q_m - q) is zero, and the link equation (y = 0) alone only
    fixes ratios of JL, FV, FS, MX, MY: none of them is printed."""
    qm, qd, qdd = multisine(8000)
    tau = 220 * qdd + 300 * qd + np.random.default_rng(2).normal(0, 1, len(qm))
    path = tmp_path / "rigid_q.csv"
    write_log(synthetic_log(qm, tau, qm.copy()), path)
    rc, out, _ = cli(["identify", str(path), "--model", "joint-motor", "--json"], capsys)
    answer = json.loads(out)
    assert rc == 0
    for name in ("K", "JL", "FV", "FS", "MX", "MY"):
        assert answer["parameters"][name]["value"] is None, name
        assert name not in answer["physical"]
    assert "y = 0" in answer["parameters"]["JL"]["reason"]
    assert answer["parameters"]["Jm"]["value"] == pytest.approx(220, rel=0.01)
    rc, out, _ = cli(["identify", str(path), "--model", "joint-motor"], capsys)
    assert re.search(r"\nJL +not identifiable", out)


def test_unphysical_estimates_are_flagged(tmp_path, capsys):
    """A torque that pushes against the acceleration: a negative inertia, flagged in the
    JSON `flags` list and in the text output."""
    qm, qd, qdd = multisine(8000)
    tau = -50 * qdd + 300 * qd + np.random.default_rng(3).normal(0, 1, len(qm))
    path = tmp_path / "neg.csv"
    write_log(synthetic_log(qm, tau), path)
    rc, out, _ = cli(["identify", str(path), "--model", "rigid", "--json"], capsys)
    answer = json.loads(out)
    assert rc == 0 and answer["physical"]["J"] == pytest.approx(-50, rel=0.02)
    flag = next(f for f in answer["flags"] if f["parameter"] == "J")
    assert flag["flag"] == "unphysical" and "an inertia cannot be" in flag["message"]
    (warning,) = answer["warnings"]   # the likely cause (identification.checks.plausibility)
    assert "every inertia is negative" in warning and "wrong sign" in warning
    rc, out, _ = cli(["identify", str(path), "--model", "rigid"], capsys)
    assert rc == 0 and re.search(r"flag: J = -[0-9.]+ is negative: an inertia cannot be", out)


def test_estimate_flags():
    flags = checks.estimate_flags({"K": -3.0, "Jm": 2.0, "MX": 0.01, "offset": -5.0},
                                  {"K": 0.1, "Jm": 0.1, "MX": 0.2, "offset": 1.0})
    assert [(f["parameter"], f["flag"]) for f in flags] == [("K", "unphysical"),
                                                           ("MX", "not_significant")]
    assert checks.estimate_flags({"J": -1.0}, {}, prismatic=True)[0]["message"] == \
        "J = -1 is negative: a mass cannot be"


def test_degrees_warning_in_json_keeps_one_object(tmp_path, capsys):
    qm, qd, qdd = multisine(8000)
    tau = 220 * qdd + 300 * qd + np.random.default_rng(4).normal(0, 1, len(qm))
    path = tmp_path / "deg.csv"
    write_log(synthetic_log(np.degrees(qm), np.degrees(tau)), path)
    rc, out, err = cli(["identify", str(path), "--model", "rigid", "--json"], capsys)
    answer = json.loads(out)  # exactly one JSON object on stdout
    assert rc == 0 and len(answer["warnings"]) == 1
    assert "look like degrees" in answer["warnings"][0]
    assert "jointbench identify: warning: " in err and "look like degrees" in err


# --- Estimation: the motor-only inversion near zero -----------------------------------------

def motor_only_ls(x1: float):
    rng = np.random.default_rng(5)
    W = rng.normal(size=(600, 7))
    X = np.array([x1, 0.0049, 0.419, 1.58, 225.0, 330.0, 48.0])
    y = W @ X * 1.0 + rng.normal(0, 1.0, 600)
    return least_squares(W, y, tuple(f"X{i}" for i in range(1, 8)))


def test_motor_only_inversion_refuses_x1_near_zero():
    with pytest.raises(InversionError, match=r"X1 = .* is not distinguishable from zero "
                                             r"\(2 sigma = .*\): the motor-only inversion "
                                             r"divides by it"):
        invert_motor_only(motor_only_ls(0.0))


def test_table3_refuses_x1_or_x2_near_zero():
    X = {"X1": 0.0024, "X2": 0.0049, "X3": 0.419, "X4": 1.58, "X5": 225.0, "X6": 330.0,
         "X7": 48.0}
    assert table3(X)["K"] > 0
    with pytest.raises(InversionError, match=r"X2 = 0.0049 is not distinguishable from zero "
                                             r"\(2 sigma = 0.01\): Table 3 divides by it "
                                             r"\(K = FV/X2\)"):
        table3(X, {"X2": 0.005})
    with pytest.raises(InversionError, match=r"X1 = 0: Table 3 divides by it"):
        table3({**X, "X1": 0.0})
    with pytest.raises(InversionError, match=r"X2 is not identified"):
        table3({k: v for k, v in X.items() if k != "X2"})


# --- Simulation faults ----------------------------------------------------------------------

def prototype_gains(**scale) -> Gains:
    base = {"kp": 5.83678819, "kv": 5188.797305, "ki": 30285.91083}
    base = {k: v * scale.get(k, 1.0) for k, v in base.items()}
    return Gains(tau_max=3000.0, **base)


@pytest.mark.parametrize("scale, reason", [
    ({"kv": 100.0}, r"the torque jumps between -3000 and \+3000 from one sample to the next "
                    r"\(20 times in [0-9.]+ s\): a limit cycle at the sampling rate"),
    ({"kv": -1.0}, r"the motor is 1 rad from the reference \(limit 1 rad, 10 chirp "
                   r"amplitudes\): unstable gains"),
    ({"kp": -1.0}, r"the motor is 1.* rad from the reference"),
])
def test_unstable_gains_stop_the_run(scale, reason):
    with pytest.raises(SimulationError, match=r"joint axis1: the simulation stopped at "
                                              r"t = [0-9.]+ s: " + reason):
        run_experiment("prototype", duration=10.0, seed=0, gains=prototype_gains(**scale))


def test_too_large_a_timestep_stops_the_run():
    """arm6 axis1 (mode 14.7 Hz) stepped at 20 Hz, one physics step a control period:
    w1 dt = 4.6, over semi-implicit Euler's 2."""
    with pytest.raises(SimulationError, match=r"joint axis1: the simulation stopped at "
                                              r"t = 0\.\d+ s: .*the timestep is too large for "
                                              r"the joint's mode: w1 dt = 4.61"):
        run_experiment("arm6", duration=5.0, seed=0, sample_rate_hz=20.0, substeps=1)


def test_too_large_a_timestep_from_the_command_line(tmp_path, capsys):
    out = tmp_path / "a1.csv"
    rc, stdout, err = cli(["simulate", "--model", "arm6", "--rate", "20", "--substeps", "1",
                           "--duration", "5", "--out", str(out)], capsys)
    assert rc == 2 and stdout == "" and not out.exists() and list(tmp_path.iterdir()) == []
    assert re.fullmatch(r"jointbench simulate: error: joint axis1: the simulation stopped at "
                        r"t = 0\.\d+ s: .*w1 dt = 4.61 .*\n", err)


def test_mjcf_timestep_is_replaced_by_the_control_period(tmp_path):
    """A user MJCF with timestep 0.05 runs at the experiment's physics step, the control
    period (350.87 Hz) over the physics steps a period, so its own timestep cannot make the
    run diverge."""
    xml = model_path("prototype").read_text().replace('timestep="0.002850058"',
                                                      'timestep="0.05"')
    path = tmp_path / "coarse.xml"
    path.write_text(xml)
    res = run_experiment(path, duration=5.0, seed=0)
    assert res.experiment.model.opt.timestep == pytest.approx(1 / (RATE * DEFAULT_SUBSTEPS),
                                                              rel=1e-9)


def test_torque_saturation_is_reported():
    probe = run_experiment("prototype", duration=5.0, seed=0)
    chirp = Chirp(duration=20.0, amplitude=0.1, center=float(probe.log.q_m[0]))
    res = run_experiment("prototype", duration=20.0, seed=0, tau_max=700.0, chirp=chirp)
    clipped = int(np.sum(np.abs(res.log.tau_m) >= 700.0))
    assert res.saturated == clipped > 0
    assert res.log.meta["saturated_samples"] == str(clipped)
    assert res.log.meta["actuator_clamped_samples"] == "0"
    assert probe.log.meta["saturated_samples"] == "0"


def test_saturation_warning_in_simulate(tmp_path, capsys):
    """A 1 N m torque limit (ctrlrange) on the prototype: the command saturates almost all
    the time; the run completes, the count is in the summary, the metadata and a warning."""
    xml = model_path("prototype").read_text().replace('ctrlrange="-3000 3000"',
                                                      'ctrlrange="-1 1"')
    model = tmp_path / "weak.xml"
    model.write_text(xml)
    out = tmp_path / "weak.csv"
    rc, stdout, err = cli(["simulate", "--model", str(model), "--duration", "5",
                           "--out", str(out), "--json", "--quiet"], capsys)
    summary = json.loads(stdout)
    assert rc == 0 and summary["saturated_samples"] > 0
    assert read_log(out).meta["saturated_samples"] == str(summary["saturated_samples"])
    assert "saturated at tau_max on" in summary["warnings"][0]
    assert "jointbench simulate: warning: the torque command saturated" in err


@pytest.mark.parametrize("edit, message", [
    (lambda xml: xml[: len(xml) // 2], r"bad.xml: MuJoCo cannot load it: XML parse error"),
    (lambda xml: re.sub(r'<joint name="axis1_motor"[^>]*/>', "", xml),
     r"bad.xml: MuJoCo cannot load it: Error: joint 'axis1_motor' not found in tendon"),
    (lambda xml: re.sub(r'<motor name="axis1_motor"[^>]*/>', "", xml),
     r"bad.xml: axis 'axis1' has no actuator 'axis1_motor'"),
    (lambda xml: xml.replace('name="axis1_spring"', 'name="axis1_rope"'),
     r"bad.xml: no flexible axis found"),
])
def test_broken_mjcf_is_refused_and_nothing_written(tmp_path, capsys, edit, message):
    model = tmp_path / "bad.xml"
    model.write_text(edit(model_path("prototype").read_text()))
    out = tmp_path / "run.csv"
    rc, stdout, err = cli(["simulate", "--model", str(model), "--duration", "5",
                           "--out", str(out)], capsys)
    assert rc == 2 and stdout == "" and not out.exists()
    assert re.search(message, err) and err.count("\n") == 1  # one line, no traceback


def test_simulation_error_is_exit_2_without_a_log(tmp_path, capsys, monkeypatch):
    """The command line maps a diverging run to status 2 and writes nothing."""
    import jointbench.bench.sim.experiment as experiment

    real = experiment.run_experiment
    monkeypatch.setattr(experiment, "run_experiment", lambda *a, **k: real(
        "prototype", duration=5.0, seed=0, gains=prototype_gains(kv=-1.0)))
    out = tmp_path / "x.csv"
    rc, stdout, err = cli(["simulate", "--duration", "5", "--out", str(out)], capsys)
    assert rc == 2 and stdout == "" and not out.exists() and list(tmp_path.iterdir()) == []
    assert "jointbench simulate: error: joint axis1: the simulation stopped at t = " in err


# --- Nothing lost ---------------------------------------------------------------------------

def test_simulate_never_overwrites_inputs_or_foreign_files(tmp_path, capsys):
    measured = tmp_path / "measured.csv"
    measured.write_text(parse_log_text())
    before = measured.read_bytes()
    rc, _, err = cli(["simulate", "--duration", "5", "--out", str(measured)], capsys)
    assert rc == 2 and "refusing to overwrite an existing file that jointbench did not write" in err
    assert measured.read_bytes() == before
    model = tmp_path / "axis.xml"
    model.write_text(model_path("prototype").read_text())
    rc, _, err = cli(["simulate", "--model", str(model), "--out", str(model)], capsys)
    assert rc == 2 and "refusing to overwrite the model file" in err
    rc, _, err = cli(["simulate", "--duration", "5", "--out", str(tmp_path / "no" / "x.csv")],
                     capsys)
    assert rc == 2 and "does not exist" in err
    # its own earlier output is replaced (atomically)
    own = tmp_path / "own.csv"
    assert cli(["simulate", "--duration", "5", "--out", str(own), "--seed", "1"], capsys)[0] == 0
    assert cli(["simulate", "--duration", "5", "--out", str(own), "--seed", "2"], capsys)[0] == 0
    assert read_log(own).meta["seed"] == "2"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["axis.xml", "measured.csv", "own.csv"]


def parse_log_text() -> str:
    t = np.arange(600) / RATE
    rows = "\n".join(f"{a:.6f},{np.sin(a):.6f},{np.cos(a):.6f}" for a in t)
    return f"# source: lab bench, 2024-03-01\nt,q_m,tau_m\n{rows}\n"


def test_identify_leaves_its_input_untouched(tmp_path, capsys, prototype_log):
    path = tmp_path / "p.csv"
    write_log(prototype_log, path)
    before, mtime = path.read_bytes(), path.stat().st_mtime_ns
    assert cli(["identify", str(path), "--json"], capsys)[0] == 0
    assert path.read_bytes() == before and path.stat().st_mtime_ns == mtime
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.csv"]


def _handler_installed(pid: int, signum: int) -> bool:
    """Whether process `pid` catches `signum` (Linux /proc/PID/status, SigCgt mask)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    mask = int(re.search(r"SigCgt:\s*([0-9a-f]+)", status).group(1), 16)
    return bool(mask >> (signum - 1) & 1)


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux /proc")
@pytest.mark.parametrize("signum, status", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_signal_during_simulate_leaves_no_file(tmp_path, signum, status):
    out = tmp_path / "X.csv"
    proc = subprocess.Popen([sys.executable, "-m", "jointbench.bench.cli", "simulate", "--duration", "600",
                             "--out", str(out), "--quiet"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            # as from a terminal: a suite started in the background inherits
                            # SIGINT ignored (POSIX), and Python then keeps it ignored
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        # wait until the command runs (its SIGTERM handler is installed), then signal it
        deadline = time.monotonic() + 120
        while not _handler_installed(proc.pid, signal.SIGTERM) and proc.poll() is None:
            assert time.monotonic() < deadline, "simulate did not start"
            time.sleep(0.05)
        time.sleep(0.3)
        proc.send_signal(signum)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == status, stderr
    assert "Traceback" not in stderr and stdout == ""
    assert stderr.strip() in ("jointbench simulate: terminated by SIGTERM",
                              "jointbench simulate: interrupted")
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_broken_pipe_is_quiet():
    """`jointbench ... | true`: the reader is gone before the first write."""
    proc = subprocess.run(["bash", "-c", f"'{sys.executable}' -m jointbench.bench.cli design-filter "
                           "--f1 3.9 --nd 2 --m 4 | true; exit ${PIPESTATUS[0]}"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode in (0, 141) and proc.stderr == ""


# --- Fuzzing: no input makes the loader or the commands crash -------------------------------

FUZZ = settings(max_examples=60, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@FUZZ
@given(st.text(max_size=400))
def test_fuzz_parse_log_text(text):
    try:
        log = parse_log(text, "fuzz.csv")
    except LogError as err:
        assert str(err).startswith("fuzz.csv")
    else:
        assert np.all(np.diff(log.t) > 0) and np.all(np.isfinite(log.q_m))


@FUZZ
@given(st.binary(max_size=400))
def test_fuzz_read_log_bytes(data):
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzz.csv"
        path.write_bytes(data)
        try:
            read_log(path)
        except LogError as err:
            assert str(err).startswith(str(path))


def valid_text(n: int, seed: int) -> str:
    """A log whose torque follows a rigid axis (J = 200, FV = 300) on a random multisine,
    with noise: identify runs its whole chain on it."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    k = int(rng.integers(1, 5))
    qm, qd, qdd = multisine(n, rng.uniform(0.3, 5.0, k), rng.uniform(0.001, 0.2, k))
    q = qm - 1e-3 * qdd / 50 + 1e-6 * rng.normal(size=n)
    tau = 200 * qdd + 300 * qd + rng.normal(0, 1.0, n)
    rows = "\n".join(f"{a:.9f},{b:.9g},{c:.9g},{d:.9g}" for a, b, c, d in zip(t, qm, q, tau))
    return f"# jointbench-log: 1\n# sample_rate_hz: {RATE}\nt,q_m,q,tau_m\n{rows}\n"


JUNK = st.sampled_from(["", "nan", "inf", "-inf", "abc", "1e999", "1,5", "0x10", " ", "\x00",
                        "\u00e9", "1;2", "--1", "1e-320", "-0", "9" * 30])


@st.composite
def perturbed_log(draw, n_min=3, n_max=60):
    """A structurally valid log with a few random edits: cells replaced by junk, lines
    deleted, duplicated or swapped, metadata changed, the text cut short."""
    text = valid_text(draw(st.integers(n_min, n_max)), draw(st.integers(0, 10**6)))
    lines = text.split("\n")
    for _ in range(draw(st.integers(0, 3))):
        kind = draw(st.sampled_from(["cell", "delete", "duplicate", "swap", "meta", "cut"]))
        k = draw(st.integers(0, len(lines) - 1))
        if kind == "cell":
            cells = lines[k].split(",")
            cells[draw(st.integers(0, len(cells) - 1))] = draw(JUNK)
            lines[k] = ",".join(cells)
        elif kind == "delete":
            del lines[k]
        elif kind == "duplicate":
            lines.insert(k, lines[k])
        elif kind == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[k], lines[j] = lines[j], lines[k]
        elif kind == "meta":
            lines.insert(1, "# " + draw(st.sampled_from(["sample_rate_hz", "gravity", "kp",
                                                          "tau_max", "axis", "jointbench-log"]))
                         + ": " + draw(JUNK))
        else:
            lines = "\n".join(lines)[: draw(st.integers(0, len("\n".join(lines))))].split("\n")
        if not lines:
            lines = [""]
    return "\n".join(lines)


@FUZZ
@given(perturbed_log())
def test_fuzz_parse_perturbed_logs(text):
    try:
        log = parse_log(text, "p.csv")
    except LogError as err:
        assert str(err).startswith("p.csv")
    else:
        assert len(log) >= 3 and np.all(np.diff(log.t) > 0)
        for x in (log.t, log.q_m, log.tau_m):
            assert np.all(np.isfinite(x))


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(perturbed_log(n_min=450, n_max=900),
       st.sampled_from(["auto", "joint-motor", "motor-only", "motor-only-printed", "rigid"]),
       st.booleans())
def test_fuzz_identify_command(text, model, as_json):
    """`identify` on fuzzed logs: status 0 or 2, never a traceback or an internal error;
    with --json, exactly one JSON object on stdout."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzz.csv"
        path.write_text(text, encoding="utf-8", errors="surrogateescape")
        args = ["identify", str(path), "--model", model] + (["--json"] if as_json else [])
        rc, out, err = run_captured(args)
        assert rc in (0, 2), err
        assert "Traceback" not in err and "internal error" not in err
        if rc == 2:
            assert out == "" and err.startswith("jointbench identify: error: ")
        elif as_json:
            json.loads(out)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.sampled_from(["--f1", "--nd", "--m", "--ac", "--rc", "--ratio", "--json",
                                 "0", "-1", "3.9", "1e308", "nan", "inf", "2", "4", "x", "1e-9"]),
                max_size=10))
def test_fuzz_design_filter_command(args):
    rc, out, err = run_captured(["design-filter"] + args)
    assert rc in (0, 2), err
    assert "Traceback" not in err and "internal error" not in err


def run_captured(args: list[str]) -> tuple[int, str, str]:
    """main(args) with stdout and stderr captured (usable inside hypothesis tests)."""
    import contextlib
    import io

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(args)
        except SystemExit as stop:
            rc = stop.code
    return rc, out.getvalue(), err.getvalue()
