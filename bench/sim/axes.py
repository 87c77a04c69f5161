"""Build the model of one experiment: one axis moves, the others are locked (paper eqs. 5-6).

Rigid axes (models/__init__.py: one joint `X` driven by actuator `X_motor`) are accepted too:
moving, the motor torque drives the joint directly; locked, the joint is welded (`rigid`) or
held by its brake, which for a rigid axis is the same thing.

Locking edits the MJCF with MjSpec:
- `rigid` (default): each other axis is welded at its angle (its link body is rotated about
  the joint axis and both joints are removed), exactly the reduced model of eqs. (5)-(6);
- `brake`: only the other motors are held (what a real robot's brakes do); their links keep
  their hinge and the joint spring, referred to the braked motor angle, so they stay elastic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from jointbench.bench.effects import HiddenEffect, apply_to_spec, as_effects, strength_of
from jointbench.bench.sim.defaults import default_substeps
from jointbench.models import (Axis, ModelStructureError, find_axes, load_model, select_axis,
                               torque_limit)
from jointbench.models.truth import AxisTruth, axis_truth
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.effects import EFFECTS

LOCKS = ("rigid", "brake")
# Effects that act on the spring or split motor and link friction: meaningless on a rigid axis.
RIGID_AXIS_REFUSES = tuple(name for name, e in EFFECTS.items() if not e.rigid_axis)


@dataclass(frozen=True)
class ExperimentModel:
    """The compiled single-axis model with what the experiment needs to know about it."""

    model: mujoco.MjModel
    axis: Axis              # indices in `model`
    truth: AxisTruth        # ground truth in the locked configuration
    center: float           # link angle the experiment is centred on [rad]
    qpos_init: np.ndarray   # static equilibrium at `center`
    tau0: float             # motor torque holding that equilibrium [N m]
    tau_max: float
    source: Path
    lock: str
    config: dict[str, float]


def secant_root(residual, x0: float, slope: float, rtol: float, kick: float) -> float:
    """Root of a residual that is piecewise linear in x (a spring, dead bands included) by
    secant iterations from the Newton step x0 - r(x0) / slope; `kick` keeps the first two
    points apart. Converges in a few steps; at most 60."""
    a = x0
    ra = residual(a)
    b = a - ra / slope + kick
    for _ in range(60):
        rb = residual(b)
        if abs(rb) < rtol * max(1.0, abs(ra)) or rb == ra:
            break
        a, b, ra = b, b - rb * (b - a) / (rb - ra), rb
    return float(b)


def _rotate_body(body: mujoco.MjsBody, pos: np.ndarray, quat: np.ndarray,
                 jpos: np.ndarray, jaxis: np.ndarray, angle: float) -> None:
    """Bake a hinge rotation `angle` about (jpos, jaxis) into the body's frame."""
    qrot = np.zeros(4)
    mujoco.mju_axisAngle2Quat(qrot, jaxis, angle)
    moved = np.zeros(3)
    mujoco.mju_rotVecQuat(moved, jpos, qrot)
    delta = np.zeros(3)
    mujoco.mju_rotVecQuat(delta, jpos - moved, quat)
    newquat = np.zeros(4)
    mujoco.mju_mulQuat(newquat, quat, qrot)
    body.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    body.pos = pos + delta
    body.quat = newquat


def _slide_body(body: mujoco.MjsBody, pos: np.ndarray, quat: np.ndarray, jaxis: np.ndarray,
                dist: float) -> None:
    delta = np.zeros(3)
    mujoco.mju_rotVecQuat(delta, jaxis * dist, quat)
    body.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    body.pos = pos + delta
    body.quat = quat


def full_qpos(model: mujoco.MjModel, axes: list[Axis], config: dict[str, float]) -> np.ndarray:
    """qpos of the full model with each link at config[axis] (default 0) and each motor at
    its link's angle (the spring deflection is settled later, on the reduced model)."""
    known = {a.name for a in axes}
    unknown = set(config) - known
    if unknown:
        raise ModelStructureError(f"no axis named {', '.join(sorted(unknown))} "
                                  f"(axes: {', '.join(a.name for a in axes)})")
    qpos = model.qpos0.copy()
    for a in axes:
        angle = config.get(a.name, 0.0)
        qpos[a.link_qpos] = angle
        qpos[a.motor_qpos] = angle
    return qpos


# Secant settings of `static_position` per free coordinate: (relative tolerance, first kick).
_SETTLE = {"motor": (1e-9, 1e-9), "link": (1e-10, 1e-12)}


def _at_rest(model: mujoco.MjModel, data: mujoco.MjData, qpos: np.ndarray) -> None:
    """Forward kinematics and forces of `qpos` with every velocity zero."""
    data.qpos[:] = qpos
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)


