"""The closed-loop stepper (bench/sim/loop.py) on tiny models against analytic expectations."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from jointbench.bench.sim.axes import static_link_position, static_position
from jointbench.bench.sim.controller import Gains
from jointbench.bench.sim.loop import CoulombSwitch, LoopChecks, first_warning, run_loop
from jointbench.bench.sim.nominal import compile_axis, rigid_axis, two_mass_axis
from jointbench.bench.sim.sensors import Sensors
from jointbench.bench.effects import torque_lag

T = 1.0 / 350.87
J = 0.5          # kg m^2, the rotor
TAU = 2.0        # N m
OPEN = Gains(kp=0.0, kv=0.0, ki=0.0, tau_max=100.0)  # tau_m[k] = I[-1] = tau0 for ever


def rotor(substeps: int = 1):
    """A rigid frictionless rotor J on a hinge, no gravity torque (mass on the axis)."""
    model, axis = compile_axis(rigid_axis(J, 0.0, 0.0, timestep=T / substeps))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data, axis


@pytest.mark.parametrize("substeps", [1, 4])
def test_constant_torque_on_rigid_rotor_is_a_parabola(substeps):
    """tau held over each tick (zero-order hold): q(t) = tau / (2 J) t^2 from rest, which RK4
    integrates exactly (up to rounding) whatever the number of substeps."""
    model, data, axis = rotor(substeps)
    n = 200
    trace = run_loop(model, data, axis, OPEN, T, TAU, np.zeros(n), substeps=substeps)
    t = np.arange(n) * T
    np.testing.assert_allclose(trace.q_m, 0.5 * TAU / J * t**2, rtol=1e-9, atol=1e-15)
    np.testing.assert_array_equal(trace.q_m, trace.q_m_true)  # exact sensors by default
    np.testing.assert_array_equal(trace.q, trace.q_m)        # one joint: q reads q_m
    assert np.all(trace.tau_m == TAU) and np.all(trace.tau_applied == TAU)
    assert trace.saturated == 0 and trace.clamped == 0
    assert first_warning(data) is None


def test_first_tick_gives_the_logged_initial_torque():
    """docs/controller.md: q_m[-1] = q_m[0], q_ref[-1] = q_ref[0], I[-1] = tau_m[0]: with the
    reference starting at the measured position, tau_m[0] is the integrator's initial state
    whatever the gains."""
    model, data, axis = rotor()
    data.qpos[axis.motor_qpos] = 0.3
    mujoco.mj_forward(model, data)
    gains = Gains(kp=40.0, kv=2500.0, ki=25000.0, tau_max=3000.0)
    q_ref = 0.3 + 0.01 * np.sin(np.arange(20) * T * 10.0)
    trace = run_loop(model, data, axis, gains, T, 12.5, q_ref)
    assert trace.tau_m[0] == 12.5
    assert trace.tau_m[1] != 12.5  # the loop acts from the second tick on


def test_disturbance_at_the_motor_is_recorded_at_the_link_it_is_not():
    n = 100
    t = np.arange(n) * T
    dist = np.full(n, 1.0)
    model, data, axis = rotor()
    motor = run_loop(model, data, axis, OPEN, T, TAU, np.zeros(n), disturbance=dist,
                     disturbance_at="motor")
    assert np.all(motor.tau_m == TAU + 1.0)
    np.testing.assert_allclose(motor.q_m, 0.5 * (TAU + 1.0) / J * t**2, rtol=1e-9, atol=1e-15)
    model, data, axis = rotor()
    link = run_loop(model, data, axis, OPEN, T, TAU, np.zeros(n), disturbance=dist)
    assert np.all(link.tau_m == TAU)
    np.testing.assert_allclose(link.q_m, 0.5 * (TAU + 1.0) / J * t**2, rtol=1e-9, atol=1e-15)


def test_sensors_quantise_and_noise_is_seeded():
    n = 100
    sensors = Sensors(motor_resolution=1e-3, link_resolution=1e-3, torque_noise_std=0.5)
    runs = []
    for seed in (3, 3, 4):
        model, data, axis = rotor()
        runs.append(run_loop(model, data, axis, OPEN, T, TAU, np.zeros(n), sensors=sensors,
                             seed=seed))
    a, b, c = runs
    np.testing.assert_array_equal(a.q_m, b.q_m)
    assert not np.array_equal(a.tau_applied, c.tau_applied)
    np.testing.assert_allclose(a.q_m / 1e-3, np.round(a.q_m_true / 1e-3), atol=1e-9)
    noise = Sensors(0, 0, 0.5).torque_noise(np.random.default_rng(3), n)
    np.testing.assert_array_equal(a.tau_applied, TAU + noise)
    assert np.all(a.tau_m == TAU)  # the noise is applied, not recorded


def test_saturation_and_checks_handlers():
    class Stop(LoopChecks):
        position_limit = 0.01
        torque_limit = 1.0

        def __init__(self):
            self.saturated_ticks = []

        def saturated(self, k, u):
            self.saturated_ticks.append(k)

        def diverged(self, k, q_m, q):
            raise RuntimeError(f"tick {k}")

    model, data, axis = rotor()
    checks = Stop()
    # tau_max 1.5 clips the held 2 N m: q = 1.5 / (2 J) t^2 crosses 0.01 rad at t = 0.0816 s
    gains = Gains(kp=0.0, kv=0.0, ki=0.0, tau_max=1.5)
    with pytest.raises(RuntimeError, match="tick 29"):
        run_loop(model, data, axis, gains, T, TAU, np.zeros(100), checks=checks)
    assert checks.saturated_ticks == list(range(29))
    assert math.sqrt(0.01 * 2 * J / 1.5) / T == pytest.approx(28.65, abs=0.01)


def test_loop_effects_add_to_the_applied_torque():
    class Constant:
        def torque(self, q_m, qd_m):
            return -0.5

    model, data, axis = rotor()
    trace = run_loop(model, data, axis, OPEN, T, TAU, np.zeros(50), loop=Constant())
    assert np.all(trace.tau_applied == TAU - 0.5) and np.all(trace.tau_m == TAU)


def test_static_positions_of_a_spring_under_gravity():
    """Eq. (5) at rest: K (q_m - q) = the gravity torque on the link, solved for either side."""
    K, MX = 1000.0, 2.0
    model, axis = compile_axis(two_mass_axis(0.1, 0.0, 0.0, K, 1.0, MX=MX, timestep=T))
    qpos = model.qpos0.copy()
    q = static_link_position(model, axis, qpos)      # motor at 0
    assert K * (0.0 - q) == pytest.approx(MX * 9.81 * math.cos(q), rel=1e-8)
    qpos[axis.link_qpos] = 0.2
    qm = static_position(model, axis, qpos, "motor")  # link at 0.2
    assert K * (qm - 0.2) == pytest.approx(MX * 9.81 * math.cos(0.2), rel=1e-8)


@pytest.mark.parametrize("integrator", ["RK4", "Euler"])
@pytest.mark.parametrize("two_mass", [False, True])
def test_loop_effects_act_on_the_rotor_beside_a_torque_lag(two_mass, integrator):
    """docs/effects.md: a bench-loop torque (a ripple, an offset, an asymmetric friction) is
    mechanical, on the rotor, after the drive's torque lag. With the command at zero the lag's
    filter stays at zero, so a lagged and an unlagged axis under the same loop torque move
    alike (to rounding), on a rigid axis (one dof) and on a two-mass one (the motor dof)."""
    class Constant:
        def torque(self, q_m, qd_m):
            return -0.5

    mode = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    runs = []
    for lag in (0.0, 0.05):
        spec = (two_mass_axis(J, 0.0, 0.0, 1000.0, 1.0, timestep=T / 2, integrator=mode,
                              gravity=0.0) if two_mass else
                rigid_axis(J, 0.0, 0.0, timestep=T / 2, integrator=mode))
        torque_lag.mjcf(spec, "axis1", lag, {}, 0.0)
        model, axis = compile_axis(spec)
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        runs.append(run_loop(model, data, axis, OPEN, T, 0.0, np.zeros(100), substeps=2,
                             loop=Constant()))
    free, lagged = runs
    assert np.all(lagged.tau_m == 0.0) and np.all(lagged.tau_applied == -0.5)
    # 100 ticks of -0.5 N m on J: |q_m| ~ 0.5 / (2 J) (100 T)^2 = 0.04 rad; lagged by 0.05 s
    # (the filter's lag) it would fall short by about 0.5 / J 0.05 (100 T) = 0.014 rad
    np.testing.assert_allclose(lagged.q_m, free.q_m, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(lagged.q, free.q, rtol=1e-9, atol=1e-12)


def _ripple_rotor(substeps: int):
    """A rigid frictionless rotor J, semi-implicit Euler (the shipped models' integrator)."""
    model, axis = compile_axis(rigid_axis(J, 0.0, 0.0, timestep=T / substeps, gravity=0.0,
                                          integrator=mujoco.mjtIntegrator.mjINT_EULER))
    data = mujoco.MjData(model)
    return model, data, axis


class _Ripple:
    """A cogging torque R(q_m) = A sin(2 pi q_m / p + pi) (a restoring well at q_m = 0) that
    records, at each call, the time, the angle it is given, the rotor's angle and the torque
    that moved the rotor over the last physics step (its inertia times MuJoCo's qacc)."""

    A, p = 2.0, 0.02   # N m, rad: well stiffness 2 pi A / p = 628 N m/rad, f 5.6 Hz on J

    def __init__(self, model, data, axis):
        self.data, self.axis, self.calls = data, axis, []
        d = axis.motor_dof
        data.qfrc_applied[d] = 1.0   # the rotor's inertia: the torque of a unit acceleration
        mujoco.mj_forward(model, data)
        self.inertia = 1.0 / float(data.qacc[d])
        data.qfrc_applied[d] = 0.0
        mujoco.mj_forward(model, data)

    def torque(self, q_m, qd_m):
        d = self.data
        r = self.A * math.sin(2 * math.pi * q_m / self.p + math.pi)
        self.calls.append((d.time, q_m, float(d.qpos[self.axis.motor_qpos]),
                           self.inertia * float(d.qacc[self.axis.motor_dof]), r))
        return r


def test_a_ripple_acts_at_each_physics_step_from_that_steps_angle():
    """docs/effects.md: a ripple is a torque of the rotor's angle, continuous in time. Under a
    constant (zero) command each physics step applies A sin(2 pi q_m / p + phase) of that
    step's q_m (not the tick's, held over the tick), so the rotor oscillates in the ripple's
    well with the energy of the continuous law: the amplitude stays q0. (A torque held at the
    tick's angle lags it by about T / 2, a negative damping (2 pi A / p) T / 2 that grows the
    amplitude as exp(pi A T t / (2 p J)), 14 fold in 3 s while the well is linear; the rotor
    leaves the well.)"""
    substeps, n = 4, 1050          # 3 s, 17 periods of the well
    model, data, axis = _ripple_rotor(substeps)
    q0 = _Ripple.p / 8
    data.qpos[axis.motor_qpos] = q0
    mujoco.mj_forward(model, data)
    ripple = _Ripple(model, data, axis)
    trace = run_loop(model, data, axis, OPEN, T, 0.0, np.zeros(n), substeps=substeps,
                     loop=ripple)
    calls = np.array(ripple.calls)
    assert len(calls) == n * (1 + substeps)   # tau_applied's at the tick, then each step's
    steps = calls.reshape(n, 1 + substeps, 5)[:, 1:].reshape(-1, 5)
    time, q_given, q_rotor, applied, r = steps.T
    h = model.opt.timestep
    # every physics step evaluates the ripple at its own angle ...
    np.testing.assert_allclose(time / h, np.arange(n * substeps), atol=1e-6)
    np.testing.assert_array_equal(q_given, q_rotor)
    # ... and the rotor moves under what that evaluation gave
    np.testing.assert_allclose(applied[1:], r[:-1], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(trace.tau_applied,
                               _Ripple.A * np.sin(2 * np.pi * trace.q_m_true / _Ripple.p
                                                  + np.pi), rtol=1e-12, atol=1e-12)
    # the continuous law keeps the amplitude; semi-implicit Euler keeps a modified energy
    # within O(omega h) (omega h = 0.025 here), and the tick's samples catch the peak within
    # 1 - cos(omega T / 2) = 0.1 %
    last = np.max(np.abs(trace.q_m_true[-n // 17:]))
    assert last == pytest.approx(q0, rel=0.03)


def test_a_zero_loop_torque_steps_as_no_loop_effect():
    """A run with loop effects is stepped one physics step at a time; that alone changes
    nothing: a loop torque of zero gives the bit-identical run of none, on a two-mass axis
    with Coulomb friction on both sides (its reversals switched at the crossing,
    `CoulombSwitch`) under the PI cascade, noise and quantised encoders."""
    class Zero:
        def torque(self, q_m, qd_m):
            return 0.0

    n, substeps = 700, 4
    q_ref = 0.02 * np.sin(2 * np.pi * 3.0 * np.arange(n) * T)
    gains = Gains(kp=40.0, kv=2500.0, ki=25000.0, tau_max=3000.0)
    sensors = Sensors(motor_resolution=1e-5, link_resolution=1e-5, torque_noise_std=0.5)
    runs = []
    for loop in (None, Zero()):
        model, axis = compile_axis(two_mass_axis(
            J, 0.5, 3.0, 20000.0, 1.0, 0.2, 2.0, timestep=T / substeps, gravity=0.0,
            friction_timeconst=2 * T / substeps,
            integrator=mujoco.mjtIntegrator.mjINT_EULER))
        assert CoulombSwitch(model, (axis.motor_dof, axis.link_dof)).dofs
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        runs.append(run_loop(model, data, axis, gains, T, 0.0, q_ref, substeps=substeps,
                             sensors=sensors, seed=3, loop=loop))
    none, zero = runs
    assert np.count_nonzero(np.diff(np.sign(np.diff(none.q_m_true)))) >= 10   # reversals
    for name in ("q_m", "q", "tau_m", "q_m_true", "q_true", "tau_applied"):
        np.testing.assert_array_equal(getattr(zero, name), getattr(none, name))
