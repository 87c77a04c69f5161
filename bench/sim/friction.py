"""Is MuJoCo's Coulomb friction hard enough for the paper's model?

MuJoCo's `frictionloss` is a soft velocity constraint: below a velocity band it acts as a
steep viscous ramp, not as FS sign(v). With the reference acceleration a_ref = -b v,
b = 2 / (dmax timeconst), the friction saturates at FS only for |v| > v_b = FS dmax
timeconst / (2 J), J the dof's inertia; timeconst is solreffriction's, raised to two time
steps unless `<flag refsafe="disable"/>`. MuJoCo's default (0.02 s) gives arm6-like axes
v_b ~ 0.01 rad/s, inside which a chirp spends a few % of its samples: Jm +6 %, FVm +70 %,
FS -22 %.

The shipped models make the friction as hard as the physics step h allows: a solreffriction
under two steps, which refsafe raises to timeconst = 2 h, so that b h = 1 / dmax, and the
semi-implicit Euler integrator, which solves the constraint once a step. A velocity inside
v_b = FS dmax h / J (what the friction takes away in one step) then stops within the step,
and beyond it the friction is FS sign(v): the Karnopp stick-slip law of an ideal Coulomb
friction, switching at the physics step inside the sample interval as a real axis' friction
switches between samples. A fixed time constant instead leaves a ramp of width v_b around
every reversal, a lag of about timeconst / 2 in the friction's switch, which biases Jm in
proportion (arm6 axis6, 60 s: Jm about +0.12 % at 0.25 ms, +0.05 % at 0.05 ms, against
+0.01 % dead-beat); RK4 evaluates the constraint at four stages and blends their forces, so
a stick that starts inside a step is smeared over it.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from jointbench.identification.log import format_meta_number
from jointbench.bench.sim.plant_keys import (PLANT_INTEGRATOR_KEY, PLANT_STEPS_KEY,
                                             PLANT_TIMECONST_KEY, plant_steps, plant_timeconst)
from jointbench.identification.log.schema import Log

SOFT_ERROR_MAX = 0.01   # friction error RMS over the torque RMS above which the model is warned


# A time constant read from an MJCF that MuJoCo wrote carries 6 significant digits (5e-6
# relative): within this share over two physics steps it is taken as two steps.
TWO_STEPS_SLACK = 1e-5


@dataclass(frozen=True)
class FrictionBand:
    """The velocity band [rad/s or m/s] below which a dof's Coulomb friction is a ramp, unless
    `dead_beat`: a single-stage integrator and a time constant between one and two physics
    steps stop a velocity inside the band within one step, the Karnopp stick of an ideal
    Coulomb friction at the physics step (module docstring), and there is no ramp."""

    dof: str            # "motor" or "link"
    v_band: float
    timeconst: float    # effective solreffriction time constant [s]
    FS: float           # the dof's frictionloss [N m or N]
    dead_beat: bool = False


def friction_bands(model: mujoco.MjModel, motor_dof: int, link_dof: int) -> list[FrictionBand]:
    """The band of each of the axis' dofs that has Coulomb friction (module docstring)."""
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    M = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    out = []
    for name, dof in (("motor", motor_dof), ("link", link_dof)):
        fs = float(model.dof_frictionloss[dof])
        tc = effective_timeconst(model, dof)
        if fs <= 0 or tc <= 0:   # no friction, or solref given as (-stiffness, -damping)
            continue
        dmax = float(model.dof_solimp[dof][1])
        h = float(model.opt.timestep)
        dead_beat = (int(model.opt.integrator) != int(mujoco.mjtIntegrator.mjINT_RK4)
                     and h <= tc <= 2 * h * (1 + TWO_STEPS_SLACK))
        out.append(FrictionBand(name, fs * dmax * tc / (2 * float(M[dof, dof])), tc, fs,
                                dead_beat))
    return out


