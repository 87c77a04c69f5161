"""Issue 17 on data that is not MuJoCo's: the independent simulator's clean logs (jointbench.
testing: five axis families, 350.87 Hz, 60 s, linear sweep, velocity feed-forward, default
sensors, no hidden effect) identified with the defaults: f1 measured, band and stencil from it,
instruments for the joint-motor model.

Bounds are the issue's: f1 within 2 %; joint-motor K, Jm, JL within 0.5 % and the truth within
3 corrected sigma; motor-only K and Jm within 3 %, JL within 8 %. Where a family misses them
today the case is a strict xfail with the measured value (benchmarks/indep_accuracy.py prints
the whole grid, feed-forward off and log sweeps included)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from jointbench.bench.present.identify import identify_json
from jointbench.identification import regressors
from jointbench.identification.filtering import decimate_parallel
from jointbench.identification.identify import identify
from jointbench.testing import FAMILIES, simulate

# measured 2026-12-01 (seed 1): what misses the bounds, and by how much
F1_OVER: dict[str, str] = {}   # the frequency response alone: heavy_link +11.3 %, soft +2.5 %,
# stiff_small +2.8 %; the identified model's f1 (reported) holds all within 1.5 %
# Joint-motor: with the Coulomb reversals placed inside the sample interval with the
# friction's kink, the held torque's steps and the motor's stick phases (identify.
# _place_reversals, identification/friction_state.py), K, Jm, JL are within 0.1 % of the truth
# with ideal sensors (no torque noise, no quantisation; test_joint_motor_without_noise below)
# on every family but soft (Jm +0.19 %, JL +0.16 %: the paper's eq. (22) chain, which its
# 4 Hz mode keeps), and stiff_small (f1 = 20 Hz at 17.5 samples a period) went from Jm +2.99
# to +0.38 %. What is left over 0.5 % at seed 1 is the closed-loop torque noise, within 1.2
# corrected sigma: heavy_link Jm -0.66 % (sigma 0.7 %), soft Jm +0.55 %, in the chooser's
# band (decimated cutoff 9.4 and 5.4 Hz; the sweep goes to 30 Hz). Over seeds 1-10 heavy_link's
# Jm was -0.10 +- 0.59 % (mean +- sd; corrected sigma 0.67 %), soft's +0.28 +- 0.51 % (sigma
# 0.46 %): the 0.5 % bound was under one sigma of a 60 s log in that band. Tried, not kept:
# prewhitening by an AR model of the residual (heavy_link sd 0.59 -> 0.50, soft 0.51 -> 0.55,
# seeds 1-10; without feed-forward in a wide band Jm off by up to 24 %), a coarser Welch
# resolution for the instruments, dropping motor rows near reversals (a 1 % velocity floor
# with the filter's span drops 88 % of them). What works is the band: identify now fits the
# joint-motor model in the chooser's band and in a wide one (the chooser's wn, the decimated
# cutoff at the excitation's top measured on the log, capped where the stencil or the
# zero-phase Butterworth distorts by 1 %) and keeps the more precise by its own corrected
# sigma unless the two disagree beyond 3 sigma (identification/band_choice.py). Seed 1:
# heavy_link wide (Nd 6), Jm -0.03 % (sigma 0.36 %); soft wide (Nd 9), K -0.26, Jm +0.01,
# JL -0.28 % (sigma 0.23, 0.19, 0.22 %). Over seeds 1-6, linear sweep (benchmarks/
# indep_accuracy.py --spread 1-6), heavy_link's Jm went from +0.09 +- 0.51 % (rms 0.48) to
# -0.02 +- 0.15 % (rms 0.14), K and JL rms 0.10 % in both; soft's Jm from +0.53 +- 0.43 %
# (rms 0.66) to +0.06 +- 0.11 % (rms 0.12), K rms 0.21 -> 0.25 %, JL 0.22 -> 0.27 %. Log
# sweep (--sweep log): soft takes the wide band, Jm rms 0.41 -> 0.33 %, K 0.13 -> 0.11, JL
# 0.13 -> 0.16; heavy_link keeps the chooser's on all six seeds. Without the Butterworth cap
# (the band up to the excitation's top, Nd 6 with soft's paper Butterworth at 28 Hz) soft's
# log sweeps came out Jm -0.49 +- 0.22 %, K -0.19, JL -0.26 % (a guess, not traced: the
# Coulomb columns, built from the filtered velocity, see the roll-off differently). Without
# feed-forward neither heavy_link's nor soft's link response shows a resonance; the motor
# response's does (first_mode._from_motor: 5.92 and 3.95 Hz), so the band is designed from it
# instead of the generic one: Jm +2.42 -> +3.02 and +4.06 -> +3.67 % at seed 1 (corrected
# sigma 2.1 and 1.6 %; not covered by the bounds here; tests/validation/test_indep_logsweep.py).
JOINT_MOTOR_OVER: dict[str, str] = {}
# the band rule's pick at seed 1 (measured; stiff_small's chooser band reaches the top already)
BAND_USED = {"wrist": "chooser", "heavy_link": "wide", "stiff_small": "chooser",
             "soft": "wide", "balanced": "wide"}
# motor-only: the link reconstructed from q_m (identification/link_fit.py) took heavy_link from
# K -15.9 / Jm -5.2 / JL -45.8 % to -0.02 / -0.08 / +0.01, stiff_small's Jm from +7.5 to +2.3 %
# (the joint-motor model's +3.0 % there is the same motor-side residue), soft's from +3.25 to
# +0.62 % (K +0.10, JL +0.15); wrist and balanced within 0.22 %
MOTOR_ONLY_OVER: dict[str, str] = {}


@pytest.fixture(scope="module")
def logs(indep_log):
    return {name: indep_log(fam, seed=1, duration=60.0, sweep="linear")
            for name, fam in FAMILIES.items()}


@pytest.fixture(scope="module")
def joint_motor(logs):
    """The joint-motor identification of each clean log with the defaults, made once for the
    mode and the parameter checks (read only)."""
    return {name: identify(log, "joint-motor") for name, log in logs.items()}


def _xfail(request, table, name):
    if name in table:
        request.applymarker(pytest.mark.xfail(strict=True, reason=table[name]))


@pytest.mark.parametrize("name", list(FAMILIES))
def test_first_mode_within_2_percent(logs, joint_motor, name, request):
    """The reported f1: the identified two-mass model's (measured: -1.50 to -0.04 %), with
    the frequency response's estimate, which designed the band, in its note."""
    _xfail(request, F1_OVER, name)
    log = logs[name]
    mode = joint_motor[name].first_mode
    assert mode.found and mode.method.startswith("identified two-mass model")
    assert "the frequency response gave" in mode.note
    assert abs(mode.f1_hz / log.truth()["f1_hz"] - 1) < 0.02, mode.f1_hz


