"""Nominal MuJoCo axes built from identified parameters (MjSpec), in the axis convention of
models/__init__.py, so that `models.find_axes`, `bench.replay.replay` and
`jointbench simulate --model FILE.xml` accept them.

- `rigid_axis`: the rigid model of docs/cli.md, tau_m = J qmdd + FV qmd + FS sign(qmd)
  + offset: one joint `X` (hinge, or slide for a prismatic axis) with damping FV,
  frictionloss FS and inertia J, half as armature (the rotor, Jm in the truth) and half in
  the moving body (JL): MuJoCo scales a slide joint's friction constraint by the body's own
  mass (its dof_invweight0 ignores armature), so a carriage carried by armature alone barely
  feels its Coulomb friction (measured: 0.004 N of a 20.4 N frictionloss); actuator
  `X_motor` on `X`; the offset is a passive actuator `X_offset` (gain 0, constant bias
  -offset), a constant load the motor holds with tau_m = offset.
- `two_mass_axis`: the joint-motor model of eq. (5)-(6): rotor hinge `X_motor` (armature Jm,
  damping FVm, frictionloss FSm), link hinge `X` (damping FV, frictionloss FS, inertia JL),
  fixed tendon `X_spring` (q_m - q, stiffness K), actuator `X_motor`; the gravity torque of
  eq. (7), MX g cos q + MY g sin q, from a link mass whose centre of mass is
  (-MX/m, 0, -MY/m) in the link frame (as models/prototype_axis.xml). Hinges only: a
  prismatic rotor would need its mass in a body for its friction (see above), which the
  truth reading (Jm = armature) does not allow.

Both have contact and refsafe disabled, the Coulomb friction's solimpfriction 0.99 0.999
0.001 and a given solreffriction time constant (default 2 ms, for a log that carries none),
the given integrator (default RK4: the replica of a measured axis; a jointbench log's replica
takes its plant's, bench.sim.friction.integrator_for_log, so that with the log's physics steps
and time constant its friction is the plant's) and the log's sample period as timestep. The builders return the MjSpec
so that callers can add effects before compiling.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

# static_link_position is imported from here by bench.sim.replay.
from jointbench.bench.sim.axes import static_link_position  # noqa: F401
from jointbench.bench.effects.offset import add_offset_load
from jointbench.bench.sim.friction import integrator_for_log
from jointbench.identification.identify import Identification
from jointbench.identification.log import Log, atomic_write_text
from jointbench.models import Axis, ModelStructureError, find_axes

# The friction constraint of models/prototype_axis.xml (README "Coulomb friction").
SOLREF_FRICTION = (0.002, 1.0)
SOLIMP_FRICTION = (0.99, 0.999, 0.001)
ROTOR_MASS = 1e-6           # the nearly massless body carrying an armature (README)
MJ_MINVAL = 1e-15           # MuJoCo's mjMINVAL: a moving body's mass and inertia must exceed it
ROTOR_INERTIA = 1e-9
AXIS_DIR = (0.0, 1.0, 0.0)  # hinge axis y, as the prototype (gravity torque of eq. 7 in x-z)
SLIDE_DIR = (1.0, 0.0, 0.0)  # slide axis x: horizontal, no gravity along a prismatic axis
RIGID_ROTOR_SHARE = 0.5     # share of a rigid axis' J held as armature (the rest in the body)


@dataclass(frozen=True)
class NominalAxis:
    """A nominal axis built from an identification: the spec, the parameters used (after the
    clamps listed in `notes`) and which model they come from."""

    spec: mujoco.MjSpec
    model: str                   # "rigid" or "joint-motor" (the spec's structure)
    parameters: dict[str, float]
    notes: tuple[str, ...] = ()


def _new_spec(name: str, timestep: float, gravity: float,
              integrator: mujoco.mjtIntegrator = mujoco.mjtIntegrator.mjINT_RK4
              ) -> mujoco.MjSpec:
    if not (timestep > 0 and math.isfinite(timestep)):
        raise ValueError(f"timestep must be a positive number of seconds, got {timestep}")
    spec = mujoco.MjSpec()
    spec.modelname = name
    spec.compiler.degree = False
    spec.compiler.autolimits = True
    spec.option.timestep = timestep
    spec.option.integrator = integrator
    spec.option.gravity = [0.0, 0.0, -gravity]
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)
    return spec


def _inertial(body: mujoco.MjsBody, mass: float, inertia: float,
              pos: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
    """An explicit inertial: `mass` at `pos`, the same principal inertia on the three axes."""
    body.explicitinertial = True
    body.mass = mass
    body.ipos = list(pos)
    body.iquat = [1.0, 0.0, 0.0, 0.0]
    body.inertia = [inertia] * 3


def _joint(body: mujoco.MjsBody, name: str, slide: bool, armature: float, damping: float,
           frictionloss: float, friction_timeconst: float = SOLREF_FRICTION[0]
           ) -> mujoco.MjsJoint:
    j = body.add_joint()
    j.name = name
    j.type = mujoco.mjtJoint.mjJNT_SLIDE if slide else mujoco.mjtJoint.mjJNT_HINGE
    j.axis = SLIDE_DIR if slide else AXIS_DIR
    j.armature = armature
    j.damping[0] = damping
    j.frictionloss = frictionloss
    j.solref_friction = (friction_timeconst, SOLREF_FRICTION[1])
    j.solimp_friction[:3] = SOLIMP_FRICTION
    return j


def _motor(spec: mujoco.MjSpec, name: str, joint: str, tau_max: float | None) -> None:
    act = spec.add_actuator()
    act.name = name
    act.target = joint
    act.trntype = mujoco.mjtTrn.mjTRN_JOINT
    act.set_to_motor()
    act.gear[0] = 1.0
    if tau_max is not None:
        if not (tau_max > 0 and math.isfinite(tau_max)):
            raise ValueError(f"tau_max must be positive, got {tau_max}")
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.ctrlrange = [-tau_max, tau_max]


def _check(values: dict[str, float], positive: tuple[str, ...],
           nonnegative: tuple[str, ...]) -> None:
    for k, v in values.items():
        if not math.isfinite(v):
            raise ValueError(f"{k} = {v} is not a finite number")
    for k in positive:
        if not values[k] > 0:
            raise ValueError(f"{k} = {values[k]:g} must be positive for a physical axis")
    for k in nonnegative:
        if values[k] < 0:
            raise ValueError(f"{k} = {values[k]:g} must be >= 0 for a physical axis")


def rigid_axis(J: float, FV: float, FS: float, offset: float = 0.0, *, timestep: float,
               prismatic: bool = False, tau_max: float | None = None, gravity: float = 9.81,
               gear_ratio: float | None = None, name: str = "axis1",
               integrator: mujoco.mjtIntegrator = mujoco.mjtIntegrator.mjINT_RK4
               ) -> mujoco.MjSpec:
    """The rigid model tau_m = J qmdd + FV qmd + FS sign(qmd) + offset as an MjSpec (module
    docstring). J in kg m^2 (kg for a prismatic axis, a horizontal slide), FV, FS, offset in
    the joint's units. ValueError for J <= 0, FV < 0 or FS < 0."""
    _check({"J": J, "FV": FV, "FS": FS, "offset": offset}, ("J",), ("FV", "FS"))
    spec = _new_spec(f"nominal_rigid_{name}", timestep, gravity, integrator)
    body = spec.worldbody.add_body()
    body.name = f"{name}_link"
    armature = RIGID_ROTOR_SHARE * J
    if prismatic:
        _inertial(body, J - armature, ROTOR_INERTIA)
    else:
        _inertial(body, ROTOR_MASS, J - armature)
    _joint(body, name, prismatic, armature, FV, FS)
    _motor(spec, f"{name}_motor", name, tau_max)
    if offset != 0.0:
        add_offset_load(spec, name, name, offset)
    if gear_ratio is not None:
        spec.add_numeric(name=f"{name}_gear_ratio", data=[gear_ratio])
    return spec


