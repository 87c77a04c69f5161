"""MJCF robots of jointbench and the code that reads their structure and ground truth.

Axis convention (every joint of every shipped model, and any user model that wants to run):
for an axis named X,
  - hinge (or slide) `X`         the link joint: damping FV, frictionloss FS;
  - hinge (or slide) `X_motor`   the rotor joint: armature Jm, damping FVm, frictionloss FSm;
  - fixed tendon `X_spring`      length q_m - q (coef +1 on `X_motor`, -1 on `X`), stiffness K;
  - motor actuator `X_motor`     the motor torque tau_m on `X_motor` (ctrlrange = torque limit);
  - optional `<numeric name="X_gear_ratio">`.
All values are referred to the joint side, as in the paper.

A rigid axis (no joint stiffness, the `rigid` identification model) is the same convention
without rotor joint and spring:
  - hinge (or slide) `X`         the axis joint: its whole inertia (armature and body), damping
                                 FV, frictionloss FS;
  - motor actuator `X_motor`     the motor torque (force, for a slide) on `X` itself;
  - optional passive actuator `X_offset` (gain 0, constant bias force): a constant load.
There must be no joint `X_motor` and no tendon `X_spring`; `Axis.rigid` is True and its motor
and link indices coincide (q = q_m).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

MODELS_DIR = Path(__file__).resolve().parent
SHIPPED = {"prototype": "prototype_axis.xml", "prototype_axis": "prototype_axis.xml",
           "arm6": "arm6.xml"}
# A gear ratio beyond this turns a motor-side encoder step or torque into a value the log
# format refuses (identification.log.read.MAX_ABS_VALUE is 1e12): a typo, not a gearbox.
MAX_GEAR_RATIO = 1e6


class ModelStructureError(ValueError):
    """An MJCF model that does not follow the jointbench axis convention."""


def model_path(name: str | Path) -> Path:
    """Path of a shipped model (`prototype`, `arm6`) or of a user's MJCF file."""
    key = str(name)
    if key in SHIPPED:
        return MODELS_DIR / SHIPPED[key]
    path = Path(name)
    if not path.exists():
        raise ModelStructureError(
            f"{path}: no such model file (shipped models: {', '.join(sorted(set(SHIPPED) - {'prototype_axis'}))})")
    return path


@dataclass(frozen=True)
class Axis:
    """Indices of one axis in a compiled model. For a rigid axis `tendon` is -1 and the motor
    indices equal the link indices (one joint)."""

    name: str
    link_joint: int
    motor_joint: int
    tendon: int
    actuator: int
    link_qpos: int
    motor_qpos: int
    link_dof: int
    motor_dof: int

    @property
    def rigid(self) -> bool:
        """True for a rigid axis (one joint driven directly, no spring)."""
        return self.tendon < 0


def _name(model: mujoco.MjModel, obj: mujoco.mjtObj, index: int) -> str:
    return mujoco.mj_id2name(model, obj, index) or ""


def _suffixed(model: mujoco.MjModel, objtype, count: int, suffix: str):
    """(index, name, axis) of the objects of `objtype` named AXIS + `suffix`."""
    for i in range(count):
        name = _name(model, objtype, i)
        if name.endswith(suffix):
            yield i, name, name[: -len(suffix)]


def _rigid_axes(model: mujoco.MjModel, source: str, flexible: set[str]) -> list[Axis]:
    """Rigid axes: an actuator `X_motor` with a joint transmission to joint `X`, no joint
    `X_motor`, no tendon `X_spring` (module docstring), in actuator order."""
    axes = []
    for act, aname, axis in _suffixed(model, mujoco.mjtObj.mjOBJ_ACTUATOR, model.nu, "_motor"):
        if axis in flexible or mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, aname) >= 0:
            continue  # flexible axis, or a malformed one that find_axes reports
        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, axis)
        if j < 0:
            continue  # no joint X: not an axis (an extra actuator of an extended model)
        if int(model.actuator_trntype[act]) != int(mujoco.mjtTrn.mjTRN_JOINT) or \
                model.actuator_trnid[act, 0] != j:
            raise ModelStructureError(
                f"{source}: actuator '{aname}' of the rigid axis '{axis}' must drive joint '{axis}'")
        if int(model.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                         int(mujoco.mjtJoint.mjJNT_SLIDE)):
            raise ModelStructureError(f"{source}: joint '{axis}' must be a hinge or slide")
        qadr, dadr = int(model.jnt_qposadr[j]), int(model.jnt_dofadr[j])
        axes.append(Axis(axis, j, j, -1, act, qadr, qadr, dadr, dadr))
    return axes