@pytest.mark.parametrize("name", list(FAMILIES))
def test_joint_motor_with_defaults(logs, joint_motor, name, request):
    _xfail(request, JOINT_MOTOR_OVER, name)
    log = logs[name]
    result, truth = joint_motor[name], log.truth()
    assert result.ls.instrumental
    band = identify_json(result, truth, [], [])["band"]   # what `identify --json` says
    assert band["used"] == result.band.used == BAND_USED[name], band["reason"]
    assert band["max_rel_sigma_corrected_pct"] <= (
        band["alternative"] or {}).get("max_rel_sigma_corrected_pct", math.inf)
    for p in ("K", "Jm", "JL"):
        assert abs(result.physical[p] / truth[p] - 1) < 0.005, (p, result.physical[p])
        z = (result.physical[p] - truth[p]) / result.physical_sigma_corrected[p]
        assert abs(z) < 3, (p, z)


@pytest.mark.parametrize("name", list(FAMILIES))
def test_motor_only_with_defaults(logs, name, request):
    _xfail(request, MOTOR_ONLY_OVER, name)
    log = logs[name]
    result, truth = identify(log, "motor-only"), log.truth()
    for p, tol in (("K", 0.03), ("Jm", 0.03), ("JL", 0.08)):
        assert abs(result.physical[p] / truth[p] - 1) < tol, (p, result.physical[p])