def two_mass_axis(Jm: float, FVm: float, FSm: float, K: float, JL: float, FV: float = 0.0,
                  FS: float = 0.0, MX: float = 0.0, MY: float = 0.0, *, timestep: float,
                  prismatic: bool = False, tau_max: float | None = None, gravity: float = 9.81,
                  gear_ratio: float | None = None, name: str = "axis1",
                  friction_timeconst: float = SOLREF_FRICTION[0],
                  integrator: mujoco.mjtIntegrator = mujoco.mjtIntegrator.mjINT_RK4
                  ) -> mujoco.MjSpec:
    """The joint-motor model of eqs. (5)-(7) as an MjSpec (module docstring), hinges only
    (`prismatic=True` raises ValueError). `friction_timeconst` [s]: the solreffriction time
    constant of both Coulomb frictions, the width of their stick band (the shipped models run
    with two physics steps, bench.sim.friction). ValueError for non-positive Jm, K, JL or negative friction."""
    _check({"Jm": Jm, "FVm": FVm, "FSm": FSm, "K": K, "JL": JL, "FV": FV, "FS": FS,
            "MX": MX, "MY": MY}, ("Jm", "K", "JL"), ("FVm", "FSm", "FV", "FS"))
    if prismatic:
        raise ValueError("two-mass nominal axes are hinges only: a slide joint's Coulomb "
                         "friction needs the rotor mass in a body, the truth reading needs it "
                         "as armature (bench/sim/nominal.py)")
    spec = _new_spec(f"nominal_two_mass_{name}", timestep, gravity, integrator)
    rotor = spec.worldbody.add_body()
    rotor.name = f"{name}_rotor"
    _inertial(rotor, ROTOR_MASS, ROTOR_INERTIA)
    if not friction_timeconst > 0:
        raise ValueError(f"friction_timeconst must be > 0 s, got {friction_timeconst}")
    _joint(rotor, f"{name}_motor", prismatic, Jm, FVm, FSm, friction_timeconst)
    link = spec.worldbody.add_body()
    link.name = f"{name}_link"
    M2 = MX * MX + MY * MY
    if M2 > 0:
        # m |c|^2 = M2 / m = JL / 2: half the inertia from the offset mass, half about the com
        m = 2.0 * M2 / JL
        if not m > MJ_MINVAL:
            raise ValueError(f"MX = {MX:.3g}, MY = {MY:.3g} kg m give the link a mass "
                             f"2 (MX^2 + MY^2) / JL = {m:.3g} kg, which MuJoCo refuses (at "
                             f"most {MJ_MINVAL:g}): a first moment this small is zero (not "
                             "identifiable) or the gravity is off")
        _inertial(link, m, JL / 2, (-MX / m, 0.0, -MY / m))
    else:
        _inertial(link, 1.0, JL)
    _joint(link, name, prismatic, 0.0, FV, FS, friction_timeconst)
    tendon = spec.add_tendon()
    tendon.name = f"{name}_spring"
    tendon.stiffness[0] = K
    tendon.springlength = [0.0, 0.0]
    tendon.wrap_joint(f"{name}_motor", 1.0)
    tendon.wrap_joint(name, -1.0)
    _motor(spec, f"{name}_motor", f"{name}_motor", tau_max)
    if gear_ratio is not None:
        spec.add_numeric(name=f"{name}_gear_ratio", data=[gear_ratio])
    return spec