def find_axes(model: mujoco.MjModel, source: str = "<model>") -> list[Axis]:
    """The axes of `model`: the flexible ones in tendon order, then the rigid ones in
    actuator order. ModelStructureError names what is missing or malformed when the model
    does not follow the axis convention."""
    axes = []
    for tid, tname, axis in _suffixed(model, mujoco.mjtObj.mjOBJ_TENDON, model.ntendon,
                                      "_spring"):
        adr, num = model.tendon_adr[tid], model.tendon_num[tid]
        wraps = {}
        for w in range(adr, adr + num):
            if int(model.wrap_type[w]) != int(mujoco.mjtWrap.mjWRAP_JOINT):
                raise ModelStructureError(f"{source}: tendon '{tname}' must be a fixed tendon")
            joint = _name(model, mujoco.mjtObj.mjOBJ_JOINT, model.wrap_objid[w])
            wraps[joint] = float(model.wrap_prm[w])  # a plain float in the message
        expected = {f"{axis}_motor": 1.0, axis: -1.0}
        if wraps != expected:
            raise ModelStructureError(
                f"{source}: tendon '{tname}' must couple joint '{axis}_motor' (coef 1) and "
                f"joint '{axis}' (coef -1); it has {wraps or 'no joints'}")
        jl = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, axis)
        jm = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"{axis}_motor")
        act = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"{axis}_motor")
        if act < 0:
            raise ModelStructureError(f"{source}: axis '{axis}' has no actuator '{axis}_motor'")
        if model.actuator_trnid[act, 0] != jm:
            raise ModelStructureError(
                f"{source}: actuator '{axis}_motor' must drive joint '{axis}_motor'")
        for j in (jl, jm):
            if int(model.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                             int(mujoco.mjtJoint.mjJNT_SLIDE)):
                raise ModelStructureError(
                    f"{source}: joint '{_name(model, mujoco.mjtObj.mjOBJ_JOINT, j)}' must be a hinge or slide")
        axes.append(Axis(axis, jl, jm, tid, act, int(model.jnt_qposadr[jl]),
                         int(model.jnt_qposadr[jm]), int(model.jnt_dofadr[jl]),
                         int(model.jnt_dofadr[jm])))
    axes += _rigid_axes(model, source, {a.name for a in axes})
    for axis in axes:
        check_values(model, axis, source)
    if not axes:
        raise ModelStructureError(
            f"{source}: no flexible axis found, nor a rigid one: expected a fixed tendon 'X_spring' coupling "
            "joints 'X_motor' and 'X', and an actuator 'X_motor' (flexible axis), or an "
            "actuator 'X_motor' driving joint 'X' (rigid axis) (see models/__init__.py)")
    return axes


def _not_physical(source: str, element: str, attribute: str, value: float, wanted: str
                  ) -> ModelStructureError:
    return ModelStructureError(f"{source}: {element}: {attribute}=\"{value:g}\" is not "
                               f"physical; it must be {wanted}")


