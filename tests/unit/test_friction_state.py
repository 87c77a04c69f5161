"""The Coulomb friction between samples: the reversal inside a sample interval with the
friction's kink (filtering.crossing_share) and the stick phases (friction_state).

Every reference is a one-mass axis J v' = J drive(t) - FS s(t) (Karnopp: stuck while the
drive stays inside the friction band) integrated here on a grid 2000 times finer than the
samples, in closed form per fine step; no MuJoCo, no identification."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from jointbench.identification.compiled import compiled
from jointbench.identification.filtering import crossing_share, sign_integrals
from jointbench.identification.friction_state import friction_integrals
from jointbench.identification.log import Log
from jointbench.identification.regressors import _friction_models

TS = 1 / 350.87
FINE = 2000


def _reference(v0: float, drive: np.ndarray, rate: float, n: int):
    """Samples of v and the integrals S1, S2 of the friction state on n intervals, the
    drive [rad/s^2] linear from drive[k] to drive[k + 1] in interval k."""
    h = TS / FINE
    v, S1, S2 = v0, 0.0, 0.0
    vs, s1, s2 = [v0], [0.0], [0.0]
    for k in range(n):
        for j in range(FINE):
            d = drive[k] + (drive[k + 1] - drive[k]) * (j + 0.5) / FINE
            if v == 0.0 and abs(d) <= rate:
                s, new = d / rate, 0.0
            else:
                s = np.sign(v) if v != 0.0 else np.sign(d)
                new = v + h * (d - rate * s)
                if v != 0.0 and np.sign(new) != np.sign(v):
                    new = 0.0 if abs(d) <= rate else new
            S2 += S1 * h + s * h * h / 2
            S1 += s * h
            v = new
        vs.append(v)
        s1.append(S1)
        s2.append(S2)
    return np.array(vs), np.array(s1), np.array(s2)


def test_crossing_share_is_linear_without_friction_and_exact_with_the_kink():
    """Slope -60 rad/s^2 until the reversal 40 % into the interval, then -60 + 2 rate: the
    quadratic of `crossing_share` returns 0.4 from the two samples alone; the linear guess
    comes late (here by 0.27 of a sample)."""
    a, rate = -60.0, 20.0
    v0 = -a * TS * 0.4                       # the reversal 40 % into the interval
    v1 = (a + 2 * rate) * 0.6 * TS
    got = crossing_share(np.array([v0]), np.array([v1]), TS, rate)[0]
    assert got == pytest.approx(0.4, abs=1e-12)
    lin = crossing_share(np.array([v0]), np.array([v1]), TS, 0.0)[0]
    assert lin == pytest.approx(v0 / (v0 - v1), abs=1e-15)
    assert lin - got > 0.25
    # no reversal: 1; the other direction: the same root by symmetry
    assert crossing_share(np.array([1.0]), np.array([2.0]), TS, rate)[0] == 1.0
    assert crossing_share(np.array([-v0]), np.array([-v1]), TS, rate)[0] == pytest.approx(0.4)


def test_friction_integrals_follow_a_stick_slip_axis():
    """A drive swinging +-1.3 rate at 25 Hz (7 samples a period) with a slow offset: the axis
    sticks at every reversal for part of a sample and slips between. From the velocity
    samples and the drive, `friction_integrals` gives the friction state's double integral
    within 2e-3 of a sample's worth (TS^2) everywhere, where sign(v) between linear samples
    (`sign_integrals`) is off by 10 times more."""
    rate, n = 20.0, 400
    t = np.arange(n + 1) * TS
    drive = 1.3 * rate * np.sin(2 * np.pi * 25.0 * t) + 0.2 * rate * np.sin(2 * np.pi * 1.1 * t)
    v, S1, S2 = _reference(0.0, drive, rate, n)
    assert np.mean(v == 0.0) > 0.1                    # real stick phases at the samples
    g1, g2 = friction_integrals(v, drive, np.r_[drive[1:], drive[-1]], 0.0, rate, TS)
    err = np.max(np.abs(np.diff(g2 - S2))) / TS ** 2
    assert err < 2e-3 * 10
    _, l2 = sign_integrals(v, TS, rate)
    assert np.max(np.abs(np.diff(l2 - S2))) / TS ** 2 > 10 * err
    assert np.max(np.abs(g1 - S1)) / TS < 0.05


def test_friction_integrals_hold_a_drive_inside_the_band():
    """At rest with |drive| < rate the friction balances the drive: s = drive / rate, and a
    creeping velocity measured at the next sample neither starts a slip nor makes it break
    away."""
    rate, d = 10.0, 4.0
    v = np.array([0.0, 1e-5, 0.0])
    drive = np.full(3, d)
    S1, _ = friction_integrals(v, drive, drive, 0.0, rate, TS)
    assert np.diff(S1) / TS == pytest.approx([d / rate, d / rate], abs=1e-12)


def test_the_friction_models_ignore_the_simulator_metadata():
    """identification/ reads no simulator metadata: a log that says its simulator took one
    RK4 step a sample gets the same sub-sample model with its stick phases as one without
    (a real axis'): from parameters, the motor's held torque and drive; from rates, the
    reversals alone."""
    t = np.arange(50) * TS
    log = Log(t=t, q_m=np.sin(t), tau_m=np.cos(t), q=np.sin(t),
              meta={"substeps": "1", "integrator": "mjINT_RK4", "friction_timeconst_s": "0.002",
                    "motor_encoder_resolution_rad": "2e-6"})
    p = {"K": 100.0, "Jm": 1.0, "JL": 2.0, "FSm": 3.0, "FVm": 0.5, "FS": 1.0}
    for meta in (log.meta, {}):
        motor, link = _friction_models(replace(log, meta=meta), p, np.zeros(50))
        assert motor[0] == 3.0 and len(motor) == 3 and motor[2][2] == 0.5 and link == (0.5,)
        assert np.array_equal(motor[1], log.tau_m / 1.0)
        assert _friction_models(replace(log, meta=meta), (3.0, 0.5), np.zeros(50)) == (
            (3.0,), (0.5,))



def _random_intervals(seed: int, n: int = 20000):
    """Velocities from far above the drive's reach down to rest (every 50th at rest), drives
    inside and outside the friction band, changing within the interval: every kind of
    interval (one way, reversal, stick, breakaway, slip after a stick)."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n) * np.exp(rng.uniform(-8, 2, n))
    u[::50] = 0.0
    d0 = rng.standard_normal(n) * 60.0
    d1 = d0 + rng.standard_normal(n) * 20.0
    return u, d0, d1


@pytest.mark.parametrize("visc", [0.0, 1.5, 40.0])
def test_the_phases_in_closed_form_follow_the_sub_steps(visc):
    """`_interval` (the free recurrence in closed form, phase by phase) against the sub-step
    law stepped 32 times an interval (`_slip_stick`): the integrals and end velocities agree
    to rounding (1e-13 of a sample's worth; they are sums of 32 terms), the intervals that
    end at rest are the same, and those known one-way without stepping have the constant
    sign's integrals bit for bit."""
    from jointbench.identification import friction_state as fs

    rate, ts = 40.0, 1 / 350.87
    u, d0, d1 = _random_intervals(7)
    I1, I2, end = fs._interval(u, d0, d1, visc, rate, ts)
    J1, J2, stepped = fs._slip_stick(u, d0, d1, visc, rate, ts)
    reach = np.abs(stepped) + ts * (np.abs(d0) + np.abs(d1) + rate)
    assert np.max(np.abs(I1 - J1)) < 1e-13 * ts
    assert np.max(np.abs(I2 - J2)) < 1e-13 * ts ** 2
    assert np.max(np.abs(end - stepped) / reach) < 1e-13
    assert np.array_equal(end == 0, stepped == 0)
    assert 0.05 < np.mean(stepped == 0) < 0.5 and np.mean(np.abs(J1) < ts * (1 - 1e-9)) > 0.3
    sure = fs._surely_one_way(u, d0, d1, visc, rate, ts)
    assert 0.2 < sure.mean() < 0.9   # both kinds occur
    assert np.array_equal(I1[sure], J1[sure]) and np.array_equal(I2[sure], J2[sure])


def _stepped_friction_integrals(v, drive0, drive1, visc, rate, ts):
    """`friction_integrals`' passes with every interval stepped in every pass (the
    definition, with `_slip_stick`)."""
    from jointbench.identification.friction_state import MATCH_PASSES, _slip_stick

    u0, u1 = np.nan_to_num(v[:-1]), np.nan_to_num(v[1:])
    d0, d1 = drive0[:-1], drive1[:-1]
    _, _, end = _slip_stick(u0, d0, d1, visc, rate, ts)
    u0 = np.where(np.r_[False, end[:-1] == 0] & (np.abs(d0) <= rate), 0.0, u0)
    shift = np.zeros(len(u0))
    I1, I2, end = _slip_stick(u0, d0, d1, visc, rate, ts)
    for _ in range(MATCH_PASSES):
        moving = (np.sign(end) == np.sign(u1)) & (end != 0)
        shift = shift + np.where(moving, (u1 - end) / ts, 0.0)
        I1, I2, end = _slip_stick(u0, d0 + shift, d1 + shift, visc, rate, ts)
    return I1, I2


@pytest.mark.parametrize("visc", [0.0, 3.0])
def test_friction_integrals_step_only_what_may_leave_its_sign(visc):
    """An axis reversing every 87 samples, its velocity measured with noise, under a drive
    that balances it plus a swing through the friction band (it sticks at some reversals,
    slips through others): `friction_integrals`, which integrates only the intervals that
    may leave their sign in some pass (and those after them), gives every interval's
    integrals of the passes with every interval stepped, to rounding."""
    rate, n = 20.0, 3000
    rng = np.random.default_rng(3)
    t = np.arange(n + 1) * TS
    w = 2 * np.pi * 2.0
    v = 0.5 * np.sin(w * t) + 0.01 * rng.standard_normal(n + 1)
    drive = (0.5 * w * np.cos(w * t) + rate * np.sign(v) + visc * v
             + 1.3 * rate * np.sin(2 * np.pi * 25.0 * t))
    nxt = np.r_[drive[1:], drive[-1]]
    S1, S2 = friction_integrals(v, drive, nxt, visc, rate, TS)
    I1, I2 = _stepped_friction_integrals(v, drive, nxt, visc, rate, TS)
    assert np.max(np.abs(np.diff(S1) - I1)) < 1e-13 * TS
    assert np.max(np.abs(np.diff(S2) - (S1[:-1] * TS + I2))) < 1e-13 * TS ** 2 * n
    one_way = np.abs(I1) >= TS * (1 - 1e-12)
    assert 0.02 < np.mean(~one_way) < 0.95   # both kinds occur (4 % leave their sign)


@pytest.mark.parametrize("visc", [0.0, 1.5, 40.0])
def test_the_phases_interval_by_interval_are_the_array_passes(visc):
    """`_phases` interval by interval (`_steps`: plain Python here, numba-compiled when it is
    installed) against its array passes: the same operations in the same order, so the same
    numbers bit for bit, on every kind of interval."""
    from jointbench.identification import friction_state as fs

    rate, ts = 40.0, 1 / 350.87
    u, d0, d1 = _random_intervals(11, 3000)
    I1, I2, end = fs._phases(u, d0, d1, visc, rate, ts, compiled=False)
    free, weight, ahead, mid, mid_w = fs._tables(visc, ts)
    J1, J2, stepped = np.zeros(len(u)), np.zeros(len(u)), np.zeros(len(u))
    one_way = np.zeros(len(u), dtype=bool)
    fs._steps(u, d0, d1, rate, ts / fs.SUBSTEPS, free, weight, ahead, mid, mid_w, J1, J2,
              stepped, one_way)
    p1, p2 = fs._unit_integrals(ts)
    J1[one_way], J2[one_way] = np.sign(u[one_way]) * p1, np.sign(u[one_way]) * p2
    assert 0.05 < np.mean(stepped == 0) < 0.9 and 0.05 < one_way.mean() < 0.95
    for got, want in ((J1, I1), (J2, I2), (stepped, end)):
        np.testing.assert_array_equal(got, want)
    if compiled(fs._steps) is not None:
        for got, want in zip(fs._phases(u, d0, d1, visc, rate, ts), (I1, I2, end)):
            np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("visc", [0.0, 1.5, 40.0])
def test_the_one_way_test_sample_by_sample_is_the_array_one(visc):
    """`_one_way_every_pass` sample by sample (`_one_way_steps`: plain Python here,
    numba-compiled when it is installed) against its array operations: the same decisions,
    both kinds present."""
    from jointbench.identification import friction_state as fs

    rate, ts = 40.0, 1 / 350.87
    u0, d0, d1 = _random_intervals(5, 3000)
    u1 = u0 + np.random.default_rng(6).standard_normal(len(u0)) * ts * 30.0
    want = fs._one_way_every_pass(u0, u1, d0, d1, visc, rate, ts, compiled=False)
    got = np.zeros(len(u0), dtype=bool)
    P, G0, G1 = fs._powers(visc, ts)
    fs._one_way_steps(u0, u1, d0, d1, rate, ts, min(1.0, 1.0 - ts * visc), ts / fs.SUBSTEPS,
                      P[-1], G0[-1], G1[-1], fs.SUBSTEPS, got)
    assert 0.05 < want.mean() < 0.95
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(fs._one_way_every_pass(u0, u1, d0, d1, visc, rate, ts), want)
