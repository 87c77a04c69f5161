"""Issue 17 on the independent simulator's logarithmic sweeps (jointbench.testing, 60 s, seed 1,
350.87 Hz, default sensors), identified with the defaults.

The log sweep spends a fifth of its time above the first mode (heavy_link: 15 s of 60 above
6 Hz, against 48 s for the linear sweep), where the motor inertia is seen; the torque noise
(1.25 % of tau_max) then leaves Jm a corrected sigma of 0.5-0.8 % with feed-forward and 1.3-2 %
without. Switched off one at a time (measured 2026-12-01, seed 1), only the torque
noise moves heavy_link's Jm (-1.71 % with it, -0.10 % without; quantisation, the measured
against the true f1, the chooser's against the wide band, the Welch segment of the
instruments and perfect instruments from a noise-free replay all within 0.35 % of -1.7 %).
Over seeds 1-16 its Jm is -0.38 % on average (sd 0.96 %, corrected sigma 0.71 %; -0.10 %
noise-free, so a bias of -0.28 +- 0.24 %, not significant): the 0.5 % bound is under one
sigma of such a log, and seed 1 is a 1.4-sd draw. So the tests below check
what the log supports: K and JL within 0.5 %, the truth within 3 corrected sigma, and Jm's
sigma under 1 %; Jm within 0.5 % is a strict xfail with the measured value."""

from __future__ import annotations

import pytest

from jointbench.identification.first_mode import measure_first_mode
from jointbench.identification.identify import identify
from jointbench.testing import FAMILIES, simulate

FEEDFORWARD = ("heavy_link", "stiff_small")   # the log sweeps with feed-forward over 0.5 % (Jm)
# measured at seed 1 (corrected sigma): heavy_link -1.71 % (0.74), stiff_small +0.52 % (0.56);
# seeds 2, 3: -0.81, -1.84 and +0.85, -0.51
JM_OVER = {"heavy_link": "Jm -1.71 % (corrected sigma 0.74 %)",
           "stiff_small": "Jm +0.52 % (corrected sigma 0.56 %)"}


@pytest.fixture(scope="module")
def ff_logs(indep_log):
    return {name: indep_log(FAMILIES[name], seed=1, duration=60.0, sweep="log")
            for name in FEEDFORWARD}


@pytest.fixture(scope="module")
def ff_fits(ff_logs):
    return {name: identify(log, "joint-motor") for name, log in ff_logs.items()}


@pytest.fixture(scope="module")
def soft_without_ff():
    return simulate(FAMILIES["soft"], seed=1, duration=60.0, sweep="log", feedforward=False)


@pytest.mark.parametrize("name", FEEDFORWARD)
def test_log_sweep_joint_motor_within_its_sigma(ff_logs, ff_fits, name):
    """K and JL within the issue's 0.5 % (measured: within 0.13 %), the truth within 3
    corrected sigma, and the log's precision on Jm under 1 % (0.74, 0.56 %)."""
    result, truth = ff_fits[name], ff_logs[name].truth()
    assert result.ls.instrumental and result.first_mode.found
    for p in ("K", "Jm", "JL"):
        err = result.physical[p] / truth[p] - 1
        z = (result.physical[p] - truth[p]) / result.physical_sigma_corrected[p]
        assert abs(z) < 3, (p, err, z)
        if p != "Jm":
            assert abs(err) < 0.005, (p, err)
    assert result.physical_sigma_corrected["Jm"] / truth["Jm"] < 0.01


@pytest.mark.parametrize("name", FEEDFORWARD)
def test_log_sweep_joint_motor_jm_within_half_a_percent(ff_logs, ff_fits, name, request):
    """The issue's 0.5 % on Jm: under one corrected sigma of these logs (module docstring)."""
    if name in JM_OVER:
        request.applymarker(pytest.mark.xfail(strict=True, reason=JM_OVER[name]))
    truth = ff_logs[name].truth()
    err = ff_fits[name].physical["Jm"] / truth["Jm"] - 1
    assert abs(err) < 0.005, err


def test_first_mode_from_the_motor_response_when_the_link_shows_none(soft_without_ff):
    """soft without feed-forward: the link response's peak is 1.7 times its median level (a
    resonance needs 2), the motor response's antiresonance dip still shows the mode: f1 is
    measured (3.986 Hz, truth 4.0), where it was "no resonance found" and the generic band."""
    log = soft_without_ff
    mode = measure_first_mode(log)
    assert mode.found and "the link response shows no resonance" in mode.method
    assert mode.method.startswith("motor q_m/tau_m")
    assert "the link response q/tau_m: no resonance stands out" in mode.note
    assert abs(mode.f1_hz / log.truth()["f1_hz"] - 1) < 0.02, mode.f1_hz


def test_motor_only_without_ff_on_a_log_sweep(soft_without_ff):
    """The motor-only model on soft's log sweep without feed-forward: it failed ("the link
    needs a > 0, ...": the generic band's eqs. 18-20 gave no start the link replays); with
    the band from the measured f1 (Nd 26) the issue's bounds hold: K, Jm within 3 %, JL within
    8 % (measured: K -0.37, Jm -2.08, JL -0.33 %; seeds 2, 3: -0.81, -2.85, -0.58 and +0.28,
    -1.04, +0.29)."""
    log = soft_without_ff
    result, truth = identify(log, "motor-only"), log.truth()
    assert result.first_mode.found
    for p, tol in (("K", 0.03), ("Jm", 0.03), ("JL", 0.08)):
        assert abs(result.physical[p] / truth[p] - 1) < tol, (p, result.physical[p])
