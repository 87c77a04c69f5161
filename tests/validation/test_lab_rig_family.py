"""The lab-rig family of the independent simulator (tests/indep_sim.py `simulate_lab_rig`: a
voltage drive whose back-EMF damps the motor side heavily, 4096-count encoders on the servo
angle and the spring deflection, a 1 V/rad P loop, a random-phase multisine, 500 Hz,
horizontal) identified with the defaults: the first mode comes from q / q_m where the peak
responses fail, and K, Jm, JL land within 1 % of the truth and within 3 sigma of it.

The seed was fixed before the first run of this file; each case is one run, as a lab has."""

from __future__ import annotations


import pytest

from jointbench.testing.simulator import LAB_RIG, simulate_lab_rig

import jointbench as jb
from jointbench.identification.first_mode import measure_first_mode

SEED = 32
CASES = [(20.0, True), (40.0, True), (80.0, True), (20.0, False)]   # (duration [s], closed loop)


@pytest.mark.parametrize("duration,closed", CASES)
def test_lab_rig_identifies_with_defaults(duration, closed):
    log = simulate_lab_rig(seed=SEED, duration=duration, closed_loop=closed)
    fit = jb.identify(log)
    assert fit.model == "joint-motor"
    for key in ("K", "Jm", "JL"):
        truth = float(log.meta[f"truth_{key}"])
        est = fit.parameters[key]
        assert abs(est.value / truth - 1) < 0.01, (key, est.value, truth)
        # sigma_hac: the residuals' autocorrelation counted (the white-residual sigma
        # understates it on a sweep); 3 of it holds the truth
        assert abs(est.value - truth) < 3 * est.sigma_hac, (key, est.value, truth, est.sigma_hac)


def test_lab_rig_first_mode_says_which_response_decided():
    log = simulate_lab_rig(seed=SEED, duration=40.0)
    mode = measure_first_mode(log)
    assert mode.found
    f1 = LAB_RIG.family.f1_hz
    assert abs(mode.f1_hz - f1) < max(3 * mode.sigma_hz, 0.02 * f1), (mode.f1_hz, f1)
    assert mode.method.startswith(("link q/tau_m", "motor q_m/tau_m", "link over motor q/q_m"))
    if mode.method.startswith("link over motor"):
        assert "decided:" in mode.method and "sqrt(K/JL)" in mode.note