@pytest.mark.parametrize("feedforward", [True, False], ids=["ff", "no-ff"])
def test_joint_motor_without_noise(indep_log, feedforward):
    """stiff_small (f1 = 20 Hz at 17.5 samples a period, motor Coulomb friction 1.6 % of the
    torque limit) with ideal sensors: no torque noise and no quantisation, so no statistical
    error is left and what remains is the method's own bias. The Coulomb columns with the
    reversals inside the sample interval, the held torque's steps and the motor's stick
    phases (identification/friction_state.py) hold K, Jm, JL within 0.1 % (measured: within
    0.05 %, with and without feed-forward); with the reversals placed linearly between
    samples they were Jm +2.79 % and +3.63 %."""
    log = indep_log(FAMILIES["stiff_small"], seed=1, duration=60.0, sweep="linear",
                    feedforward=feedforward, ideal_sensors=True)
    result, truth = identify(log, "joint-motor"), log.truth()
    for p in ("K", "Jm", "JL"):
        assert abs(result.physical[p] / truth[p] - 1) < 0.001, (p, result.physical[p])


def test_joint_motor_without_noise_or_feedforward_in_the_papers_band(indep_log):
    """soft (f1 = 4 Hz, within 20 % of the paper's 3.9 Hz, so the chooser gives the paper's
    band: wn 176 rad/s, Nd 26, eq. (22)'s 3 points) without feed-forward, ideal sensors: the
    motor sticks at most reversals (it creeps under 5 mrad/s 75 % of the time). The 3-point
    chain's Coulomb column was sign(v), every reversal slip-through, while the 5-point one
    had the stick phases (identification/friction_state.py): Jm -3.33 % (FVm +24 %), -10.2 %
    at Nd 15, where the simulator's own friction state as the column gives +0.13 % (3 points)
    and +0.000 % (5 points). With the stick phases in both chains: K -0.02, Jm -0.07, JL
    +0.29 % (measured 2026-12-01); the issue's 0.5 %."""
    log = indep_log(FAMILIES["soft"], seed=1, duration=60.0, sweep="linear",
                    feedforward=False, ideal_sensors=True)
    result, truth = identify(log, "joint-motor"), log.truth()
    assert (result.settings.Nd, result.settings.stencil) == (26, 3)
    for p in ("K", "Jm", "JL"):
        assert abs(result.physical[p] / truth[p] - 1) < 0.005, (p, result.physical[p])


@pytest.mark.xfail(strict=True, reason="ideal sensors, no feed-forward: heavy_link Jm -0.25 %")
def test_joint_motor_without_noise_sticking_motor():
    """heavy_link without feed-forward, ideal sensors: the motor sticks at most reversals
    and no statistical error is left, so what remains is the method's own bias where the
    friction holds the drive for many samples. Measured 2026-12-01: Jm -0.25 % in the wide
    band (Nd 6, 5 points; FVm +24 %); soft -0.07 % in the paper's band. Traced (issue 17,
    session 8): with the simulator's own friction state (its FSm tanh(v / v_s) integrated
    alongside the plant) as the column, Jm -0.004 %; with friction_state's Karnopp model fed
    the true sample velocities and the true drive, -0.39 %: the model, not its inputs. The
    simulator's Coulomb friction is smoothed over v_s = 1 mrad/s and the motor creeps under
    5 v_s 65 % of the time, where the true state is tanh(v / v_s), 0.19 rms away from the
    balance drive / rate that a stick model gives; the same axis simulated with v_s = 0.1
    mrad/s comes out within 0.02 % (K -0.000, Jm -0.011, JL -0.001 %, FVm +0.2 %). A
    measured log does not say its friction law near zero speed; not fixed. Strict: a fix
    must take this case out."""
    log = simulate(FAMILIES["heavy_link"], seed=1, duration=60.0, sweep="linear",
                   feedforward=False, ideal_sensors=True)
    result, truth = identify(log, "joint-motor"), log.truth()
    for p in ("K", "Jm", "JL"):
        assert abs(result.physical[p] / truth[p] - 1) < 0.001, (p, result.physical[p])


