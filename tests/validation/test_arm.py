"""Issue 3 on the six-axis arm: the joint-motor identification of three joints against the
ground truth of their locked configuration (all axes at 0, the "ready" posture).

Settings (README, "Accuracy on the six-axis arm"):
- sample rate twice eq. (29)'s (identification.filtering.design_rate_hz, about 105 f1:
  1549 Hz for axis1, 1986 Hz for axis4, 1923 Hz for axis6), so that the central-difference
  distortion at the mode is 0.12 % instead of 0.47 %;
- the filter from f1 (identification.filtering.default_settings(rate, f1));
- the shipped chirp (0.05-30 Hz, 0.1 rad, 60 s) with its acceleration cap raised from 40 % to
  55 % of the torque limit over Jm + JL: more motor motion at high frequency shortens the
  Coulomb stick phases at the velocity reversals relative to the motion;
- models/arm6.xml's friction time constant 0.25 ms (was 2 ms).
"""

from __future__ import annotations

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.cli import main
from jointbench.bench.sim.experiment import default_chirp, run_experiment
from jointbench.identification.design import design_bandpass
from jointbench.identification.filter_choice import default_settings, design_rate_hz
from jointbench.identification.identify import identify
from jointbench.identification.log import read_log
from jointbench.models import model_path

JOINTS = ("axis1", "axis4", "axis6")
ACCELERATION_SHARE = 0.55  # chirp acceleration cap: share of tau_max over Jm + JL (default 0.4)
DURATION = 60.0
SEED = 1


def err_pct(value: float, truth: float) -> float:
    return 100 * (value - truth) / abs(truth)


def arm_experiment(joint: str, model: str = "arm6", seed: int = SEED):
    """One arm experiment with the settings of the module docstring, identified with the
    joint-motor model: (ExperimentResult, Identification, truth dict)."""
    rate = design_rate_hz(build_experiment_model(model, joint).truth.f1_hz)
    exp = build_experiment_model(model, joint, sample_rate_hz=rate)
    chirp = default_chirp(exp, DURATION)
    chirp = replace(chirp, max_acceleration=ACCELERATION_SHARE * exp.tau_max
                    / (exp.truth.Jm + exp.truth.JL))
    res = run_experiment(model, joint, duration=DURATION, seed=seed, chirp=chirp,
                         sample_rate_hz=rate)
    truth = res.log.truth()
    return res, identify(res.log, "joint-motor", default_settings(rate, truth["f1_hz"])), truth


@pytest.fixture(scope="module")
def arm_runs():
    return {joint: arm_experiment(joint) for joint in JOINTS}


@pytest.mark.parametrize("joint", JOINTS)
def test_arm_joint_motor_accuracy(arm_runs, joint):
    """Issue 3's targets: K, Jm, JL within 0.5 %; FVm, FSm, FV, FS within 5 %; MY within 2 %.
    Measured (seed 1): axis1 K +0.02 % Jm +0.26 % JL +0.08 %, axis4 K -0.24 % Jm +0.22 %
    JL -0.14 %, axis6 K -0.15 % Jm +0.20 % JL -0.06 %; over 8 seeds the worst were 0.25, 0.34
    and 0.15 % (frictions 3.9 %, MY 0.42 %)."""
    res, result, truth = arm_runs[joint]
    assert result.settings.decimated_cutoff_hz > truth["f1_hz"]  # the band holds the mode
    for name, tol in (("K", 0.5), ("Jm", 0.5), ("JL", 0.5), ("FVm", 5), ("FSm", 5),
                      ("FV", 5), ("FS", 5)):
        assert abs(err_pct(result.physical[name], truth[name])) < tol, (name, result.physical[name])
    if joint == "axis1":
        # A vertical axis: gravity has no torque about it in any configuration (MX = MY = 0
        # in the truth), so the 2 % test is void; the identified first moments must instead be
        # indistinguishable from zero (within 3 corrected sigma) and their torque g |MX, MY|
        # under 0.1 % of the torque limit (0.07 % seen).
        assert truth["MX"] == truth["MY"] == 0.0
        for name in ("MX", "MY"):
            value, sigma = result.physical[name], result.physical_sigma_corrected[name]
            assert abs(value) < 3 * sigma, (name, value, sigma)
            assert 9.81 * abs(value) < 1e-3 * res.experiment.tau_max, (name, value)
    else:
        assert abs(err_pct(result.physical["MY"], truth["MY"])) < 2


