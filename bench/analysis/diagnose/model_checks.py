"""What `diagnose LOG --model ROBOT.xml` checks before comparing: the MJCF loads (its errors
name the file), the log's axis is one of the model's, the axis type (hinge or slide) and the
gear ratio agree with the log's metadata; and the model's asset paths stay valid in the
corrected and extended models written into another folder.

Every value the comparison reads is checked finite and of its sign by the axis convention
(`models.check_values`, run by `models.find_axes`).
"""

from __future__ import annotations

from pathlib import Path

import mujoco

from jointbench.identification.log import Log
from jointbench.models import Axis, ModelStructureError, gear_ratio, select_axis

# The log's and the model's gear ratios are the same number written twice (10 and 6
# significant digits): a relative difference over this is another gearbox.
GEAR_RATIO_TOLERANCE = 1e-3


def _one_line(err: BaseException) -> str:
    return "; ".join(line.strip() for line in str(err).splitlines() if line.strip())


def load_spec(source: Path) -> mujoco.MjSpec:
    """The MJCF at `source` as an MjSpec with its asset folders made absolute (so that a copy
    written elsewhere still finds its meshes and textures). ModelStructureError naming the
    file when MuJoCo cannot read it."""
    if Path(source).is_dir():
        raise ModelStructureError(f"{source}: is a directory, not an MJCF file")
    try:
        spec = mujoco.MjSpec.from_file(str(source))
    except ValueError as err:
        raise ModelStructureError(f"{source}: MuJoCo cannot load it: {_one_line(err)}") from None
    absolute_assets(spec, source)
    return spec


def absolute_assets(spec: mujoco.MjSpec, source: Path) -> None:
    """Set the spec's mesh and texture folders to absolute paths, read relative to the folder
    of `source` as MuJoCo reads them: the MJCF text it writes then loads from any folder."""
    base = Path(source).resolve().parent
    for attribute in ("meshdir", "texturedir"):
        folder = getattr(spec, attribute) or ""
        setattr(spec, attribute, str(base / folder) if not Path(folder).is_absolute()
                else folder)


def compiled(spec: mujoco.MjSpec, source: Path) -> mujoco.MjModel:
    """`spec` compiled; ModelStructureError naming the file when it does not compile."""
    try:
        return spec.compile()
    except ValueError as err:
        raise ModelStructureError(f"{source}: does not compile: {_one_line(err)}") from None


def _log_name(log: Log) -> str:
    return str(log.path) if log.path else "the log"


def log_axis(log: Log, model: mujoco.MjModel, axes: list[Axis], joint: str | None,
             source: Path) -> tuple[str, list[str]]:
    """The model's axis the log moves (`joint`, else the log's `joint` metadata, else the
    model's only axis) and warnings. ModelStructureError naming the log and the model when
    the log's axis is not one of the model's, or its axis type is not the model's."""
    names = [a.name for a in axes]
    logged = log.meta.get("joint")
    if joint is None and logged is not None:
        if logged not in names:
            raise ModelStructureError(
                f"{source}: has no axis '{logged}', the axis of {_log_name(log)} (its metadata "
                f"'joint'); the model's axes: {', '.join(names)}; give --joint to say which "
                "of them the log moves")
        joint = logged
    axis = select_axis(axes, joint, str(source))
    slide = int(model.jnt_type[axis.link_joint]) == int(mujoco.mjtJoint.mjJNT_SLIDE)
    if slide != log.prismatic:
        kind = "a slide (prismatic)" if slide else "a hinge (revolute)"
        other = "prismatic (metadata 'axis: prismatic')" if log.prismatic else \
            "revolute (no 'axis: prismatic' metadata)"
        raise ModelStructureError(
            f"{source}: axis '{axis.name}' is {kind} joint, and {_log_name(log)} is {other}: "
            "their parameters are in different units (N/m against N m/rad); choose the "
            "matching model or axis")
    notes = []
    N_model, N_log = gear_ratio(model, axis.name), log.meta_float("gear_ratio")
    if N_model is not None and N_log is not None and \
            abs(N_model / N_log - 1.0) > GEAR_RATIO_TOLERANCE:
        notes.append(f"gear ratio: {source} gives {N_model:g} (numeric "
                     f"'{axis.name}_gear_ratio'), {_log_name(log)} {N_log:g} (metadata "
                     "'gear_ratio'): the log's joint-side values and the model's may be "
                     "referred through different gearboxes")
    return axis.name, notes