def static_position(model: mujoco.MjModel, axis: Axis, qpos: np.ndarray,
                    free: str = "motor") -> float:
    """The position of the `free` coordinate ("motor" or "link") at which the spring holds the
    link at rest, every other coordinate as in `qpos` (eq. 5 with qd = qdd = 0): secant
    iterations from zero deflection (the residual is linear for a linear spring, rising with
    q_m and falling with q at slope K). A rigid axis stays where it is."""
    if axis.rigid:
        return float(qpos[axis.motor_qpos])
    moving, start = (axis.motor_qpos, axis.link_qpos) if free == "motor" else \
        (axis.link_qpos, axis.motor_qpos)
    data = mujoco.MjData(model)
    q = qpos.copy()

    def residual(x: float) -> float:
        q[moving] = x
        _at_rest(model, data, q)
        return float(data.qfrc_passive[axis.link_dof] - data.qfrc_bias[axis.link_dof])

    K = float(model.tendon_stiffness[axis.tendon]) or 1.0
    rtol, kick = _SETTLE[free]
    return secant_root(residual, float(qpos[start]), K if free == "motor" else -K, rtol, kick)


def static_link_position(model: mujoco.MjModel, axis: Axis, qpos: np.ndarray) -> float:
    """Link position at rest with the motor held at qpos[axis.motor_qpos] (`static_position`);
    equals q_m for a rigid axis."""
    return static_position(model, axis, qpos, "link")


def _static_equilibrium(model: mujoco.MjModel, axis: Axis, qpos: np.ndarray,
                        tau_extra: float = 0.0) -> tuple[np.ndarray, float]:
    """Settle the moving axis' motor so that the spring holds the link at rest
    (`static_position`) and return (qpos, tau0) with tau0 the holding motor torque. A rigid
    axis stays where it is; tau0 holds gravity, passive forces and any passive actuator
    (offset)."""
    data = mujoco.MjData(model)
    qpos = qpos.copy()
    d = axis.motor_dof
    if axis.rigid:
        data.ctrl[:] = 0.0
        _at_rest(model, data, qpos)
        tau0 = float(data.qfrc_bias[d] - data.qfrc_passive[d] - data.qfrc_actuator[d]) + tau_extra
        return qpos, tau0
    qpos[axis.motor_qpos] = static_position(model, axis, qpos, "motor")
    _at_rest(model, data, qpos)
    tau0 = -float(data.qfrc_passive[d] - data.qfrc_bias[d]) + tau_extra
    return qpos, tau0


def _missing_axis(model: mujoco.MjModel, joint: str, path: Path, names: list[str]) -> str:
    """Why `joint` is not an axis of `model`: the part of the convention it lacks."""
    def has(obj, name: str) -> bool:
        return mujoco.mj_name2id(model, obj, name) >= 0

    J, T, A = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_TENDON, mujoco.mjtObj.mjOBJ_ACTUATOR
    if has(J, joint) and has(J, f"{joint}_motor") and not has(T, f"{joint}_spring"):
        return (f"{path}: axis '{joint}': joints '{joint}' and '{joint}_motor' exist but no "
                f"fixed tendon '{joint}_spring' couples them (stiffness K; models/__init__.py)")
    if has(J, joint) and not has(A, f"{joint}_motor"):
        return f"{path}: axis '{joint}': joint '{joint}' has no actuator '{joint}_motor'"
    return f"{path}: no axis '{joint}' (axes: {', '.join(names)})"