def test_arm_truth_within_3_sigma_after_bias_correction(arm_runs):
    """Issue 3: the truth within 3 reported sigma for K, Jm, JL on all three joints.

    60 s at 2 kHz pin Jm to 0.03-0.05 %. Least squares alone missed it on some: Jm lay
    +0.10 / +0.16 / +0.10 % (z = 1.5 / 3.3 / 3.9 corrected sigma) above the truth on axes
    1 / 4 / 6, the motor Coulomb friction's bias left once the reversals were placed by the
    identified friction (+0.26 / +0.22 / +0.20 %, 5-7 sigma, before that). With the motor's
    state taken as MuJoCo's RK4 step applies it, over the log's noise (identification/
    coulomb_noise.py), least squares alone is within 3 sigma (z 1.4 / 2.4 / 1.2). The bias correction
    (bench/analysis/debias.py, 4 closed-loop replicas on the nominal axis with the friction
    time constant the log carries) keeps it there. On the dead-beat plant at the default 12
    physics steps a period least squares alone leaves Jm at z 2.71 / 2.76 / 1.49; the z falls
    with the step count toward about 2.5-2.7, the estimator's (docs/design-notes.md, "The
    default physics step"), so this bar is the least-squares one with the least margin."""
    from jointbench.bench.analysis.debias import debias

    z_ls = {joint: (result.physical["Jm"] - truth["Jm"]) / result.physical_sigma_corrected["Jm"]
            for joint, (_, result, truth) in arm_runs.items()}
    assert max(abs(z) for z in z_ls.values()) < 3, z_ls   # least squares alone
    for joint, (res, result, truth) in arm_runs.items():
        d = debias(res.log, result, replicas=4, seed=SEED)
        assert d.replicas == 4, d.failed
        for name in ("K", "Jm", "JL"):
            z = (d.estimate[name] - truth[name]) / d.sigma[name]
            assert abs(z) < 3, (joint, name, z)
            # 0.2 %: with the instruments (issue 17) axis4's K comes out -0.15 % (0.03 % with
            # least squares, whose bias the replicas then took out whole)
            assert abs(err_pct(d.estimate[name], truth[name])) < 0.2, (joint, name)


def test_arm_jm_bias_is_the_motor_coulomb_friction(arm_runs, tmp_path):
    """The cause of the Jm bias, isolated: the same axis4 experiment with the motor's Coulomb
    friction removed (frictionloss 0 on axis4_motor, nothing else changed) brought Jm from
    +0.16 % to +0.02 % with the reversals placed by the identified friction (+0.22 % to
    +0.06 % before that). With the motor's state taken as MuJoCo's RK4 step applies it, over
    the log's noise (identification/coulomb_noise.py), the friction adds nothing measurable: Jm is
    0.050 % off with it and 0.048 % without."""
    spec = mujoco.MjSpec.from_file(str(model_path("arm6")))
    spec.joint("axis4_motor").frictionloss = 0.0
    path = tmp_path / "arm6_no_motor_coulomb.xml"
    path.write_text(spec.to_xml())
    _, without, truth = arm_experiment("axis4", model=str(path))
    _, with_friction, _ = arm_runs["axis4"]
    e_without = abs(err_pct(without.physical["Jm"], truth["Jm"]))
    e_with = abs(err_pct(with_friction.physical["Jm"], truth["Jm"]))
    assert e_without < 0.12 and abs(e_with - e_without) < 0.05, (e_without, e_with)


def test_design_rate_is_twice_eq29():
    """The rate rule: twice eq. (29)'s Fs, which leaves a central-difference distortion of the
    second derivative at the mode, 1 - sinc(w1 Ts)^2 (eq. 24), of 0.12 % (0.47 % at eq. 29's
    own rate, where it biases K and Jm by about 0.2 %)."""
    for f1 in (3.716, 14.68, 18.82, 19.53):
        fs = design_rate_hz(f1)
        assert fs == pytest.approx(2 * design_bandpass(f1, nd=2, m=4).fs_hz, rel=1e-12)
        x = 2 * math.pi * f1 / fs
        assert 1 - np.sinc(x / math.pi) ** 2 == pytest.approx(x ** 2 / 3, rel=0.01)
        assert 1 - np.sinc(x / math.pi) ** 2 < 0.0013
    with pytest.raises(ValueError, match="margin"):
        design_rate_hz(18.8, margin=0.5)


def test_default_settings_hold_the_mode():
    """At the paper's rate the paper's filter for the prototype (f1 near 3.9 Hz or unknown);
    for an arm mode at that rate the filter from f1, whose band holds the mode (the paper's
    Nd = 26 would cut at 5.4 Hz, below it)."""
    paper = default_settings(350.87)
    assert (paper.wn, paper.Nd) == (176.0, 26)
    assert default_settings(350.87, 3.716) == paper
    arm = default_settings(350.87, 18.82)
    assert arm.decimated_cutoff_hz > 18.82 and arm.Nd == 5
    assert arm.wn == pytest.approx(design_bandpass(18.82, nd=2, m=4).wn_rad_s)


def test_simulate_rate_option(tmp_path, capsys):
    out = tmp_path / "a6.csv"
    assert main(["simulate", "--model", "arm6", "--joint", "axis6", "--duration", "5",
                 "--rate", "auto", "--out", str(out), "--quiet"]) == 0
    log = read_log(out)
    assert log.sample_rate_hz == pytest.approx(
        design_rate_hz(float(log.meta["truth_f1_hz"])), rel=1e-3)
    capsys.readouterr()
    assert main(["simulate", "--model", "arm6", "--duration", "5", "--rate", "1000",
                 "--out", str(out), "--quiet", "--json"]) == 0
    assert read_log(out).sample_rate_hz == pytest.approx(1000.0)
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "--model", "arm6", "--rate", "fast", "--out", str(out)])
    assert exc.value.code == 2
    assert "neither a rate in Hz nor 'auto'" in capsys.readouterr().err
