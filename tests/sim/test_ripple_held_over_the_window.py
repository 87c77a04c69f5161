"""A ripple's columns as the aligned torque holds them (torque_ripple.design, held): the
mean of sin(2 pi qm / p) over the window the aligned torque averages, and a torque lag's lead
by the 3-point difference of the pointwise samples (stacked.led_extra). On a light wrist the
motor turns the default ripple period (2 pi / 600 rad) in 5.6 samples at its median speed
and past half a period a sample at its fastest: the pointwise sample keeps its size where the
torque holds a ripple shrunk as sinc, and the fitted amplitude falls short of the truth. The
truth is the hidden ripple's amplitude, fitted beside the hidden lag with both at their true
nonlinear values."""

from __future__ import annotations

import math

import numpy as np
import pytest

import jointbench.testing.simulator as indep
from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.identification.discrepancy.nominal import nominal
from jointbench.identification.discrepancy.stacked import stacked

pytestmark = pytest.mark.slow

AMPLITUDE = 0.6
LAG_S = 0.003


@pytest.fixture(scope="module")
def nom():
    family = indep.FAMILIES["wrist"]
    log = indep.simulate(family, 5, 30.0, feedforward=True,
                         effects=f"torque_ripple={AMPLITUDE},torque_lag={LAG_S}")
    return nominal(log, diagnosis_settings(log)[0]), 2 * math.pi / (6 * family.gear_ratio)


def test_a_fast_ripple_is_fitted_at_its_amplitude_beside_a_lag(nom):
    nom, period = nom
    sig = nom.sig
    phase_step = 2 * math.pi * sig.ts * np.nanmedian(np.abs(sig.qmd)) / period
    assert phase_step > 1.0   # the ripple is fast: over a radian a sample at the median speed
    s = stacked(nom, [("torque_lag", {"lag_s": LAG_S}),
                      ("torque_ripple", {"ripple_period_rad": period})])
    y, W, names = s.design()
    theta, *_ = np.linalg.lstsq(W, y, rcond=None)
    r = y - W @ theta
    dof = len(y) - W.shape[1]
    cov = (r @ r / dof) * np.linalg.inv(W.T @ W)
    i, j = names.index("As"), names.index("Ac")
    amplitude = math.hypot(theta[i], theta[j])
    # the amplitude's standard error (the larger of the two columns'), 3 of them: fitted
    # on the held columns it lies within one; on the pointwise columns 8 % short, 6 of them
    se = math.sqrt(max(cov[i, i], cov[j, j]))
    assert abs(amplitude - AMPLITUDE) < 3 * se
