"""The position loops of docs/controller.md section 3 (P, PD, PI, PID on q_m or q), checked
against the law computed by hand, and read back from a log's metadata."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.sim.controller import (Gains, PIController, PositionController,
                                             PositionGains, control_law, controller_from_log,
                                             describe, has_controller)
from jointbench.identification.log import Log, LogError

T = 0.002
Q_M = [0.0, 0.01, 0.03, 0.02]
Q = [0.0, 0.005, 0.02, 0.025]
R = [0.1, 0.2, 0.2, 0.15]


def _hand(kind: str, kp: float, ki: float, kd: float, y: list[float], ff: bool,
          tau0: float) -> list[float]:
    """docs/controller.md section 3, written out."""
    out, y_prev, r_prev = [], y[0], R[0]
    I = tau0 - kp * (R[0] - y[0]) if ki else 0.0
    for yk, rk in zip(y, R):
        e = rk - yk
        I += ki * T * e
        d = kd * ((rk - r_prev if ff else 0.0) - (yk - y_prev)) / T
        out.append(kp * e + I + d)
        y_prev, r_prev = yk, rk
    return out


@pytest.mark.parametrize("kind,ki,kd", [("P", 0, 0), ("PD", 0, 0.3), ("PI", 5.0, 0),
                                        ("PID", 5.0, 0.3)])
@pytest.mark.parametrize("feedback", ["q_m", "q"])
@pytest.mark.parametrize("ff", [False, True])
def test_position_loop_is_the_documented_law(kind, ki, kd, feedback, ff):
    g = PositionGains(kind, kp=2.0, ki=ki, kd=kd, tau_max=100.0, feedback=feedback,
                      velocity_feedforward=ff)
    y = Q_M if feedback == "q_m" else Q
    got = control_law(np.array(Q_M), np.array(R), g, T, 0.7, q=np.array(Q))
    assert got == pytest.approx(_hand(kind, 2.0, ki, kd, y, ff, 0.7), rel=1e-12, abs=1e-15)


def test_position_loop_with_integrator_starts_at_the_logged_torque():
    g = PositionGains("PI", kp=2.0, ki=5.0, tau_max=100.0)
    assert PositionController(g, T, 0.7).step(0.0, 0.1) == pytest.approx(0.7 + 5.0 * T * 0.1)


def test_position_loop_clips_and_counts():
    ctrl = PositionController(PositionGains("P", kp=10.0, tau_max=0.5), T)
    assert ctrl.step(0.0, 1.0) == 0.5 and ctrl.step(0.0, -1.0) == -0.5
    assert ctrl.saturated == 2


def test_a_gain_the_kind_does_not_name_is_refused():
    with pytest.raises(ValueError, match="a P loop has no kd"):
        PositionGains("P", kp=1.0, kd=0.1, tau_max=1.0)
    with pytest.raises(ValueError, match="controller kind"):
        PositionGains("PIDF", kp=1.0, tau_max=1.0)


def _log(meta: dict[str, str]) -> Log:
    t = np.arange(4) * T
    return Log(t=t, q_m=np.array(Q_M), tau_m=np.zeros(4), q=np.array(Q), q_ref=np.array(R),
               meta={"sample_rate_hz": "500", **meta})


@pytest.mark.parametrize("gains", [
    PositionGains("P", kp=0.128, tau_max=1.28),
    PositionGains("PD", kp=3.0, kd=0.2, tau_max=10.0, feedback="q", velocity_feedforward=True),
    PositionGains("PID", kp=3.0, ki=30.0, kd=0.2, tau_max=10.0),
    Gains(kp=2.0, kv=10.0, ki=100.0, tau_max=1000.0, velocity_feedforward=False),
])
def test_metadata_round_trip(gains):
    log = _log(gains.to_meta())
    assert controller_from_log(log) == gains
    assert has_controller(log)
    assert describe(gains)


def test_cascade_is_the_default_and_its_step_ignores_the_link():
    g = Gains(kp=2.0, kv=10.0, ki=100.0, tau_max=1000.0)
    assert controller_from_log(_log(g.to_meta())) == g
    a, b = PIController(g, T, 5.0), PIController(g, T, 5.0)
    assert a.step(0.01, 0.1) == b.step(0.01, 0.1, 123.0)


def test_incomplete_position_loop_metadata_is_named():
    log = _log({"controller": "PD", "pid_kp": "1", "tau_max": "2"})
    with pytest.raises(LogError, match="PD loop lacks pid_kd"):
        controller_from_log(log)
    assert not has_controller(log)
    with pytest.raises(LogError, match="'controller'"):
        controller_from_log(_log({"controller": "bang-bang"}))
    with pytest.raises(LogError, match="'feedback'"):
        controller_from_log(_log({"controller": "P", "pid_kp": "1", "tau_max": "2",
                                  "feedback": "q_ref"}))


def test_transfer_function_from_python_control_is_the_pi_loop():
    """C(z) = (kp + ki T - kp z^-1) / (1 - z^-1) is the PI loop of section 3.1, written as
    python-control's discrete transfer function."""
    control = pytest.importorskip("control")
    from jointbench.bench.sim.controller import TransferGains

    kp, ki = 2.0, 5.0
    sys_ = control.tf([kp + ki * T, -kp], [1.0, -1.0], T)
    tf = TransferGains.from_control(sys_, tau_max=100.0)
    pi = PositionGains("PI", kp=kp, ki=ki, tau_max=100.0)
    got = control_law(np.array(Q_M), np.array(R), tf, T, 0.7)
    want = control_law(np.array(Q_M), np.array(R), pi, T, 0.7)
    assert got == pytest.approx(want, rel=1e-12, abs=1e-15)
    log = _log(tf.to_meta())
    assert controller_from_log(log) == tf and has_controller(log)


def test_transfer_function_metadata_errors_are_named():
    with pytest.raises(LogError, match="lacks tf_den"):
        controller_from_log(_log({"controller": "TF", "tf_num": "1 2", "tau_max": "3"}))
    with pytest.raises(LogError, match="'tf_num': not a list"):
        controller_from_log(_log({"controller": "TF", "tf_num": "1 x", "tf_den": "1",
                                  "tau_max": "3"}))
    with pytest.raises(LogError, match="first coefficient"):
        controller_from_log(_log({"controller": "TF", "tf_num": "1", "tf_den": "0 1",
                                  "tau_max": "3"}))
