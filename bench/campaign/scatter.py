"""Parameter scatter: each run's axis drawn around the model, its K, Jm, JL, FVm, FSm, FV, FS
scaled by log-normal factors (`--scatter`), written into the model's own MJCF text."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from jointbench.identification.parameters import FRICTIONS, STIFFNESS_AND_INERTIAS
from jointbench.models import ModelStructureError, load_model, select_axis

SCATTERED = STIFFNESS_AND_INERTIAS + FRICTIONS   # K, Jm, JL, FVm, FSm, FV, FS: the draw order


def scattered_factors(scatter: float, seed: int) -> dict[str, float]:
    """Log-normal factors exp(scatter z), z ~ N(0, 1), for K, Jm, JL, FVm, FSm, FV, FS."""
    if scatter <= 0:
        return {p: 1.0 for p in SCATTERED}
    z = np.random.default_rng(seed).standard_normal(len(SCATTERED))
    return {p: float(np.exp(scatter * zi)) for p, zi in zip(SCATTERED, z)}


def _scale_first(element, attr: str, compiled: float, factor: float) -> None:
    """Set the first number of `attr` (the compiled value when the attribute is absent, e.g.
    from a default class) to compiled x factor, at full precision (repr)."""
    tokens = (element.get(attr) or "").split()
    value = repr(float(compiled) * factor)
    element.set(attr, " ".join([value] + tokens[1:]) if tokens else value)


def scattered_mjcf(model: str, joint: str | None, factors: dict[str, float]) -> tuple[str, str]:
    """The MJCF text of `model` with the axis' parameters scaled by `factors`: tendon
    stiffness (K), rotor armature, damping and frictionloss (Jm, FVm, FSm), link damping and
    frictionloss (FV, FS), and the link body's mass and inertia (JL; its first moments MX, MY
    scale with it: a heavier or lighter payload). Returns (xml, joint).

    The file's own XML is edited (ElementTree) with the compiled values x factor written at
    full precision: MjSpec.to_xml rounds every number to 6 digits (K 20341.0458 becomes 20341, the
    timestep too). Relative asset folders and includes are made absolute, so the text compiles
    from any folder. Raises ModelStructureError when the file lacks an element it scales."""
    full, axes, path = load_model(model)
    axis = select_axis(axes, joint, str(path))
    joint = axis.name
    root = ET.parse(path).getroot()
    base = path.resolve().parent

    def named(tag: str, name: str):
        found = [e for e in root.iter(tag) if e.get("name") == name]
        if len(found) != 1:
            raise ModelStructureError(f"{path}: parameter scatter needs exactly one <{tag} "
                                      f"name=\"{name}\"> in the file itself (found {len(found)})")
        return found[0]

    _scale_first(named("fixed", f"{joint}_spring"), "stiffness",
                 full.tendon_stiffness[axis.tendon], factors["K"])
    rotor, link = named("joint", f"{joint}_motor"), named("joint", joint)
    _scale_first(rotor, "armature", full.dof_armature[axis.motor_dof], factors["Jm"])
    for el, dof, fv, fs in ((rotor, axis.motor_dof, "FVm", "FSm"),
                            (link, axis.link_dof, "FV", "FS")):
        _scale_first(el, "damping", full.dof_damping[dof], factors[fv])
        _scale_first(el, "frictionloss", full.dof_frictionloss[dof], factors[fs])
    body = named("body", full.body(full.jnt_bodyid[axis.link_joint]).name)
    inertial = body.find("inertial")
    if inertial is None:
        raise ModelStructureError(f"{path}: body '{body.get('name')}' has no explicit "
                                  "<inertial>: parameter scatter scales the link's mass and inertia")
    f = factors["JL"]
    inertial.set("mass", repr(float(inertial.get("mass")) * f))
    for attr in ("diaginertia", "fullinertia"):
        if inertial.get(attr):
            inertial.set(attr, " ".join(repr(float(v) * f) for v in inertial.get(attr).split()))
    compiler = root.find("compiler")
    if compiler is None:
        compiler = ET.SubElement(root, "compiler")
    for attr in ("meshdir", "texturedir", "assetdir"):
        folder = compiler.get(attr)
        if folder is not None or attr == "assetdir":
            compiler.set(attr, str(base / (folder or "")))
    for inc in root.iter("include"):
        inc.set("file", str(base / inc.get("file")))
    return ET.tostring(root, encoding="unicode"), joint
