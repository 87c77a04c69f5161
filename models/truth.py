"""Ground truth of an axis under the paper's names, read from the compiled MuJoCo model."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import mujoco
import numpy as np

from jointbench.models import Axis, gear_ratio


@dataclass(frozen=True)
class AxisTruth:
    """Parameters of eqs. (5)-(7) for one axis in one locked configuration (joint side, SI).

    `JL` = M_jj(q_L) (eq. 5) from MuJoCo's mass matrix; `MX`, `MY` the first moments of eq. (7)
    from MuJoCo's gravity torque; `q0` the rest position of eq. (17); `f1_hz` the locked first
    mode sqrt(K (1/Jm + 1/JL)) / 2 pi.
    """

    K: float
    Jm: float
    JL: float
    FVm: float
    FSm: float
    FV: float
    FS: float
    MX: float
    MY: float
    q0: float
    f1_hz: float
    g: float
    gear_ratio: float | None

    def as_dict(self) -> dict[str, float]:
        return {k: v for k, v in asdict(self).items() if v is not None}


def gravity_torque(model: mujoco.MjModel, data: mujoco.MjData, dof: int) -> float:
    """Q of eq. (7) at the current qpos: the gravity part of qfrc_bias at `dof` (zero velocity)."""
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)
    return float(data.qfrc_bias[dof])


def axis_truth(model: mujoco.MjModel, axis: Axis, qpos: np.ndarray) -> AxisTruth:
    """Ground truth of `axis` with every joint at `qpos` (the other axes locked there)."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    M = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    JL = float(M[axis.link_dof, axis.link_dof])
    g = float(np.linalg.norm(model.opt.gravity))
    if g > 0:
        # Eq. (7) is A cos q + B sin q exactly when the other joints are fixed.
        data.qpos[axis.link_qpos] = 0.0
        MX = gravity_torque(model, data, axis.link_dof) / g
        data.qpos[axis.link_qpos] = math.pi / 2
        MY = gravity_torque(model, data, axis.link_dof) / g
    else:
        MX = MY = 0.0
    scale = max(abs(MX), abs(MY))
    if scale < 1e-12:
        q0 = 0.0  # gravity acts on nothing along this axis: every position is a rest position
    elif abs(MY) < 1e-12 * scale:
        q0 = -math.copysign(math.pi / 2, MX)
    else:
        q0 = -math.atan(MX / MY)  # eq. (17)
    if axis.rigid:
        return rigid_axis_truth(model, axis, JL, MX, MY, q0, g)
    Jm = float(model.dof_armature[axis.motor_dof])
    K = float(model.tendon_stiffness[axis.tendon])
    return AxisTruth(
        K=K, Jm=Jm, JL=JL,
        FVm=float(model.dof_damping[axis.motor_dof]),
        FSm=float(model.dof_frictionloss[axis.motor_dof]),
        FV=float(model.dof_damping[axis.link_dof]),
        FS=float(model.dof_frictionloss[axis.link_dof]),
        MX=MX, MY=MY, q0=q0,
        f1_hz=math.sqrt(K * (1.0 / Jm + 1.0 / JL)) / (2 * math.pi), g=g,
        gear_ratio=gear_ratio(model, axis.name))


def rigid_axis_truth(model: mujoco.MjModel, axis: Axis, M_jj: float, MX: float, MY: float,
                     q0: float, g: float) -> AxisTruth:
    """Truth of a rigid axis (models/__init__.py): one joint `X`, so K and f1 are infinite;
    as in the two-mass convention the joint's armature is the rotor inertia Jm, the rest of
    M_jj the link inertia JL, and joint `X`'s damping and frictionloss are FV and FS (FVm =
    FSm = 0). The rigid model's parameters are J = Jm + JL, FV and FS."""
    Jm = float(model.dof_armature[axis.motor_dof])
    return AxisTruth(
        K=math.inf, Jm=Jm, JL=M_jj - Jm, FVm=0.0, FSm=0.0,
        FV=float(model.dof_damping[axis.link_dof]),
        FS=float(model.dof_frictionloss[axis.link_dof]),
        MX=MX, MY=MY, q0=q0, f1_hz=math.inf, g=g, gear_ratio=gear_ratio(model, axis.name))
