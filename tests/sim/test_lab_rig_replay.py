"""The lab-rig family of the independent simulator (tests/indep_sim.py `simulate_lab_rig`):
its log describes its controller (docs/controller.md), and a MuJoCo replay of it on the true
axis reproduces it to the noise floor, one log per controller kind of docs/controller.md
(P, PD, PI, PID, the PI cascade, a transfer function; with and without feed-forward; on q_m
and on q)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from jointbench.testing.simulator import (LAB_RIG, LAB_RIG_RATE, Multisine, PositionLoop,
                                          simulate_lab_rig)

from jointbench.bench.sim import nominal as nominal_axes
from jointbench.bench.sim.controller import (Gains, TransferGains, control_law,
                                             controller_from_log)
from jointbench.bench.sim.replay import forward_errors, replay

DURATION = 12.0
G = LAB_RIG.volt_to_torque
T = 1.0 / LAB_RIG_RATE


def _tf_pid() -> PositionLoop:
    """A PID with a filtered derivative, G (2 + 1 / s + 0.05 s / (0.01 s + 1)), discretised by
    Tustin in python-control, as a TF loop on the link encoder."""
    control = pytest.importorskip("control")
    c = control.tf([G * (2 * 0.01 + 0.05), G * (2 + 0.01), G], [0.01, 1, 0])
    tf = TransferGains.from_control(control.sample_system(c, T, method="tustin"), 1.0)
    return PositionLoop("TF", feedback="q", num=tf.num, den=tf.den)


def _cascade(feedforward: bool) -> PositionLoop:
    """docs/controller.md section 2 with a velocity crossover wv = 2 pi 4 rad/s on the rigid
    inertia (kv = J wv, ki = kv wv / 4, kp = wv / 4, the bench's rule at a lower wv)."""
    wv = 2 * math.pi * 4.0
    kv = (LAB_RIG.Jm + LAB_RIG.JL) * wv
    return PositionLoop("PI cascade", kp=wv / 4, kv=kv, ki=kv * wv / 4, feedforward=feedforward)


# kind -> (loop, reference RMS [rad]): each kind once, the derivative and the cascade with
# and without feed-forward, feedback on q_m and on q; the stiffer loops get a smaller
# reference so that the command stays within u_max
LOOPS = {
    "P": (None, 0.5),    # the lab's: u = 1 V/rad (r - theta)
    "PD": (PositionLoop("PD", kp=G * 2.0, kd=G * 0.05, feedforward=True), 0.5),
    "PD-q": (PositionLoop("PD", kp=G * 2.0, kd=G * 0.05, feedback="q"), 0.5),
    "PI": (PositionLoop("PI", kp=G * 1.0, ki=G * 0.5), 0.5),
    "PID-q": (PositionLoop("PID", kp=G * 2.0, ki=G * 1.0, kd=G * 0.05, feedback="q"), 0.5),
    "PID-ff": (PositionLoop("PID", kp=G * 2.0, ki=G * 1.0, kd=G * 0.05, feedforward=True),
               0.5),
    "cascade": (_cascade(True), 0.05),
    "cascade-noff": (_cascade(False), 0.05),
    "TF-q": (None, 0.5),     # _tf_pid(), built in the test (python-control)
}


def _truth_axis(log):
    f = LAB_RIG.family
    spec = nominal_axes.two_mass_axis(Jm=f.Jm, FVm=f.FVm, FSm=f.FSm, K=f.K, JL=f.JL, FV=f.FV,
                                      timestep=log.ts, tau_max=f.tau_max, gravity=0.0,
                                      name="lab_rig")
    return nominal_axes.compile_axis(spec)


def test_lab_rig_is_deterministic_and_its_metadata_is_the_torque_law():
    a, b = simulate_lab_rig(seed=4, duration=4.0), simulate_lab_rig(seed=4, duration=4.0)
    for x, y in ((a.q_m, b.q_m), (a.q, b.q), (a.tau_m, b.tau_m), (a.q_ref, b.q_ref)):
        assert np.array_equal(x, y)
    g = controller_from_log(a)
    assert g.kind == "P" and g.kp == pytest.approx(G * 1.0)
    # the logged command is the documented law on the logged positions (rounding only)
    assert np.max(np.abs(control_law(a.q_m, a.q_ref, g, a.ts, 0.0) - a.tau_m)) < 1e-9
    # the columns the lab records: q = theta - alpha, tau_m = g_u u; back-EMF inside FVm
    assert np.array_equal(a.q, a.extra["theta"] - a.extra["alpha"])
    assert np.allclose(a.tau_m, G * a.extra["u"])
    assert float(a.meta["truth_FVm"]) == pytest.approx(
        LAB_RIG.FVm_mech + LAB_RIG.back_emf_damping)
    res = 2 * math.pi / 4096
    assert np.allclose(np.round(a.extra["alpha"] / res) * res, a.extra["alpha"])


@pytest.mark.parametrize("kind", list(LOOPS))
def test_replay_of_each_controller_kind_reaches_the_noise_floor(kind):
    """The floor: the same run without voltage noise and quantisation (same seed, same
    reference) differs from the log by what no replay can know. The replay measures exactly
    and has no noise, so its error is the floor plus the model's own (MuJoCo against RK4,
    frictionloss against tanh), which the replay of that ideal twin measures: the noisy
    replay's error stays within 10 % over their quadrature sum (the cross term)."""
    loop, rms = LOOPS[kind]
    loop = _tf_pid() if kind == "TF-q" else loop
    ref = Multisine(DURATION, rms=rms)
    log = simulate_lab_rig(seed=7, duration=DURATION, loop=loop, reference=ref)
    twin = simulate_lab_rig(replace(LAB_RIG, voltage_noise_std=0.0, counts=0.0), seed=7,
                            duration=DURATION, loop=loop, reference=ref)
    assert log.meta["saturated_samples"] == "0"
    got = controller_from_log(log)
    want = loop or PositionLoop("P")
    if want.kind == "PI cascade":
        assert isinstance(got, Gains) and got.velocity_feedforward == want.feedforward
    elif want.kind == "TF":
        assert isinstance(got, TransferGains) and got.feedback == want.feedback
    else:
        assert (got.kind, got.feedback, got.velocity_feedforward) == (
            want.kind, want.feedback, want.feedforward)
    model, axis = _truth_axis(log)
    err = forward_errors(log, replay(model, axis, log))
    own = forward_errors(twin, replay(model, axis, twin))
    for col, key in (("q_m", "position_rms"), ("q", "link_position_rms")):
        floor = float(np.sqrt(np.mean((getattr(log, col) - getattr(twin, col)) ** 2)))
        assert err[key] <= 1.1 * math.hypot(floor, own[key]), (col, err[key], floor, own[key])
    assert own["position_rel_pct"] < 0.2     # the model itself: the true axis
