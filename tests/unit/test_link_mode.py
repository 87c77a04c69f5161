"""identification.link_mode on exact two-mass responses (eqs. 5-6 with viscous frictions):
the link mode, the link damping and the inertias come back to rounding."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointbench.identification.link_mode import inertia_ratio, link_over_motor

Jm, JL, K, FVm, FV = 0.002, 0.0035, 1.6, 0.073, 0.0015
FS = 500.0
f = np.linspace(0.1, 12.0, 120)
s = 2j * np.pi * f


def _q_over_qm():
    return K / (JL * s ** 2 + FV * s + K)


def _q_over_tau():
    """eq. (6) with q_m = q (JL s^2 + FV s + K) / K, the torque half a sample late (ZOH)."""
    qm_over_q = (JL * s ** 2 + FV * s + K) / K
    tau_over_q = (Jm * s ** 2 + FVm * s) * qm_over_q + JL * s ** 2 + FV * s
    return np.exp(-s / (2 * FS)) / tau_over_q


def test_link_over_motor_recovers_wa_and_b():
    wa2, b = link_over_motor(f, _q_over_qm(), np.ones_like(f), top_hz=11.0)
    assert wa2 == pytest.approx(K / JL, rel=1e-9)
    assert b == pytest.approx(FV / JL, rel=1e-6)


def test_inertia_ratio_gives_the_locked_mode():
    jm, fvm, jl = inertia_ratio(f, _q_over_tau(), np.ones_like(f), K / JL, FV / JL, 11.0, FS)
    assert (jm, fvm, jl) == pytest.approx((Jm, FVm, JL), rel=1e-6)
    f1 = math.sqrt(K / JL * (1 + jl / jm)) / (2 * math.pi)
    assert f1 == pytest.approx(math.sqrt(K * (1 / Jm + 1 / JL)) / (2 * math.pi), rel=1e-6)


def test_no_peak_no_mode():
    flat = np.ones_like(f, dtype=complex)
    assert link_over_motor(f, flat, np.ones_like(f), top_hz=11.0) is None
    assert link_over_motor(f, _q_over_qm(), np.zeros_like(f), top_hz=11.0) is None
