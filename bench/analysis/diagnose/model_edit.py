"""The user's MJCF with corrected parameters (MjSpec edits; everything else of the file kept),
and the values of eqs. (5)-(7) a spec gives its axis in a locked configuration.

Where each parameter of the joint-motor model lives in the axis convention (models/__init__.py):
K the stiffness of tendon `X_spring`; Jm, FVm, FSm the armature, damping and frictionloss of
joint `X_motor`; FV, FS the damping and frictionloss of joint `X`; JL = M_XX (eq. 5), the
mass matrix at the link joint. JL is raised with armature on joint `X` (a pure inertia about
the axis: gravity unchanged) and lowered by taking that armature off first, then by scaling
the rotational inertias (not the masses) of the bodies the joint moves, so the gravity
moments MX, MY stay as they are; only when that cannot reach the value are the masses scaled
too (MX, MY then scale with them, a note says so). MX, MY (eq. 7, the first moment of the
moving bodies across the axis) are set in two exact steps, both linear in what they change:
the moving bodies' masses and inertias scaled by one factor (a uniformly heavier or lighter
link: the moment's magnitude, its direction kept), then the centre of mass of the joint's own
body moved across the axis (the rest, its direction). JL is set after them, and both again
when JL had to scale the masses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from jointbench.bench.analysis.diagnose.model_checks import load_spec
from jointbench.bench.sim.axes import full_qpos
from jointbench.models import Axis, ModelStructureError, find_axes
from jointbench.models.truth import AxisTruth, axis_truth

# Parameter -> (element kind, name pattern, attribute) of the axis convention.
ATTRIBUTES = {"K": ("tendon", "{}_spring", "stiffness"),
              "Jm": ("joint", "{}_motor", "armature"),
              "FVm": ("joint", "{}_motor", "damping"),
              "FSm": ("joint", "{}_motor", "frictionloss"),
              "FV": ("joint", "{}", "damping"),
              "FS": ("joint", "{}", "frictionloss")}
GRAVITY = ("MX", "MY")
EDITABLE = (*ATTRIBUTES, "JL", *GRAVITY)
ROUNDS = 3   # gravity, then JL, again while JL scales the masses (module docstring)


@dataclass(frozen=True)
class Corrected:
    """A corrected spec, the parameters set, and what could not be set as asked."""

    spec: mujoco.MjSpec
    values: dict[str, float]      # the parameters written
    notes: tuple[str, ...] = ()


def spec_truth(spec: mujoco.MjSpec, joint: str, config: dict[str, float],
               source: str = "<model>") -> tuple[AxisTruth, mujoco.MjModel, Axis]:
    """Compile `spec` and read eqs. (5)-(7) of axis `joint` with the axes at `config`
    (default 0, models.truth.axis_truth). ModelStructureError when it does not compile or has
    no such axis."""
    try:
        model = spec.compile()
    except ValueError as err:
        raise ModelStructureError(f"{source}: does not compile: {err}") from None
    axes = find_axes(model, source)
    found = [a for a in axes if a.name == joint]
    if not found:
        raise ModelStructureError(f"{source}: no axis '{joint}' (axes: "
                                  f"{', '.join(a.name for a in axes)})")
    return axis_truth(model, found[0], full_qpos(model, axes, config)), model, found[0]


def _set(spec: mujoco.MjSpec, joint: str, name: str, value: float) -> None:
    kind, pattern, attribute = ATTRIBUTES[name]
    element = getattr(spec, kind)(pattern.format(joint))
    if element is None:
        raise ModelStructureError(f"no {kind} '{pattern.format(joint)}' for {name}")
    if attribute in ("stiffness", "damping"):   # arrays in MjSpec (nonlinear terms after)
        getattr(element, attribute)[0] = value
    else:
        setattr(element, attribute, value)


def _subtree(model: mujoco.MjModel, root: int) -> list[str]:
    """Names of body `root` and every body below it."""
    out = []
    for b in range(model.nbody):
        a = b
        while a > 0 and a != root:
            a = int(model.body_parentid[a])
        if a == root:
            out.append(model.body(b).name)
    return out


def _scale_inertia(spec: mujoco.MjSpec, names: list[str], s: float, masses: bool) -> None:
    for name in names:
        body = spec.body(name)
        if body is None or not body.explicitinertial:
            continue
        if np.isnan(body.fullinertia[0]):
            body.inertia = [v * s for v in body.inertia]
        else:
            body.fullinertia = [v * s for v in body.fullinertia]
        if masses:
            body.mass = body.mass * s


def _jl(spec: mujoco.MjSpec, joint: str, config: dict[str, float]) -> float:
    return spec_truth(spec, joint, config)[0].JL


def _moments(spec: mujoco.MjSpec, joint: str, config: dict[str, float]) -> np.ndarray:
    t = spec_truth(spec, joint, config)[0]
    return np.array([t.MX, t.MY])


def _moving(spec: mujoco.MjSpec, joint: str) -> tuple[str, list[str]]:
    """(the body of joint `joint`, that body and every body below it)."""
    model = spec.compile()
    body = int(model.jnt_bodyid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, joint)])
    return model.body(body).name, _subtree(model, body)


def _across(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors orthogonal to `axis` and to each other."""
    a = axis / np.linalg.norm(axis)
    e1 = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1)


