"""Issue 17: `simulate` warns when an MJCF's MuJoCo Coulomb friction is too soft for the
paper's FS sign(v) (bench/sim/friction.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from jointbench.bench.present.experiment import friction_warnings
from jointbench.bench.sim.defaults import DEFAULT_SUBSTEPS
from jointbench.bench.sim.experiment import run_experiment
from jointbench.bench.sim.friction import friction_bands

ARM6 = Path(__file__).resolve().parents[2] / "models" / "arm6.xml"


def test_band_is_the_constraint_ramp():
    """v_b = FS dmax timeconst / (2 J): arm6 axis1's motor, FS 35 N m, J 36 kg m^2,
    dmax 0.999, timeconst two physics steps (refsafe raises the model's 1 us to them), the
    physics step the period of 350.87 Hz over the default sub-steps."""
    exp = run_experiment("arm6", "axis1", duration=5.0, seed=1).experiment
    motor = friction_bands(exp.model, exp.axis.motor_dof, exp.axis.link_dof)[0]
    tc = 2 / (350.87 * DEFAULT_SUBSTEPS)
    assert motor.dof == "motor" and motor.timeconst == pytest.approx(tc, rel=1e-9)
    assert motor.dead_beat   # semi-implicit Euler at two steps: no ramp, the stick
    assert motor.v_band == pytest.approx(35 * 0.999 * tc / (2 * 36), rel=1e-6)


def test_mujocos_default_softness_is_warned_and_the_shipped_arm_is_not(tmp_path):
    """MuJoCo's default solreffriction (0.02 s) on arm6: the motor's ramp reaches 0.0097 rad/s
    and misses FS sign(v) by about 6 % of the torque RMS (measured 5.8 %), over the 1 % bar.
    The shipped arm's dead-beat friction has no ramp."""
    soft = tmp_path / "arm6_soft.xml"
    text = ARM6.read_text()
    assert 'solreffriction="0.000001 1"' in text
    soft.write_text(text.replace('solreffriction="0.000001 1"', 'solreffriction="0.02 1"'))
    warned = friction_warnings(run_experiment(soft, duration=20.0, seed=1))
    assert warned and "motor friction is soft" in warned[0] and "solreffriction=" in warned[0]
    assert friction_warnings(run_experiment("arm6", duration=20.0, seed=1)) == []