def build_experiment_model(model: str | Path = "prototype", joint: str | None = None,
                           config: dict[str, float] | None = None, center: float | None = None,
                           lock: str = "rigid",
                           effect: HiddenEffect | tuple[HiddenEffect, ...] | None = None,
                           substeps: int | None = None, sample_rate_hz: float = PAPER_RATE,
                           tau_max: float | None = None) -> ExperimentModel:
    """Compile the experiment model of axis `joint` (default: the first axis).

    `joint` is an axis name or its index counting from 1 (`models.select_axis`). `config`
    gives the locked angles of the other axes (default 0); `center` the link angle the chirp
    is centred on (default: the moving axis' entry of `config`, else the rest position q0 of
    eq. 17, shifted by the hidden `gravity` effect's offset). Raises ModelStructureError for
    a model that does not follow the axis convention and ValueError for bad arguments.
    """
    effects = as_effects(effect)   # one hidden effect, several, or none
    if lock not in LOCKS:
        raise ValueError(f"lock must be one of {', '.join(LOCKS)}, got {lock!r}")
    if substeps is None:
        substeps = default_substeps(sample_rate_hz)
    if substeps < 1:
        raise ValueError(f"substeps must be >= 1, got {substeps}")
    if Path(str(model)).is_dir():
        raise ModelStructureError(f"{model}: is a directory, not an MJCF file")
    full, axes, path = load_model(model)
    names = [a.name for a in axes]
    if joint is not None and joint not in names and not str(joint).strip().isdigit():
        raise ModelStructureError(_missing_axis(full, joint, path, names))
    for j in range(full.njnt):  # a rotor joint outside every axis would move unmodelled
        jname = mujoco.mj_id2name(full, mujoco.mjtObj.mjOBJ_JOINT, j) or ""
        if jname.endswith("_motor") and jname[:-len("_motor")] not in names:
            raise ModelStructureError(_missing_axis(full, jname[:-len("_motor")], path, names))
    moving = select_axis(axes, joint, str(path))
    joint = moving.name
    config = dict(config or {})
    qpos_full = full_qpos(full, axes, config)
    truth = axis_truth(full, moving, qpos_full)
    if moving.rigid and not (truth.Jm > 0 and truth.JL > 0):
        raise ModelStructureError(
            f"{path}: rigid axis '{joint}': give the rotor inertia as the armature of joint "
            f"'{joint}' and the moving body a mass (Jm = {truth.Jm:g}, JL = {truth.JL:g}); "
            "the default gain rule needs both")
    if center is None and joint in config:  # the moving axis' own entry centres the chirp
        center = config[joint]
    if center is None:
        center = truth.q0 + strength_of(effects, "gravity")
    config[joint] = center
    qpos_full = full_qpos(full, axes, config)

    # Static torque each braked link needs (spring referred to the braked motor angle).
    data = mujoco.MjData(full)
    data.qpos[:] = qpos_full
    mujoco.mj_forward(full, data)
    hold = {a.name: float(data.qfrc_bias[a.link_dof]) for a in axes}

    spec = mujoco.MjSpec.from_file(str(path))
    refused = [e.name for e in effects if e.name in RIGID_AXIS_REFUSES]
    if moving.rigid and refused:
        raise ModelStructureError(
            f"{path}: effect '{refused[0]}' needs a flexible axis (spring, link and motor "
            f"friction); axis '{joint}' is rigid")
    for a in axes:
        if a.name == joint:
            continue
        spec.delete(spec.actuator(f"{a.name}_motor"))
        if a.rigid:
            passive = spec.actuator(f"{a.name}_offset")
            if passive is not None:
                spec.delete(passive)
        else:
            spec.delete(spec.tendon(f"{a.name}_spring"))
            hardening = spec.tendon(f"{a.name}_hardening")
            if hardening is not None:
                spec.delete(hardening)
            spec.delete(spec.body(full.body(full.jnt_bodyid[a.motor_joint]).name))
        link = spec.joint(a.name)
        angle = config.get(a.name, 0.0)
        if lock == "rigid" or a.rigid:
            bid = full.jnt_bodyid[a.link_joint]
            body = spec.body(full.body(bid).name)
            if int(full.jnt_type[a.link_joint]) == int(mujoco.mjtJoint.mjJNT_HINGE):
                _rotate_body(body, full.body_pos[bid].copy(), full.body_quat[bid].copy(),
                             full.jnt_pos[a.link_joint].copy(), full.jnt_axis[a.link_joint].copy(),
                             angle)
            else:
                _slide_body(body, full.body_pos[bid].copy(), full.body_quat[bid].copy(),
                            full.jnt_axis[a.link_joint].copy(), angle)
            spec.delete(link)
        else:
            K = float(full.tendon_stiffness[a.tendon])
            link.stiffness[0] = K
            link.springref = angle + hold[a.name] / K
    for e in effects:
        apply_to_spec(spec, joint, e,
                      math.inf if moving.rigid else float(full.tendon_stiffness[moving.tendon]))
    T = 1.0 / sample_rate_hz
    spec.option.timestep = T / substeps
    try:
        reduced = spec.compile()
    except ValueError as err:
        raise ModelStructureError(f"{path}: the experiment model does not compile: {err}") from None
    axis = [a for a in find_axes(reduced, str(path)) if a.name == joint][0]
    qpos = reduced.qpos0.copy()
    for j in range(reduced.njnt):
        name = reduced.joint(j).name
        base = name[: -len("_motor")] if name.endswith("_motor") else name
        if base in config:
            qpos[reduced.jnt_qposadr[j]] = config[base]
    offset = strength_of(effects, "offset")
    qpos, tau0 = _static_equilibrium(reduced, axis, qpos, offset)
    if tau_max is None:
        tau_max = torque_limit(full, moving)
    if tau_max is None:
        # No ctrlrange: allow ten times the static and rigid-body chirp torque scale.
        # A rigid axis (f1 infinite) takes the top of the default chirp, 30 Hz.
        f_top = truth.f1_hz if math.isfinite(truth.f1_hz) else 30.0
        tau_max = 10.0 * max(abs(tau0), (truth.Jm + truth.JL) * (2 * math.pi * f_top) ** 2 * 0.05, 1.0)
    return ExperimentModel(model=reduced, axis=axis, truth=truth, center=float(center),
                           qpos_init=qpos, tau0=tau0, tau_max=float(tau_max), source=path,
                           lock=lock, config=config)
