"""`diagnose` on the lab-rig family (tests/indep_sim.py `simulate_lab_rig`): a horizontal
axis under a P loop. What the log cannot identify is exactly zero, the forward view runs the
P loop, the MJCF it writes compiles, and every file the report names exists."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from jointbench.testing.simulator import simulate_lab_rig

from jointbench.bench.analysis.diagnose.report import write
from jointbench.bench.analysis.diagnose.run import diagnose
from jointbench.bench.sim import nominal as nominal_axes


@pytest.fixture(scope="module")
def lab_log():
    """The lab rig, seed 9, 20 s (read only: the tests derive copies with replace)."""
    return simulate_lab_rig(seed=9, duration=20.0)


@pytest.fixture(scope="module")
def diagnosis(lab_log):
    return diagnose(lab_log)


def test_horizontal_axis_has_exactly_zero_first_moments(diagnosis):
    p = diagnosis.nominal_parameters
    assert p["MX"] == 0.0 and p["MY"] == 0.0


def test_forward_view_runs_the_p_loop(diagnosis):
    assert diagnosis.forward_nominal is not None, diagnosis.forward_note
    # the true axis replayed: the error is the encoders' and the voltage noise's (a few mrad)
    assert diagnosis.forward_nominal.q_m_rms < 0.01


def test_every_file_the_report_names_exists(diagnosis, tmp_path):
    out = tmp_path / "diag"
    d = write(diagnosis, out, lambda msg: None)
    assert (out / "nominal.xml").is_file()
    for f in d.files:
        assert Path(f).is_file(), f
    report = (out / "report.md").read_text()
    for name in set(re.findall(r"`?([\w.-]+\.(?:xml|png|json))`?", report)):
        assert (out / name).is_file(), name


def test_a_link_mass_mujoco_refuses_is_a_clear_error():
    with pytest.raises(ValueError, match="MuJoCo refuses"):
        nominal_axes.two_mass_axis(Jm=0.002, FVm=0.07, FSm=0.0, K=1.6, JL=0.0035, MY=-7e-13,
                                   timestep=0.002)


def test_without_a_controller_the_motor_driven_view_runs(lab_log):
    """A vendor drive whose loop nobody knows: no controller metadata. The motor-driven view
    (q_m drives the model) judges the nominal model: the truth leaves the encoders' and the
    voltage noise's share, a stiffness 10 % off several times more."""
    from dataclasses import replace as rep

    from jointbench.identification.motor_driven import motor_driven_view

    log = lab_log
    bare = rep(log, meta={k: v for k, v in log.meta.items()
                          if k not in ("controller", "pid_kp", "feedback")})
    d = diagnose(bare)
    assert d.forward_nominal is None and "motor-driven view" in d.forward_note
    truth = {k: float(log.meta[f"truth_{k}"]) for k in
             ("Jm", "FVm", "FSm", "K", "JL", "FV", "FS", "MX", "MY")}
    good = motor_driven_view(log, truth, 8.0)
    bad = motor_driven_view(log, {**truth, "K": 1.1 * truth["K"]}, 8.0)
    assert bad.q_rms > 3 * good.q_rms and bad.tau_rel_pct > 3 * good.tau_rel_pct
    assert good.q_rel_pct < 2.0


def test_the_forward_note_says_why_the_loop_is_not_replayed():
    """No q_ref (an open-loop run), a P loop without its torque limit, no controller: each
    note names what is missing."""
    from dataclasses import replace as rep

    from jointbench.bench.analysis.diagnose.forward import no_replay_note

    log = simulate_lab_rig(seed=9, duration=2.0)
    assert "no q_ref column" in no_replay_note(rep(log, q_ref=None))
    no_limit = rep(log, meta={k: v for k, v in log.meta.items() if k != "tau_max"})
    assert "P loop lacks tau_max" in no_replay_note(no_limit)
    bare = rep(log, meta={k: v for k, v in log.meta.items() if k != "controller"
                          and not k.startswith("pid_")})
    assert "does not describe the controller" in no_replay_note(bare)
