"""The closed-loop tick: the one stepper of the virtual experiment and of the replay of a log.

Per control tick k (period T, docs/controller.md):
  1. the encoders sample the motor and link positions (quantised by `Sensors`);
  2. the controller (`make_controller`: the PI cascade or a position loop, docs/controller.md)
     computes tau_m[k] from the encoders and q_ref[k];
  3. a disturbance, when given, adds to tau_m[k] (at the motor) or goes into qfrc_applied
     (at the link);
  4. the rotor receives tau_m[k] + torque noise, held over the tick (zero-order hold) while
     MuJoCo integrates `substeps` steps.
     Semi-implicit Euler (the shipped models') is the leapfrog scheme: the force of step n
     moves the velocity of [t_n - h/2, t_n + h/2], so a force switched at t_n acts h/2
     early, a lead of the torque over the positions first order in h, which the estimator
     reads as a delay of the held torque (unblended, at 29 steps a period: arm6 axis1
     FVm -6.5 %, FSm +1.3 % (4.5 sigma); a frictionless prototype's 5-point chain K +1.4 %).
     The first step of each tick therefore takes the mean of the held and the new torque
     (and link disturbance), the impulse of the zero-order hold over that half-open step;
     the others take the new one. An actuator with dynamics (a filter's state, continuous)
     takes the new torque at once. The bench-loop effects (a ripple, an offset, an
     asymmetric friction) are mechanical, functions of the rotor's state, on the rotor after
     the drive (docs/effects.md): their torque goes into qfrc_applied on the motor dof, not
     through the actuator (nor torque_lag's filter), evaluated at every physics step from
     that step's motor angle and velocity, as the continuous law is (a ripple held at the
     tick's angle lags the rotor by about half a tick); a run with them is stepped one
     physics step at a time;
  5. a tick in which the motor or the link velocity changes sign is stepped again one physics
     step at a time, and the Coulomb friction of the step where the velocity slips through
     zero is switched at the crossing (`CoulombSwitch`).
The fault checks (`LoopChecks`) compare the state with limits each tick and stop the run
through their handlers; the callers (`bench.sim.experiment`, `bench.sim.replay`) own the
starting state, the limits and the messages.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import mujoco
import numpy as np

from jointbench.bench.effects import LoopEffects
from jointbench.bench.sim.controller import Gains, PositionGains, make_controller
from jointbench.bench.sim.friction import TWO_STEPS_SLACK
from jointbench.bench.sim.sensors import Sensors
from jointbench.models import Axis

INSTABILITY_WARNINGS = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                        mujoco.mjtWarning.mjWARN_BADQACC)

# MuJoCo's default warning handler prints the text and appends it to MUJOCO_LOG.TXT in the
# working directory. Every run reads the warnings from MjData.warning (`first_warning`) and
# names them in its error, so the texts are only kept here (the last few, for messages) and
# nothing is written. `bench.sim.experiment` collects them per run on top of this handler.
MUJOCO_WARNING_TEXTS: list[str] = []


def _keep_warning(text: str) -> None:
    MUJOCO_WARNING_TEXTS.append(text)
    del MUJOCO_WARNING_TEXTS[:-10]


if mujoco.get_mju_user_warning() is None:
    mujoco.set_mju_user_warning(_keep_warning)


@dataclass(frozen=True)
class LoopTrace:
    """The signals of one run, one value per tick: `q_m`, `q` the encoder readings [rad or m]
    (`q` reads the motor joint on a rigid axis), `tau_m` the torque a log records (the
    controller's output plus a disturbance at the motor) [N m or N], `q_m_true`, `q_true` the
    exact positions, `tau_applied` the torque the rotor received before any actuator lag (the
    command plus noise plus the bench-loop effects' at the tick's state); `saturated` ticks
    clipped at tau_max, `clamped` ticks whose actuator input (the command plus noise)
    exceeded `LoopChecks.ctrl_limit`."""

    q_m: np.ndarray
    q: np.ndarray
    tau_m: np.ndarray
    q_m_true: np.ndarray
    q_true: np.ndarray
    tau_applied: np.ndarray
    saturated: int
    clamped: int


class LoopChecks:
    """The fault checks of a run. The stepper compares against the limits inline (cheap) and
    calls the handler when one is crossed; a handler raises to stop the run or returns to go
    on. The defaults check nothing."""

    position_limit = math.inf  # |q_m| must stay under it (a NaN fails too)
    link_limit = math.inf      # |q| must stay under it
    track_limit = math.inf     # |q_ref - q_m(measured)| must stay under it
    torque_limit = math.inf    # |tau_m| reaching it calls `saturated`
    ctrl_limit = math.inf      # |applied torque| over it counts as clamped

    def diverged(self, k: int, q_m: float, q: float) -> None:
        """|q_m| or |q| is over its limit (or not a number) at tick k."""

    def lost_track(self, k: int, error: float) -> None:
        """The motor is `error` from the reference at tick k."""

    def saturated(self, k: int, u: float) -> None:
        """The controller's output `u` reached the torque limit at tick k."""

    def mujoco_unstable(self, k: int) -> None:
        """MuJoCo flagged a bad qpos, qvel or qacc during the steps before tick k."""


SATURATED = 1e-6   # a friction force within this share of FS is saturated (a slip-through)


class CoulombSwitch:
    """The reversal of a dead-beat Coulomb friction placed at the velocity's crossing.

    With semi-implicit Euler and the friction constraint's time constant at refsafe's floor
    (2 h, impedance near 1, models/prototype_axis.xml) the constraint stops a velocity within
    one physics step h when FS can: an ideal Coulomb friction at the step (stick included).
    In a step where the drive carries the velocity v_n through zero, the constraint saturates
    at the new direction's friction for the whole step, while the exact law keeps the old
    direction's until the crossing t*: the friction switches t* early, about h / 2 at every
    slip-through reversal, a bias of Jm and the frictions first order in h. The impulse the
    step misses is P = -2 FS sign(v_n) t*, with t* = -v_n / a1 (at most h) and a1 the dof's
    acceleration under the old direction's friction, a1 = (v_{n+1} - v_n) / h
    - 2 FS sign(v_n) (M^-1)_dd; adding M^-1 e_d P to the velocities places the switch at the
    crossing (the position then lags by a term of order P h, second order). A creep inside a
    stick (the constraint's impedance leaves |v| near 1e-2 h |a|) may flip sign, and a step
    that stops the velocity (the constraint's force under FS: a stick begins) is not a
    slip-through; neither is corrected. Other integrators (RK4's stages blend the
    constraint) and a friction slower than two steps (a ramp, not saturated through the
    step) are left as MuJoCo steps them."""

    def __init__(self, model: mujoco.MjModel, dofs: Sequence[int]):
        h = model.opt.timestep
        refsafe = not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_REFSAFE
        euler = model.opt.integrator == mujoco.mjtIntegrator.mjINT_EULER
        self.dofs: tuple[int, ...] = tuple(
            d for d in dict.fromkeys(dofs)
            if euler and model.dof_frictionloss[d] > 0 and 0 < model.dof_solref[d][0]
            and (max(model.dof_solref[d][0], 2 * h) if refsafe else model.dof_solref[d][0])
            <= 2 * h * (1 + TWO_STEPS_SLACK))
        self._spec = mujoco.mjtState.mjSTATE_INTEGRATION
        self._state = np.empty(mujoco.mj_stateSize(model, self._spec))
        self._unit = np.zeros((1, model.nv))
        self._column = np.empty((1, model.nv))

    def step(self, model: mujoco.MjModel, data: mujoco.MjData, substeps: int) -> None:
        """`substeps` physics steps, a velocity's sign change among them stepped again one
        step at a time with its switch placed (class docstring)."""
        if not self.dofs:
            mujoco.mj_step(model, data, substeps)
            return
        qvel = data.qvel
        before = [qvel[d] for d in self.dofs]
        mujoco.mj_getState(model, data, self._state, self._spec)
        mujoco.mj_step(model, data, substeps)
        if all(v * qvel[d] >= 0 for v, d in zip(before, self.dofs)):
            return
        mujoco.mj_setState(model, data, self._state, self._spec)
        h = model.opt.timestep
        for _ in range(substeps):
            vn = [qvel[d] for d in self.dofs]
            mujoco.mj_step(model, data)
            for v, d in zip(vn, self.dofs):
                if v * qvel[d] < 0:
                    self._switch(model, data, d, v, h)

    def step_one(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """One physics step with a velocity's sign change in it switched at the crossing: the
        same step as `step(model, data, 1)`, without its save and replay of the state."""
        qvel = data.qvel
        before = [qvel[d] for d in self.dofs]
        mujoco.mj_step(model, data)
        for v, d in zip(before, self.dofs):
            if v * qvel[d] < 0:
                self._switch(model, data, d, v, model.opt.timestep)

    def _switch(self, model: mujoco.MjModel, data: mujoco.MjData, d: int, v: float,
                h: float) -> None:
        fs = float(model.dof_frictionloss[d])
        s = 1.0 if v > 0 else -1.0
        n = data.nefc
        row = np.flatnonzero((data.efc_type[:n] == mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF)
                             & (data.efc_id[:n] == d))
        if not len(row) or data.efc_force[row[0]] * s < fs * (1 - SATURATED):
            return   # the constraint stopped the velocity (a stick): no slip-through
        self._unit[0, d] = 1.0
        mujoco.mj_solveM(model, data, self._column, self._unit)   # M(q_n)^-1 e_d
        self._unit[0, d] = 0.0
        a1 = (data.qvel[d] - v) / h - 2 * fs * s * self._column[0, d]
        t_cross = min(h, -v / a1) if a1 * s < 0 else 0.0
        data.qvel[:] += self._column[0] * (-2 * fs * s * t_cross)


def first_warning(data: mujoco.MjData) -> tuple[str, int] | None:
    """The first MuJoCo warning raised on `data` as (name, count), None when there is none."""
    for w in range(len(data.warning)):
        if data.warning[w].number:
            return mujoco.mjtWarning(w).name, int(data.warning[w].number)
    return None


def _add_rotor(qfrc: np.ndarray, dm: int, dl: int, rotor: float) -> None:
    """Put the loop effects' torque `rotor` on the motor dof of `qfrc` (qfrc_applied), after
    the link force was written: added to it on a rigid axis (one dof), set otherwise."""
    if dm == dl:
        qfrc[dm] += rotor
    else:
        qfrc[dm] = rotor


def run_loop(model: mujoco.MjModel, data: mujoco.MjData, axis: Axis,
             gains: Gains | PositionGains,
             period: float, tau0: float, q_ref: Sequence[float], *, substeps: int = 1,
             sensors: Sensors | None = None, seed: int = 0, loop: LoopEffects | None = None,
             disturbance: Sequence[float] | None = None, disturbance_at: str = "link",
             checks: LoopChecks | None = None,
             progress: Callable[[float], None] | None = None) -> LoopTrace:
    """Run len(q_ref) ticks of the module docstring from the state in `data` (stepped in
    place). `period` T [s]; `tau0` the integrator's initial state I[-1]; `sensors` quantise
    the encoders and draw the torque noise from `seed` (default: exact, no noise); `loop`
    adds its torque to the applied one; `disturbance` [N m or N per tick] enters at
    `disturbance_at` ("link" or "motor"); `progress(fraction)` is called about 100 times.
    Raises whatever the `checks` handlers raise."""
    sensors = sensors or Sensors.ideal()
    checks = checks or LoopChecks()
    n = len(q_ref)
    quant_m, quant_l = sensors.motor_quantizer(), sensors.link_quantizer()
    noise = sensors.torque_noise(np.random.default_rng(seed), n).tolist()
    ctrl = make_controller(gains, period, tau0)
    q_m, q, tau = np.empty(n), np.empty(n), np.empty(n)
    q_m_true, q_true, tau_app = np.empty(n), np.empty(n), np.empty(n)
    qpos, qvel, ctrl_arr, qfrc = data.qpos, data.qvel, data.ctrl, data.qfrc_applied
    im, il, dm, dl, act = (axis.motor_qpos, axis.link_qpos, axis.motor_dof, axis.link_dof,
                           axis.actuator)
    switch = CoulombSwitch(model, (axis.motor_dof, axis.link_dof))
    step, step_one = switch.step, switch.step_one
    leapfrog = int(model.opt.integrator) != int(mujoco.mjtIntegrator.mjINT_RK4)
    # an actuator with dynamics (torque_lag's filter) applies its continuous state: no switch
    lagged = int(model.actuator_dyntype[act]) != int(mujoco.mjtDyn.mjDYN_NONE)
    blend = leapfrog and not lagged
    held, held_link = float(tau0), float(qfrc[dl])
    refs = np.asarray(q_ref, dtype=float).tolist()  # Python floats: the fast scalar path
    dist = None if disturbance is None else np.asarray(disturbance, dtype=float).tolist()
    at_motor = disturbance_at == "motor"
    pos_limit, link_limit = checks.position_limit, checks.link_limit
    track_limit, torque_limit, ctrl_limit = checks.track_limit, checks.torque_limit, \
        checks.ctrl_limit
    bad_qpos, bad_qvel, bad_qacc = (data.warning[int(w)] for w in INSTABILITY_WARNINGS)
    every = max(1, n // 100)
    clamped = 0
    for k in range(n):
        qm_k = qpos[im]
        ql_k = qpos[il]
        # Before quantising: round() of an infinite or NaN position raises.
        if not (abs(qm_k) < pos_limit and abs(ql_k) < link_limit):
            checks.diverged(k, qm_k, ql_k)
        meas_m = quant_m(qm_k)
        r_k = refs[k]
        if abs(r_k - meas_m) > track_limit:
            checks.lost_track(k, r_k - meas_m)
        meas_l = quant_l(ql_k)
        u = ctrl.step(meas_m, r_k, meas_l)
        if abs(u) >= torque_limit:
            checks.saturated(k, u)
        link_force = held_link
        if dist is not None:
            if at_motor:
                u += dist[k]
            else:
                link_force = dist[k]
        applied = u + noise[k]
        # the loop effects act on the rotor (docs/effects.md), a function of its state at
        # each physics step, beside the actuator (and torque_lag's filter), not through it
        tau_app[k] = applied if loop is None else applied + loop.torque(qm_k, qvel[dm])
        if abs(applied) > ctrl_limit:
            clamped += 1
        q_m[k], q[k], tau[k] = meas_m, meas_l, u
        q_m_true[k], q_true[k] = qm_k, ql_k
        if loop is not None:
            ctrl_arr[act] = 0.5 * (held + applied) if blend else applied
            qfrc[dl] = 0.5 * (held_link + link_force) if leapfrog else link_force
            for j in range(substeps):
                if j == 1:
                    ctrl_arr[act] = applied
                if j:
                    qfrc[dl] = link_force
                _add_rotor(qfrc, dm, dl, loop.torque(qpos[im], qvel[dm]))
                step_one(model, data)
        elif leapfrog:
            ctrl_arr[act] = 0.5 * (held + applied) if blend else applied
            qfrc[dl] = 0.5 * (held_link + link_force)
            step(model, data, 1)
            if substeps > 1:
                ctrl_arr[act] = applied
                qfrc[dl] = link_force
                step(model, data, substeps - 1)
        else:
            ctrl_arr[act] = applied
            qfrc[dl] = link_force
            step(model, data, substeps)
        held, held_link = applied, link_force
        if bad_qpos.number or bad_qvel.number or bad_qacc.number:
            checks.mujoco_unstable(k + 1)
        if progress is not None and k % every == 0:
            progress(k / n)
    return LoopTrace(q_m=q_m, q=q, tau_m=tau, q_m_true=q_m_true, q_true=q_true,
                     tau_applied=tau_app, saturated=ctrl.saturated, clamped=clamped)
