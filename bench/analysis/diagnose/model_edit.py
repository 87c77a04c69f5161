"""The user's MJCF with corrected parameters (MjSpec edits; everything else of the file kept),
and the values of eqs. (5)-(7) a spec gives its axis in a locked configuration.

Where each parameter of the joint-motor model lives in the axis convention (models/__init__.py):
K the stiffness of tendon `X_spring`; Jm, FVm, FSm the armature, damping and frictionloss of
joint `X_motor`; FV, FS the damping and frictionloss of joint `X`; JL = M_XX (eq. 5), the
mass matrix at the link joint. JL is raised with armature on joint `X` (a pure inertia about
the axis: gravity unchanged) and lowered by taking that armature off first, then by scaling
the rotational inertias (not the masses) of the bodies the joint moves, so the gravity
moments MX, MY stay as they are; only when that cannot reach the value are the masses scaled
too (MX, MY then scale with them, a note says so). MX and MY themselves (masses and centres
of mass) are reported, never edited.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

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
EDITABLE = (*ATTRIBUTES, "JL")
NOT_EDITED = ("MX", "MY")   # masses and centres of mass: reported, never edited


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
    model = spec.compile()
    jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, joint)
    bodies = _subtree(model, int(model.jnt_bodyid[jid]))
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
    spec = mujoco.MjSpec.from_file(str(path))
    notes: list[str] = []
    for name, v in values.items():
        if name not in EDITABLE:
            continue
        if not math.isfinite(v) or v < 0 or (v == 0 and name in ("K", "Jm", "JL")):
            raise ValueError(f"{name} = {v:g} cannot be written into the model")
        if name == "JL":
            continue
        _set(spec, joint, name, v)
    if "JL" in values:
        _set_jl(spec, joint, config, values["JL"], notes)
    truth = spec_truth(spec, joint, config, str(path))[0]
    written = {n: float(getattr(truth, n)) for n in values if n in EDITABLE}
    return Corrected(spec=spec, values=written, notes=tuple(notes))
