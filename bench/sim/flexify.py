"""A rigid MJCF arm made flexible in the axis convention of models/__init__.py (MjSpec).

A rigid arm (MuJoCo Menagerie's style) drives each hinge `X` with an actuator of gear N.
`flexify` keeps every body, geom, mesh, contact pair and other element of the user's model
and, per joint X:
  - adds a body `X_rotor` beside X's body (same parent, frame, joint position and axis) with
    the hinge `X_motor`: armature Jm, damping FVm, frictionloss FSm;
  - adds the fixed tendon `X_spring` (q_m - q, stiffness K, spring length 0);
  - replaces the user's actuator by the motor `X_motor` on `X_motor`, gear 1, ctrlrange
    +-tau_max, the joint-side torque limit: the original ctrlrange times the gear (times the
    gain of a motor-type actuator; a servo's forcerange times the gear);
  - moves the rigid joint's armature (the rotor inertia the rigid model lumps on the link) to
    the rotor: X's armature becomes 0, and Jm defaults to it;
  - sets X's damping FV and frictionloss FS when given, and records `X_gear_ratio` N.
Both Coulomb frictions get the dead-beat constraint of models/arm6.xml (solreffriction
FRICTION_TC, under two physics steps, which refsafe raises to two) and the integrator is
semi-implicit Euler, as the bench's experiments are validated with (bench/sim/friction.py).

Values (joint side, SI): `--set` first, then a survey or identify JSON, then the defaults:
  Jm   the joint's armature, else the link inertia JL at qpos0 (an inertia ratio of 1);
  K    the stiffness placing the locked first mode sqrt(K (1/Jm + 1/JL)) / 2 pi at F1_DEFAULT_HZ;
  FVm, FSm  0;  FV, FS  the joint's own damping and frictionloss;  N  the actuator's gear.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from jointbench.models import ModelStructureError, find_axes

PARAMETERS = ("K", "Jm", "FVm", "FSm", "FV", "FS", "N", "tau_max")
F1_DEFAULT_HZ = 15.0          # default K: the locked first mode of arm6's axes (14.7-18.9 Hz)
FRICTION_TC = 1e-6            # solreffriction time constant [s] of models/arm6.xml (refsafe: 2 steps)
SOLIMP_FRICTION = (0.99, 0.999, 0.001)
ROTOR_MASS, ROTOR_INERTIA = 1e-6, 1e-9   # the rotor body: its inertia is the armature Jm
SUFFIXES = ("_motor", "_rotor", "_spring")


@dataclass(frozen=True)
class JointDrive:
    """The drive of one flexified joint: its values and where each came from."""

    joint: str
    values: dict[str, float]
    sources: dict[str, str]
    JL: float
    f1_hz: float


@dataclass(frozen=True)
class Flexified:
    """The flexified spec, the drives and the model-wide changes made."""

    spec: mujoco.MjSpec
    drives: tuple[JointDrive, ...]
    changes: tuple[str, ...]


def _name(model: mujoco.MjModel, obj, i: int) -> str:
    return mujoco.mj_id2name(model, obj, i) or ""


def _actuator_of(model: mujoco.MjModel, joint: int, source: str, jname: str) -> int:
    acts = [a for a in range(model.nu) if int(model.actuator_trntype[a]) ==
            int(mujoco.mjtTrn.mjTRN_JOINT) and int(model.actuator_trnid[a, 0]) == joint]
    if not acts:
        raise ModelStructureError(f"{source}: joint '{jname}' has no actuator (flexify needs "
                                  "the motor driving each joint; --joints selects others)")
    if len(acts) > 1:
        names = ", ".join(_name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or f"#{a}" for a in acts)
        raise ModelStructureError(f"{source}: joint '{jname}' has several actuators ({names})")
    return acts[0]


def torque_limit(model: mujoco.MjModel, act: int, source: str, aname: str
                 ) -> tuple[float, str] | None:
    """The joint-side torque limit of a rigid arm's actuator (module docstring) and how it was
    found; None when unlimited. ModelStructureError for a gear of 0."""
    gear = float(model.actuator_gear[act, 0])
    if gear == 0:
        raise ModelStructureError(f"{source}: actuator '{aname}' has gear 0 (it transmits no "
                                  "torque)")
    motor = (int(model.actuator_biastype[act]) == int(mujoco.mjtBias.mjBIAS_NONE) and
             int(model.actuator_gaintype[act]) == int(mujoco.mjtGain.mjGAIN_FIXED))
    if motor and model.actuator_ctrllimited[act]:
        return (float(np.max(np.abs(model.actuator_ctrlrange[act])) *
                      abs(model.actuator_gainprm[act, 0]) * abs(gear)), "ctrlrange x gear")
    if model.actuator_forcelimited[act]:
        return (float(np.max(np.abs(model.actuator_forcerange[act])) * abs(gear)),
                "forcerange x gear")
    return None


def _defaults(model: mujoco.MjModel, j: int, gear: float, limit: tuple[float, str] | None
              ) -> tuple[dict[str, float], dict[str, str], float]:
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    M = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    dof = int(model.jnt_dofadr[j])
    armature = float(model.dof_armature[dof])
    JL = float(M[dof, dof]) - armature
    values = {"Jm": armature if armature > 0 else JL, "FVm": 0.0, "FSm": 0.0,
              "FV": float(model.dof_damping[dof]), "FS": float(model.dof_frictionloss[dof]),
              "N": abs(gear)}
    sources = {"Jm": "default: the joint's armature" if armature > 0 else
               "default: JL (no armature on the joint)", "FVm": "default 0", "FSm": "default 0",
               "FV": "the joint's damping", "FS": "the joint's frictionloss",
               "N": "the actuator's gear"}
    if limit is not None:
        values["tau_max"], sources["tau_max"] = limit
    return values, sources, JL


def flexify(path: str | os.PathLike, given: dict[str, dict[str, float]],
            from_file: dict[str, dict[str, float]] | None = None,
            joints: list[str] | None = None, from_name: str = "--from") -> Flexified:
    """The flexified spec of the MJCF at `path` (module docstring). `given`: joint ->
    parameter -> value (--set); `from_file`: the same from a survey or identify JSON;
    `joints`: the joints to flexify (default every joint). ModelStructureError for a joint
    that is not a hinge, has no actuator, a gear of 0, or a name the convention needs taken."""
    source = str(path)
    try:
        spec = mujoco.MjSpec.from_file(source)
        model = spec.compile()
    except ValueError as err:
        raise ModelStructureError(f"{source}: MuJoCo cannot load it: {err}") from None
    all_joints = [_name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]
    names = joints if joints is not None else all_joints
    if not names:
        raise ModelStructureError(f"{source}: no joint to flexify")
    for name in list(given) + list(from_file or {}):
        if name not in all_joints:
            raise ModelStructureError(f"{source}: no joint '{name}' (joints: "
                                      f"{', '.join(all_joints)})")
    for name in given:
        if name not in names:
            raise ModelStructureError(f"{source}: --set gives values for '{name}', which is "
                                      f"not among the joints to flexify ({', '.join(names)})")
    taken = {_name(model, o, i) for o, n in ((mujoco.mjtObj.mjOBJ_JOINT, model.njnt),
                                             (mujoco.mjtObj.mjOBJ_BODY, model.nbody),
                                             (mujoco.mjtObj.mjOBJ_TENDON, model.ntendon),
                                             (mujoco.mjtObj.mjOBJ_ACTUATOR, model.nu))
             for i in range(n)}
    plan = []
    for name in names:
        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        if j < 0 or not name:
            raise ModelStructureError(f"{source}: no joint '{name}' (joints: "
                                      f"{', '.join(all_joints)})")
        if int(model.jnt_type[j]) != int(mujoco.mjtJoint.mjJNT_HINGE):
            kind = mujoco.mjtJoint(int(model.jnt_type[j])).name[6:].lower()
            raise ModelStructureError(f"{source}: joint '{name}' is a {kind} joint, not a "
                                      "hinge (flexify makes hinges flexible; --joints selects "
                                      "the hinges)")
        for suffix in SUFFIXES:
            if name + suffix in taken:
                raise ModelStructureError(f"{source}: the name '{name}{suffix}' the axis "
                                          "convention needs is already used")
        act = _actuator_of(model, j, source, name)
        aname = _name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, act)
        limit = torque_limit(model, act, source, aname or f"#{act}")
        plan.append((name, j, act, limit))

    drives = []
    for name, j, act, limit in plan:
        values, sources, JL = _defaults(model, j, float(model.actuator_gear[act, 0]), limit)
        for label, table in ((from_name, (from_file or {}).get(name, {})),
                             ("--set", given.get(name, {}))):
            for key, value in table.items():
                values[key], sources[key] = float(value), label
        if "K" not in values:
            w = 2 * math.pi * F1_DEFAULT_HZ
            values["K"] = w * w / (1 / values["Jm"] + 1 / JL)
            sources["K"] = f"default: f1 = {F1_DEFAULT_HZ:g} Hz"
        for key in ("K", "Jm"):
            if not (values[key] > 0 and math.isfinite(values[key])):
                raise ModelStructureError(f"{source}: joint '{name}': {key} = {values[key]:g} "
                                          f"({sources[key]}) must be positive")
        for key in ("FVm", "FSm", "FV", "FS"):
            if not (values[key] >= 0 and math.isfinite(values[key])):
                raise ModelStructureError(f"{source}: joint '{name}': {key} = {values[key]:g} "
                                          f"({sources[key]}) must be >= 0")
        f1 = math.sqrt(values["K"] * (1 / values["Jm"] + 1 / JL)) / (2 * math.pi)
        drives.append(JointDrive(name, values, sources, JL, f1))

    actuators = list(spec.actuators)
    for (name, j, act, _), drive in zip(plan, drives):
        _edit(spec, model, name, j, drive.values)
        spec.delete(actuators[act])
    changes = ["integrator Euler", "refsafe enabled (the frictions' solreffriction "
               f"{FRICTION_TC:g} s runs at two physics steps: dead-beat Coulomb friction)"]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)
    try:
        flex = spec.compile()
    except ValueError as err:
        raise ModelStructureError(f"{source}: the flexified model does not compile: {err}"
                                  ) from None
    axes = {a.name for a in find_axes(flex, source)}
    missing = [n for n, *_ in plan if n not in axes]
    if missing:
        raise ModelStructureError(f"{source}: flexified joints not found as axes: {missing}")
    return Flexified(spec, tuple(drives), tuple(changes))


def _edit(spec: mujoco.MjSpec, model: mujoco.MjModel, name: str, j: int,
          v: dict[str, float]) -> None:
    """Rotor body and hinge, spring tendon, motor, gear ratio for joint `name` (index j)."""
    bid = int(model.jnt_bodyid[j])
    parent = int(model.body_parentid[bid])
    pbody = spec.worldbody if parent == 0 else _spec_body(spec, model, parent)
    rotor = pbody.add_body()
    rotor.name = f"{name}_rotor"
    rotor.pos = model.body_pos[bid].copy()
    rotor.quat = model.body_quat[bid].copy()
    rotor.explicitinertial = True
    rotor.mass = ROTOR_MASS
    rotor.inertia = [ROTOR_INERTIA] * 3
    rotor.ipos, rotor.iquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]   # written as <inertial>
    rotor.fullinertia = [math.nan] * 6
    hinge = rotor.add_joint()
    hinge.name = f"{name}_motor"
    hinge.type = mujoco.mjtJoint.mjJNT_HINGE
    hinge.pos = model.jnt_pos[j].copy()
    hinge.axis = model.jnt_axis[j].copy()
    hinge.armature = v["Jm"]
    hinge.damping[0] = v["FVm"]
    hinge.frictionloss = v["FSm"]
    hinge.stiffness[0] = 0.0
    hinge.limited = mujoco.mjtLimited.mjLIMITED_FALSE          # nothing inherited from a
    hinge.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE    # default class limits the rotor
    for jt in (hinge, spec.joint(name)):
        jt.solref_friction = (FRICTION_TC, 1.0)
        jt.solimp_friction[:3] = SOLIMP_FRICTION
    link = spec.joint(name)
    link.armature = 0.0
    link.damping[0] = v["FV"]
    link.frictionloss = v["FS"]
    tendon = spec.add_tendon()
    tendon.name = f"{name}_spring"
    tendon.stiffness[0] = v["K"]
    tendon.springlength = [0.0, 0.0]
    tendon.wrap_joint(f"{name}_motor", 1.0)
    tendon.wrap_joint(name, -1.0)
    act = spec.add_actuator()
    act.name = f"{name}_motor"
    act.target = f"{name}_motor"
    act.trntype = mujoco.mjtTrn.mjTRN_JOINT
    act.set_to_motor()
    act.gear[0] = 1.0
    if "tau_max" in v:
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.ctrlrange = [-v["tau_max"], v["tau_max"]]
    else:
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    numeric = spec.numeric(f"{name}_gear_ratio")
    if numeric is not None:
        numeric.data = [v["N"]]
    else:
        spec.add_numeric(name=f"{name}_gear_ratio", data=[v["N"]])


def _spec_body(spec: mujoco.MjSpec, model: mujoco.MjModel, bid: int) -> mujoco.MjsBody:
    """The spec body of compiled body `bid` (by name; spec.bodies follows the compiled order
    for an unnamed one)."""
    name = _name(model, mujoco.mjtObj.mjOBJ_BODY, bid)
    body = spec.body(name) if name else None
    return body if body is not None else spec.bodies[bid]


def to_xml(spec: mujoco.MjSpec, src: Path, out: Path) -> tuple[str, list[str]]:
    """The MJCF text of `spec` (compiled) to be written at `out`, its meshdir and texturedir
    pointing from `out`'s folder to the source's assets (the user's files stay where they
    are); and the changes made."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(spec.to_xml())
    compiler = root.find("compiler")
    if compiler is None:
        compiler = ET.Element("compiler")
        root.insert(0, compiler)
    changes = []
    base = src.resolve().parent
    for attr in ("meshdir", "texturedir"):
        old = compiler.get(attr, "")
        new = os.path.relpath(base / old, out.resolve().parent)
        if os.path.normpath(old or ".") != new:
            compiler.set(attr, new)
            changes.append(f"{attr} {new} (the source's assets, from the output's folder)")
    ET.indent(root, "  ")
    return ET.tostring(root, encoding="unicode") + "\n", changes