def _set_gravity(spec: mujoco.MjSpec, joint: str, config: dict[str, float],
                 target: np.ndarray, notes: list[str]) -> None:
    """Make (MX, MY) = target (module docstring): the masses (M = M_0 + c M_1, M_1 the part
    of the moving bodies with an explicit inertial: c the least-squares factor), then the
    joint body's centre of mass (M linear in its shift across the axis: a 2 x 2 solve);
    appends a note when it cannot (the body has no explicit inertial, or no mass)."""
    name, bodies = _moving(spec, joint)
    now = _moments(spec, joint, config)
    _scale_inertia(spec, bodies, 2.0, True)
    part = _moments(spec, joint, config) - now
    _scale_inertia(spec, bodies, 0.5, True)          # back (powers of two: exact)
    c = 1 + float(part @ (target - now)) / float(part @ part) if part @ part > 0 else 1.0
    if c > 0 and c != 1:                              # c <= 0: a reversed moment, no mass can
        _scale_inertia(spec, bodies, c, True)
    body = spec.body(name)
    if not body.explicitinertial or not body.mass > 0:
        notes.append(f"MX, MY: body '{name}' has no explicit inertial with a mass; its centre "
                     "of mass cannot be moved")
        return
    base, ipos = _moments(spec, joint, config), np.array(body.ipos)
    steps = _across(np.array(spec.joint(joint).axis))
    slopes = []
    for e in steps:                                   # M is linear in the shift: one step each
        body.ipos = ipos + e
        slopes.append(_moments(spec, joint, config) - base)
    A = np.array(slopes).T
    if not abs(np.linalg.det(A)) > 1e-9 * float(np.abs(A).max()) ** 2:   # no turn of M
        body.ipos = ipos
        notes.append(f"MX, MY: moving the centre of mass of '{name}' does not turn them (a "
                     "slide joint, or a hinge along gravity)")
        return
    d = np.linalg.solve(A, target - base)
    body.ipos = ipos + d[0] * steps[0] + d[1] * steps[1]


def _set_jl(spec: mujoco.MjSpec, joint: str, config: dict[str, float], target: float,
            notes: list[str]) -> None:
    """Make JL = target (module docstring: armature first, then rotational inertias, then
    masses); appends a note when the masses had to change or the target was not reached."""
    link = spec.joint(joint)
    now = _jl(spec, joint, config)
    if target >= now - link.armature:
        link.armature = link.armature + (target - now)
        return
    link.armature = 0.0
    bodies = _moving(spec, joint)[1]
    for masses in (False, True):
        base = _jl(spec, joint, config)
        _scale_inertia(spec, bodies, 0.5, masses)
        half = _jl(spec, joint, config)
        _scale_inertia(spec, bodies, 2.0, masses)   # back (powers of two: exact)
        slope = 2 * (base - half)                   # JL(s) = base + slope (s - 1), linear
        s = 1 + (target - base) / slope if slope > 0 else -1.0
        if s > 0:
            _scale_inertia(spec, bodies, s, masses)
            if masses:
                notes.append(f"JL: the moving bodies' masses scaled by {s:.4g} as well (their "
                             "rotational inertias alone cannot lower JL that far): MX, MY "
                             "scale with them")
            return
    notes.append(f"JL: cannot be lowered to {target:g} by scaling the moving bodies; left at "
                 f"{_jl(spec, joint, config):g}")


def corrected_spec(path: str, joint: str, config: dict[str, float],
                   values: dict[str, float]) -> Corrected:
    """The MJCF at `path` with axis `joint`'s parameters set to `values` (any of EDITABLE;
    others are ignored), read again from the compiled result. ValueError for a value that is
    not physical (K, Jm, JL <= 0, a negative friction)."""
    spec = load_spec(Path(path))
    notes: list[str] = []
    for name, v in values.items():
        if name not in EDITABLE:
            continue
        if not math.isfinite(v) or (name not in GRAVITY and (
                v < 0 or (v == 0 and name in ("K", "Jm", "JL")))):
            raise ValueError(f"{name} = {v:g} cannot be written into the model")
        if name in ATTRIBUTES:
            _set(spec, joint, name, v)
    gravity = None
    if any(n in values for n in GRAVITY):
        now = _moments(spec, joint, config)
        gravity = np.array([values.get(n, now[i]) for i, n in enumerate(GRAVITY)])
    for _ in range(ROUNDS):   # JL after gravity; again when JL had to scale the masses
        notes = []
        if gravity is not None:
            _set_gravity(spec, joint, config, gravity, notes)
        if "JL" in values:
            _set_jl(spec, joint, config, values["JL"], notes)
        if gravity is None or np.allclose(_moments(spec, joint, config), gravity,
                                          rtol=1e-9, atol=1e-12 * float(np.abs(gravity).max())):
            break
    else:
        notes.append("MX, MY: left at " + ", ".join(
            f"{v:.5g}" for v in _moments(spec, joint, config)) + (
            " (with JL set)" if "JL" in values else ""))
    truth = spec_truth(spec, joint, config, str(path))[0]
    written = {n: float(getattr(truth, n)) for n in values if n in EDITABLE}
    return Corrected(spec=spec, values=written, notes=tuple(notes))