def check_values(model: mujoco.MjModel, axis: Axis, source: str = "<model>") -> None:
    """ModelStructureError, naming the file, the element and the attribute, for a value of
    `axis` that no physical axis has (each would give zero gains, the square root of a
    negative, a division by zero or a dropped row): a spring stiffness K or a rotor armature
    Jm that is not finite and > 0, a damping, frictionloss, armature or joint stiffness that
    is not finite and >= 0, an actuator gear other than 1 (tau_m is the torque on the rotor
    joint, already referred to the joint side: the gear ratio goes into
    `<numeric name="X_gear_ratio">`), a gear ratio that is not finite and in
    (0, MAX_GEAR_RATIO]."""
    def check(element: str, attribute: str, value: float, positive: bool, what: str = ""):
        if not (np.isfinite(value) and (value > 0 if positive else value >= 0)):
            raise _not_physical(source, element, attribute, float(value),
                                ("finite and > 0" if positive else "finite and >= 0") + what)

    for j in sorted({axis.link_joint, axis.motor_joint}):
        name = f"joint '{_name(model, mujoco.mjtObj.mjOBJ_JOINT, j)}'"
        dof = int(model.jnt_dofadr[j])
        rotor = j == axis.motor_joint and not axis.rigid
        check(name, "armature", model.dof_armature[dof], rotor,
              " (the rotor inertia Jm)" if rotor else "")
        check(name, "damping", model.dof_damping[dof], False)
        check(name, "frictionloss", model.dof_frictionloss[dof], False)
        check(name, "stiffness", model.jnt_stiffness[j], False)
    if not axis.rigid:
        name = f"tendon '{_name(model, mujoco.mjtObj.mjOBJ_TENDON, axis.tendon)}'"
        check(name, "stiffness", float(np.ravel(model.tendon_stiffness[axis.tendon])[0]), True,
              " (the joint stiffness K)")
        check(name, "damping", float(np.ravel(model.tendon_damping[axis.tendon])[0]), False)
        check(name, "frictionloss", float(model.tendon_frictionloss[axis.tendon]), False)
    gear = float(model.actuator_gear[axis.actuator, 0])
    if gear != 1.0:
        act = _name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, axis.actuator)
        raise ModelStructureError(
            f"{source}: actuator '{act}': gear=\"{gear:g}\" is not the axis convention's 1: "
            f"tau_m is the torque on the joint, already referred to the joint side; give the "
            f"gear ratio as <numeric name=\"{axis.name}_gear_ratio\" data=\"N\"/>")
    nid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, f"{axis.name}_gear_ratio")
    if nid >= 0:
        adr, size = int(model.numeric_adr[nid]), int(model.numeric_size[nid])
        value = float(model.numeric_data[adr]) if size else float("nan")
        if not (np.isfinite(value) and 0 < value <= MAX_GEAR_RATIO):
            raise _not_physical(source, f"numeric '{axis.name}_gear_ratio'", "data", value,
                                f"a finite gear ratio in (0, {MAX_GEAR_RATIO:g}]")


def select_axis(axes: list[Axis], joint: str | None, source: str = "<model>") -> Axis:
    """The axis named `joint`, else the `joint`-th one counting from 1 when it is a whole
    number (`--joint 1`: names first, then the index), the first axis when None.
    ModelStructureError otherwise, listing the axes."""
    if joint is None:
        return axes[0]
    names = [a.name for a in axes]
    if joint in names:
        return axes[names.index(joint)]
    text = str(joint).strip()
    if text.isdigit() and 1 <= int(text) <= len(axes):
        return axes[int(text) - 1]
    listed = ", ".join(f"{i} {n}" for i, n in enumerate(names, start=1))
    raise ModelStructureError(f"{source}: no axis '{joint}' (give a name or an index: {listed})")


def load_model(name: str | Path) -> tuple[mujoco.MjModel, list[Axis], Path]:
    """Compile a shipped or user model and find its axes; ModelStructureError on failure."""
    path = model_path(name)
    try:
        model = mujoco.MjModel.from_xml_path(str(path))
    except ValueError as err:
        raise ModelStructureError(f"{path}: MuJoCo cannot load it: {err}") from None
    return model, find_axes(model, str(path)), path


def gear_ratio(model: mujoco.MjModel, axis: str) -> float | None:
    nid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, f"{axis}_gear_ratio")
    if nid < 0:
        return None
    return float(model.numeric_data[model.numeric_adr[nid]])


def torque_limit(model: mujoco.MjModel, axis: Axis) -> float | None:
    """The actuator's ctrlrange bound (symmetric limit), None when unlimited."""
    if not model.actuator_ctrllimited[axis.actuator]:
        return None
    return float(np.max(np.abs(model.actuator_ctrlrange[axis.actuator])))