def test_settings_without_a_mode_identify_as_the_defaults(indep_log):
    """`identify(log, settings=...)` without f1 (campaign --wn/--decimate/--stencil,
    tune-filter, the API) still measures the first mode on the log for the instruments: with
    the chooser's own settings it must give the defaults' answer. stiff_small, log sweep
    (the chooser's band is already the widest, so the band rule keeps it): before, the
    instruments took 8 s Welch segments without f1 and Jm came out -41 % against +0.52 %,
    without a warning."""
    from jointbench.identification.filter_choice import choose_filter
    log = indep_log(FAMILIES["stiff_small"], seed=1, duration=60.0, sweep="log")
    default = identify(log, "joint-motor")
    given = identify(log, "joint-motor", settings=choose_filter(log).settings)
    assert given.first_mode.found
    for p in ("K", "Jm", "JL"):
        assert given.physical[p] == pytest.approx(default.physical[p], rel=1e-9), p


def _motor_equation_crb(log, settings, truth: dict, noise_std: float) -> float:
    """The Cramer-Rao bound of Jm [same unit] from the motor equation alone in the band of
    `settings`: white torque noise of `noise_std` on the plant, through the torque's chain
    (ZOH alignment, Butterworth, decimation: its variance measured on an independent white
    draw), against the motor rows of eq. (13) built with the true parameters, sigma^2
    (W' W)^-1 with Jm, FVm, FSm and K free (the link equation, which pins K / JL, is left
    out, so a joint fit may do slightly better)."""
    reg = regressors.joint_motor(log, settings, truth)
    motor = reg.block == 0
    W = reg.W[motor][:, [reg.names.index(n) for n in ("Jm", "FVm", "FSm", "K")]]
    w = np.random.default_rng(12345).normal(0.0, noise_std, len(log.t))
    e = regressors._torque(replace(log, tau_m=w), settings)
    var = float(np.var(decimate_parallel(e, np.zeros((len(e), 1)), settings)[0]))
    return math.sqrt(var * np.linalg.inv(W.T @ W)[0, 0])


def test_jm_sigma_without_feedforward_is_the_log_s_information(indep_log):
    """soft without feed-forward (linear sweep, default sensors, seed 1): Jm's corrected
    sigma (1.55 %) is what the log holds, not a failing of the fit: the Cramer-Rao bound of
    the motor equation in the band used is 1.70 % (the wide band's 1.52 %: the excitation
    above the chooser's band adds 10-13 % of information without feed-forward). Over seeds
    1-10 (2026-12-01) Jm was -0.11 +- 1.72 % (mean corrected sigma 1.64 %, bound 1.77 %),
    heavy_link seeds 1-5 +1.17 +- 2.95 % (2.31 %, bound 2.45 %): the issue's 0.5 % is under a
    third of one sigma of a 60 s log, so it is checked against the sigma instead: the truth
    within 3 corrected sigma, and the sigma within 25 % of the bound."""
    log = indep_log(FAMILIES["soft"], seed=1, duration=60.0, sweep="linear", feedforward=False)
    result, truth = identify(log, "joint-motor"), log.truth()
    for p in ("K", "Jm", "JL"):
        z = (result.physical[p] - truth[p]) / result.physical_sigma_corrected[p]
        assert abs(z) < 3, (p, z)
    crb = _motor_equation_crb(log, result.settings, truth, FAMILIES["soft"].torque_noise_std)
    ratio = result.physical_sigma_corrected["Jm"] / crb
    assert 0.75 < ratio < 1.25, (result.physical_sigma_corrected["Jm"], crb)