def soft_friction_warnings(bands: list[FrictionBand], v_motor: np.ndarray,
                           v_link: np.ndarray | None, tau: np.ndarray, period: float
                           ) -> list[str]:
    """A warning, with the fix, per dof whose friction departs from FS sign(v) by more than
    1 % of the torque (RMS of FS (sign(v) - clip(v / v_b, -1, 1)) over the RMS of tau): the
    model error the least squares of eq. (13) then absorbs."""
    out = []
    scale = float(np.sqrt(np.mean(np.square(tau)))) if len(tau) else 0.0
    for b in bands:
        if b.dead_beat:
            continue
        v = v_motor if b.dof == "motor" else v_link
        if v is None or not len(v) or scale == 0:
            continue
        miss = b.FS * (np.sign(v) - np.clip(v / b.v_band, -1.0, 1.0))
        ratio = float(np.sqrt(np.mean(miss ** 2))) / scale
        if ratio > SOFT_ERROR_MAX:
            share = float(np.mean(np.abs(v) < b.v_band))
            out.append(
                f"MuJoCo's {b.dof} friction is soft: below |v| = {b.v_band:.3g} (timeconst "
                f"{b.timeconst:.3g} s) it is a viscous ramp, not FS sign(v); {100 * share:.2g} % "
                f"of the samples lie there and the difference is {100 * ratio:.2g} % of the "
                "torque (RMS), which biases Jm and the frictions; fix: solreffriction="
                "\"0.000001 1\" on the joints, refsafe on (MuJoCo's default) and "
                "integrator=\"Euler\" in <option>: the friction dead-beat at the physics step "
                "(as models/arm6.xml)")
    return out


META_KEY = PLANT_TIMECONST_KEY   # docs/log-format.md: the simulated axis' solreffriction


def effective_timeconst(model: mujoco.MjModel, dof: int) -> float:
    """The time constant [s] the friction constraint of `dof` runs with: its solreffriction,
    raised to two physics steps when refsafe is on (MuJoCo's rule)."""
    tc = float(model.dof_solref[dof][0])
    if tc > 0 and not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_REFSAFE:
        tc = max(tc, 2 * float(model.opt.timestep))
    return tc


def motor_timeconst(model: mujoco.MjModel, motor_dof: int) -> float:
    """The friction time constant the rotor dof runs with [s] (`effective_timeconst`: what a
    log of this model carries under META_KEY, so that replicas of it, at the log's physics
    steps and with refsafe off, stick as it does)."""
    return effective_timeconst(model, motor_dof)


def integrator_for_log(log: Log) -> mujoco.mjtIntegrator:
    """The integrator that replays `log`'s plant as it was simulated: the log's own when it
    names one of MuJoCo's (a jointbench log carries it), else RK4, whose four stages keep a
    friction constraint slower than the step stable (a measured axis' replica has no physics
    step of its own)."""
    name = log.meta.get(PLANT_INTEGRATOR_KEY, "").strip()
    return mujoco.mjtIntegrator.__members__.get(name, mujoco.mjtIntegrator.mjINT_RK4)


def plant_meta(model: mujoco.MjModel, motor_dof: int, substeps: int) -> dict[str, str]:
    """How the simulated plant switches its friction, as a log of it carries it: physics steps
    per sample (`substeps`), the integrator and the rotor's friction time constant (META_KEY).
    The identification reads none of them; the bench's replays (bias correction, refinement,
    forward view) do, to simulate the plant as it was; a measured log has none of them."""
    return {PLANT_STEPS_KEY: str(substeps),
            PLANT_INTEGRATOR_KEY: mujoco.mjtIntegrator(model.opt.integrator).name,
            META_KEY: format_meta_number(motor_timeconst(model, motor_dof))}


def log_substeps(log: Log, default: int) -> int:
    """MuJoCo steps per sample that simulate `log`'s plant as it was simulated: the log's own
    `substeps` (a jointbench log of a MuJoCo plant carries it), else `default`. A replica of
    the log (bias correction, refinement, replay) then has the log's discretisation."""
    steps = plant_steps(log)
    return int(steps) if steps is not None and steps >= 1 and steps == int(steps) else default


def timeconst_for_log(log: Log, default: float, given: float | None = None
                      ) -> tuple[float, str]:
    """The friction time constant of a nominal axis replaying a log, and where it comes from:
    `given` (the command's flag), else the log's META_KEY (a jointbench log carries its
    model's), else `default`, said to be one: a measured robot's friction has no MuJoCo time
    constant, and the bias correction depends on it (README, "Bias correction"). Raises
    LogError when the log's value is not a number."""
    if given is not None:
        return given, "given (--friction-timeconst)"
    value = plant_timeconst(log)
    if value is not None:
        return value, f"the log's {META_KEY} (the simulated model's)"
    return default, (f"default: the log has no {META_KEY}; a measured axis's Coulomb friction "
                     "has none, and the correction of Jm and the frictions depends on it "
                     "(set --friction-timeconst)")

