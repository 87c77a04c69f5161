"""Ground truth read from the MJCF models against the paper's Table 1 and MuJoCo's own
mass matrix and gravity torque."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from jointbench.bench.sim.axes import build_experiment_model, full_qpos
from jointbench.models import ModelStructureError, load_model
from jointbench.models.truth import axis_truth

TABLE1 = {"Jm": 174.7996, "K": 20341.0458, "JL": 47.4458, "FSm": 41.4254, "FVm": 235.9100,
          "FV": 83.1508, "MX": -0.7241, "MY": -53.4201, "FS": 8.4612}


def test_prototype_truth_is_table1():
    model, axes, _ = load_model("prototype")
    truth = axis_truth(model, axes[0], model.qpos0.copy())
    for name, value in TABLE1.items():
        # The MJCF is written from Table 1; 1e-6 relative covers the 6-7 digit XML values.
        assert getattr(truth, name) == pytest.approx(value, rel=1e-6), name
    assert truth.q0 == pytest.approx(-math.atan(TABLE1["MX"] / TABLE1["MY"]), abs=1e-12)  # eq. 17


def test_gravity_torque_is_eq7():
    """Q(q) = MX g cos q + MY g sin q for any q (eq. 7), from MuJoCo's qfrc_bias."""
    model, axes, _ = load_model("prototype")
    data = mujoco.MjData(model)
    ax = axes[0]
    for q in np.linspace(-2, 2, 7):
        data.qpos[:] = q
        mujoco.mj_forward(model, data)
        expected = 9.81 * (TABLE1["MX"] * math.cos(q) + TABLE1["MY"] * math.sin(q))
        assert data.qfrc_bias[ax.link_dof] == pytest.approx(expected, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("config", [{}, {"axis2": -0.5, "axis3": 1.0}])
def test_arm_truth_against_mass_matrix_and_locking(config):
    """JL = M_jj(q_L) of the full arm, and the rigidly locked 2-DOF experiment model has the
    same link inertia (locking by MjSpec is exact), in two configurations."""
    full, axes, _ = load_model("arm6")
    assert len(axes) == 6
    qpos = full_qpos(full, axes, config)
    data = mujoco.MjData(full)
    data.qpos[:] = qpos
    mujoco.mj_forward(full, data)
    M = np.zeros((full.nv, full.nv))
    mujoco.mj_fullM(full, data, M)
    for ax in axes:
        truth = axis_truth(full, ax, qpos)
        assert truth.JL == pytest.approx(M[ax.link_dof, ax.link_dof], rel=1e-12)
        assert 5.0 <= truth.f1_hz <= 25.0, (ax.name, truth.f1_hz)
        exp = build_experiment_model("arm6", ax.name, config=config, center=qpos[ax.link_qpos])
        assert exp.model.nv == 2
        d = mujoco.MjData(exp.model)
        d.qpos[:] = exp.qpos_init
        mujoco.mj_forward(exp.model, d)
        Mr = np.zeros((2, 2))
        mujoco.mj_fullM(exp.model, d, Mr)
        # 1e-6: the welded bodies go through a quaternion product and renormalisation
        assert Mr[exp.axis.link_dof, exp.axis.link_dof] == pytest.approx(truth.JL, rel=1e-6)


def test_arm_gravity_first_moments():
    """MX, MY of an arm axis reproduce MuJoCo's gravity torque at other angles of that axis."""
    full, axes, _ = load_model("arm6")
    config = {"axis2": -0.5, "axis3": 1.0}
    ax = axes[1]
    truth = axis_truth(full, ax, full_qpos(full, axes, config))
    data = mujoco.MjData(full)
    for q in (-0.7, 0.3, 1.1):
        data.qpos[:] = full_qpos(full, axes, {**config, "axis2": q})
        mujoco.mj_forward(full, data)
        expected = truth.g * (truth.MX * math.cos(q) + truth.MY * math.sin(q))
        assert data.qfrc_bias[ax.link_dof] == pytest.approx(expected, rel=1e-9)


def test_structure_errors_are_named(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text('<mujoco><worldbody><body><joint name="j"/><geom size=".1"/></body>'
                   "</worldbody></mujoco>")
    with pytest.raises(ModelStructureError, match="no flexible axis"):
        load_model(bad)
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody>")
    with pytest.raises(ModelStructureError, match="cannot load"):
        load_model(broken)
    with pytest.raises(ModelStructureError, match="no such model"):
        load_model(tmp_path / "missing.xml")
    with pytest.raises(ModelStructureError, match="no axis 'axis9'"):
        build_experiment_model("arm6", "axis9")