def from_identification(ident: Identification, *, timestep: float, tau_max: float | None = None,
                        gravity: float = 9.81, name: str = "axis1",
                        integrator: mujoco.mjtIntegrator = mujoco.mjtIntegrator.mjINT_RK4
                        ) -> NominalAxis:
    """The nominal axis of an identification: `rigid` -> `rigid_axis`; `joint-motor` and
    `motor-only` (physical parameters) -> `two_mass_axis`. Friction that came out negative or
    unidentified is set to 0 (named in `notes`); non-positive inertia or stiffness raises
    ValueError."""
    p = ident.physical
    notes: list[str] = []

    def friction(key: str) -> float:
        v = p.get(key)
        if v is None or not math.isfinite(v):
            notes.append(f"{key} not identified: 0 in the nominal model")
            return 0.0
        if v < 0:
            notes.append(f"{key} = {v:.4g} < 0 identified: 0 in the nominal model")
            return 0.0
        return float(v)

    def need(key: str) -> float:
        v = p.get(key)
        if v is None or not v > 0:
            raise ValueError(f"the {ident.model} identification gives {key} = {v}: no nominal "
                             "model can be built (it must be positive)")
        return float(v)

    if ident.model == "rigid":
        params = {"J": need("J"), "FV": friction("FV"), "FS": friction("FS"),
                  "offset": float(p.get("offset", 0.0))}
        spec = rigid_axis(**params, timestep=timestep, prismatic=ident.prismatic,
                          tau_max=tau_max, gravity=gravity, name=name, integrator=integrator)
        return NominalAxis(spec, "rigid", params, tuple(notes))
    params = {"Jm": need("Jm"), "FVm": friction("FVm"), "FSm": friction("FSm"), "K": need("K"),
              "JL": need("JL"), "FV": friction("FV"), "FS": friction("FS"),
              "MX": 0.0 if ident.prismatic else float(p.get("MX", 0.0)),
              "MY": 0.0 if ident.prismatic else float(p.get("MY", 0.0))}
    spec = two_mass_axis(**params, timestep=timestep, prismatic=ident.prismatic,
                         tau_max=tau_max, gravity=gravity, name=name, integrator=integrator)
    return NominalAxis(spec, "joint-motor", params, tuple(notes))


def for_log(ident: Identification, log: Log, name: str | None = None) -> NominalAxis:
    """`from_identification` with the log's sample period as timestep, its `tau_max`, gravity,
    joint name (default axis1) and its plant's integrator (bench.sim.friction)."""
    return from_identification(ident, timestep=log.ts, tau_max=log.meta_float("tau_max"),
                               gravity=log.gravity, name=name or log.meta.get("joint") or "axis1",
                               integrator=integrator_for_log(log))


def compile_axis(spec: mujoco.MjSpec, source: str = "<nominal>") -> tuple[mujoco.MjModel, Axis]:
    """Compile `spec` and find its (single) axis; ModelStructureError when it does not follow
    the axis convention or has several axes."""
    try:
        model = spec.compile()
    except ValueError as err:
        raise ModelStructureError(f"{source}: does not compile: {err}") from None
    axes = find_axes(model, source)
    if len(axes) != 1:
        raise ModelStructureError(f"{source}: expected one axis, found "
                                  f"{', '.join(a.name for a in axes)}")
    return model, axes[0]


def write_xml(spec: mujoco.MjSpec, path) -> None:
    """Write the spec's MJCF to `path` atomically (compiles it first, as MjSpec.to_xml needs).
    MuJoCo's writer keeps 6 significant digits (relative 5e-6 on every value, the timestep
    included; the replay and the experiment set the timestep from the sample rate anyway)."""
    spec.compile()
    atomic_write_text(path, spec.to_xml())
