"""Unit tests of bench/sim/controller.py: the discrete PI law of docs/controller.md,

    w[k]     = (q_m[k] - q_m[k-1]) / T
    v_ref[k] = kp (q_ref[k] - q_m[k]) + ff (q_ref[k] - q_ref[k-1]) / T
    e[k]     = v_ref[k] - w[k]
    I[k]     = I[k-1] + ki T e[k]
    tau_m[k] = clip(kv e[k] + I[k], -tau_max, tau_max)

with q_m[-1] = q_m[0], q_ref[-1] = q_ref[0], I[-1] = tau_m[0]; and the stability of the
default gain rule on the shipped models (the controller module's docstring cites this file).

Hand-computed sequences are exact in real arithmetic; 1e-12 allows for float rounding on
values of order 10.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.sim.controller import Gains, PIController, control_law, gains_rule
from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ
from jointbench.identification.log import Log, LogError
from jointbench.models import load_model

T = 0.01
GAINS = Gains(kp=2.0, kv=10.0, ki=100.0, tau_max=1000.0)
Q_M = [0.0, 0.001, 0.003]
Q_REF = [0.01, 0.012, 0.015]
TAU0 = 5.0
# By hand, with kp = 2, kv = 10, ki T = 1, I[-1] = 5:
#  k=0: w = 0,   v_ref = 2(0.01)  + 0          = 0.02,  e = 0.02,   I = 5.02,  tau = 5.22
#  k=1: w = 0.1, v_ref = 2(0.011) + 0.002/0.01 = 0.222, e = 0.122,  I = 5.142, tau = 6.362
#  k=2: w = 0.2, v_ref = 2(0.012) + 0.003/0.01 = 0.324, e = 0.124,  I = 5.266, tau = 6.506
TAU_FF = [5.22, 6.362, 6.506]
# Without the velocity feedforward (ff = 0):
#  k=0: e = 0.02,   I = 5.02,  tau = 5.22
#  k=1: e = -0.078, I = 4.942, tau = -0.78 + 4.942 = 4.162
#  k=2: e = -0.176, I = 4.766, tau = -1.76 + 4.766 = 3.006
TAU_NO_FF = [5.22, 4.162, 3.006]


def _run(gains: Gains, q_m=Q_M, q_ref=Q_REF, tau0=TAU0) -> tuple[list[float], PIController]:
    ctrl = PIController(gains, T, tau0)
    return [ctrl.step(a, b) for a, b in zip(q_m, q_ref)], ctrl


def test_three_ticks_by_hand():
    taus, ctrl = _run(GAINS)
    np.testing.assert_allclose(taus, TAU_FF, rtol=0, atol=1e-12)
    assert ctrl.saturated == 0


def test_three_ticks_without_velocity_feedforward():
    gains = Gains(kp=2.0, kv=10.0, ki=100.0, tau_max=1000.0, velocity_feedforward=False)
    taus, _ = _run(gains)
    np.testing.assert_allclose(taus, TAU_NO_FF, rtol=0, atol=1e-12)


def test_control_law_is_the_stepped_controller():
    taus = control_law(np.array(Q_M), np.array(Q_REF), GAINS, T, TAU0)
    np.testing.assert_allclose(taus, TAU_FF, rtol=0, atol=1e-12)


def test_the_integrator_starts_at_the_logged_torque():
    # At rest on the reference (e = 0 throughout): tau_m[k] = I[-1] = tau_m[0] for all k,
    # the static load the experiment starts from.
    taus, _ = _run(GAINS, q_m=[0.2] * 5, q_ref=[0.2] * 5, tau0=-37.5)
    assert taus == [-37.5] * 5
    taus, _ = _run(GAINS, q_m=[0.2] * 3, q_ref=[0.2] * 3, tau0=0.0)
    assert taus == [0.0] * 3


def test_first_sample_has_no_velocity_and_no_feedforward():
    # q_m[-1] = q_m[0], q_ref[-1] = q_ref[0]: a large first sample is not a velocity.
    taus, _ = _run(GAINS, q_m=[100.0], q_ref=[100.0], tau0=1.0)
    assert taus == [1.0]


def test_saturation_clips_at_tau_max_and_counts():
    gains = Gains(kp=2.0, kv=10.0, ki=100.0, tau_max=6.0)
    taus, ctrl = _run(gains)
    np.testing.assert_allclose(taus, [5.22, 6.0, 6.0], rtol=0, atol=1e-12)
    assert ctrl.saturated == 2
    # Symmetric: the mirrored sequence clips at -tau_max.
    taus, ctrl = _run(gains, q_m=[-x for x in Q_M], q_ref=[-x for x in Q_REF], tau0=-TAU0)
    np.testing.assert_allclose(taus, [-5.22, -6.0, -6.0], rtol=0, atol=1e-12)
    assert ctrl.saturated == 2


def test_the_integrator_runs_on_through_saturation():
    # The law has no anti-windup: I[k] follows e[k] while tau is clipped. A fourth tick with
    # e = 0 (q_m still, q_ref where kp (q_ref - q_m) + (q_ref - q_ref[2]) / T = 0) returns
    # kv 0 + I[2] = 5.266, the unclipped integrator of the hand computation.
    gains = Gains(kp=2.0, kv=10.0, ki=100.0, tau_max=6.0)
    q_ref3 = (gains.kp * Q_M[2] + Q_REF[2] / T) / (gains.kp + 1 / T)
    taus, ctrl = _run(gains, q_m=Q_M + [Q_M[2]], q_ref=Q_REF + [q_ref3])
    assert taus[3] == pytest.approx(5.266, abs=1e-12)
    assert ctrl.saturated == 2


def test_gains_round_trip_through_log_metadata():
    gains = Gains(kp=40.0, kv=2500.0, ki=25000.0, tau_max=3000.0, velocity_feedforward=False)
    log = Log(t=np.arange(3) * T, q_m=np.zeros(3), tau_m=np.zeros(3), meta=gains.to_meta())
    assert Gains.from_log(log) == gains
    meta = dict(gains.to_meta())
    del meta["velocity_feedforward"]        # CONTRACT: default true
    log = Log(t=np.arange(3) * T, q_m=np.zeros(3), tau_m=np.zeros(3), meta=meta)
    assert Gains.from_log(log).velocity_feedforward is True


def test_gains_from_log_name_what_is_missing():
    log = Log(t=np.arange(3) * T, q_m=np.zeros(3), tau_m=np.zeros(3),
              meta={"kp": "40", "kv": "2500"})
    with pytest.raises(LogError, match="ki, tau_max"):
        Gains.from_log(log)


def _closed_loop(Jm: float, JL: float, K: float, FVm: float, FV: float, gains: Gains,
                 T: float) -> tuple[np.ndarray, np.ndarray]:
    """Transition matrix F of the two-mass axis (eqs. 5-6, no Coulomb friction, no gravity)
    under the section 2 law with q_ref = 0, state z = (qm, qm', q, q', q_m[k-1], I[k-1]),
    and the row c with tau_m[k] = c z[k]; the plant is discretised exactly for the
    zero-order-hold torque."""
    A = np.array([[0, 1, 0, 0], [-K / Jm, -FVm / Jm, K / Jm, 0],
                  [0, 0, 0, 1], [K / JL, 0, -K / JL, -FV / JL]])
    B = np.array([0, 1 / Jm, 0, 0])
    M = np.zeros((5, 5))
    M[:4, :4], M[:4, 4] = A * T, B * T
    E = expm(M)
    Ad, Bd = E[:4, :4], E[:4, 4]
    kiT = gains.ki * T
    e = np.zeros(6)                       # e[k] = -kp qm - (qm - q_m[k-1]) / T
    e[0], e[4] = -gains.kp - 1 / T, 1 / T
    tau = (gains.kv + kiT) * e            # tau[k] = kv e + I[k-1] + ki T e
    tau[5] += 1.0
    F = np.zeros((6, 6))
    F[:4, :4] = Ad
    F[:4] += np.outer(Bd, tau)
    F[4, 0] = 1.0
    F[5] = kiT * e
    F[5, 5] += 1.0
    return F, tau


def test_closed_loop_matrix_is_the_stepped_controller():
    # The matrix used for the stability check below encodes the law: stepping it and
    # stepping PIController on the same plant give the same torques.
    p = {"Jm": 1.6, "JL": 0.52, "K": 5500.0, "FVm": 1.5, "FV": 0.4}
    gains = gains_rule(p["Jm"], p["JL"], p["K"], 1e9, T)
    F, c = _closed_loop(**p, gains=gains, T=T)
    z = np.array([0.01, 0.0, 0.01, 0.0, 0.01, 0.0])   # at rest off the reference, I[-1] = 0
    ctrl = PIController(gains, T, tau0=0.0)
    for _ in range(20):
        assert c @ z == pytest.approx(ctrl.step(z[0], 0.0), rel=1e-12, abs=1e-12)
        z = F @ z


def _shipped_axes():
    for name in ("prototype", "arm6"):
        _, axes, _ = load_model(name)
        for axis in axes:
            yield name, axis.name


@pytest.mark.parametrize("model, joint", list(_shipped_axes()))
def test_the_gain_rule_is_stable_on_the_shipped_axes(model, joint):
    exp = build_experiment_model(model, joint)
    t = exp.truth
    T_exp = 1.0 / SAMPLE_RATE_HZ
    gains = gains_rule(t.Jm, t.JL, t.K, exp.tau_max, T_exp)
    # Without the axes' damping (the worst case for the lightly damped joint mode): every
    # closed-loop eigenvalue strictly inside the unit circle. The measured spectral radius
    # is 0.96-0.993; the bound leaves no room for a marginal loop.
    F, _ = _closed_loop(t.Jm, t.JL, t.K, 0.0, 0.0, gains, T_exp)
    assert np.max(np.abs(np.linalg.eigvals(F))) < 0.999
