"""bench.analysis.diagnose.stability: the closed-loop matrix is the stepped PI cascade on the
plant with its lag, and the phase crossover is where the loop's response is real and
negative."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.stability import (LimitCycle, band_hz, closed_loop,
                                                          crossover_hz, dominant_mode,
                                                          over_spread, plant)
from jointbench.bench.sim.controller import Gains, PIController, gains_rule

T = 1.0 / 350.87
P = {"Jm": 0.5, "FVm": 0.75, "K": 646.0, "JL": 5.0, "FV": 6.0}


@pytest.mark.parametrize("lag", [0.0, 2e-3])
def test_the_matrix_is_the_stepped_controller_on_the_lagged_plant(lag):
    gains = gains_rule(P["Jm"], P["JL"], P["K"], 1e9, T)
    F = closed_loop(P, gains.kp, gains.kv, gains.ki, T, lag)
    Ad, Bd = plant(P, T, lag)
    n = len(Bd)
    z = np.zeros(n + 2)
    z[0] = z[2] = z[n] = 0.01     # at rest off the reference (q_m[-1] = q_m[0]), I[-1] = 0
    x = z[:n].copy()
    ctrl = PIController(Gains(gains.kp, gains.kv, gains.ki, 1e9, False), T, tau0=0.0)
    for _ in range(50):
        tau = ctrl.step(x[0], 0.0)
        x = Ad @ x + Bd * tau
        z = F @ z
        assert z[:n] == pytest.approx(x, rel=1e-9, abs=1e-12)


def test_a_lag_past_the_onset_makes_the_loop_grow():
    gains = gains_rule(P["Jm"], P["JL"], P["K"], 1e9, T)
    r0, _ = dominant_mode(closed_loop(P, gains.kp, gains.kv, gains.ki, T), T)
    r1, f1 = dominant_mode(closed_loop(P, gains.kp, gains.kv, gains.ki, T, 3e-3), T)
    assert r0 < 1 < r1 and 0 < f1 < 0.5 / T
    fc = crossover_hz(P, gains.kp, gains.kv, gains.ki, T, 3e-3)
    # at the crossover the loop's response is real, negative and over 1 in size
    Ad, Bd = plant(P, T, 3e-3)
    zz = np.exp(2j * math.pi * fc * T)
    G = np.linalg.solve(zz * np.eye(len(Bd)) - Ad, Bd)[0]
    L = (gains.kv + gains.ki * T * zz / (zz - 1)) * (gains.kp + (zz - 1) / (zz * T)) * G
    assert abs(L.imag) < 1e-3 * abs(L) and L.real < -1


def test_a_spring_damping_damps_the_locked_mode_as_eq_5_6_say():
    """D (q_m' - q') in parallel with K: without the frictions the locked mode of the plant
    decays at sigma = D (1/Jm + 1/JL) / 2 per second, its frequency sqrt(K (1/Jm + 1/JL) -
    sigma^2); the held plant's pole is exp((-sigma + i w) ts) exactly."""
    D = 3.0
    p = {"Jm": P["Jm"], "K": P["K"], "JL": P["JL"], "D": D}
    Ad, _ = plant(p, T)
    inv_j = 1 / P["Jm"] + 1 / P["JL"]
    sigma = D * inv_j / 2
    w = math.sqrt(P["K"] * inv_j - sigma ** 2)
    ev = np.linalg.eigvals(Ad)
    mode = ev[np.argmax(np.abs(ev.imag))]
    assert abs(mode) == pytest.approx(math.exp(-sigma * T), rel=1e-9)
    assert abs(np.angle(mode)) == pytest.approx(w * T, rel=1e-9)


def test_the_band_over_the_fitted_values_spread_holds_the_true_loops_cycle():
    """A lag fitted a tenth long (3.46 ms against 3.19 ms, the spring damping 1.0 against
    1.2) moves the grown loop's mode and crossover down by over the 1 Hz resolution of a 40 s
    log's spectrum (40 segments): a log cycling at the true loop's mode lies outside the
    point estimate's mode and crossover. Over the fitted values' spread, when it covers the
    truth, the band holds the true loop's two frequencies and the cycle is confirmed; with no
    spread it is not (the point estimate taken as exact)."""
    gains = gains_rule(P["Jm"], P["JL"], P["K"], 1e9, T)
    true = {**P, "D": 1.2, "lag_s": 3.19e-3}
    fitted = {**P, "D": 1.0, "lag_s": 3.46e-3}
    spread = {"lag_s": 0.3e-3, "D": 0.3}
    F = closed_loop(true, gains.kp, gains.kv, gains.ki, T, true["lag_s"])
    r_true, f_true = dominant_mode(F, T)
    c_true = crossover_hz(true, gains.kp, gains.kv, gains.ki, T, true["lag_s"])
    lo, hi = band_hz(fitted, gains.kp, gains.kv, gains.ki, T, spread)
    assert lo <= min(f_true, c_true) and max(f_true, c_true) <= hi
    r_fit, f_fit = dominant_mode(closed_loop(fitted, gains.kp, gains.kv, gains.ki, T,
                                             fitted["lag_s"]), T)
    c_fit = crossover_hz(fitted, gains.kp, gains.kv, gains.ki, T, fitted["lag_s"])
    cycle = dict(nominal_radius=0.99, extended_radius=r_fit, lag_s=fitted["lag_s"],
                 mode_hz=f_fit, crossover_hz=c_fit, cycle_hz=f_true, resolution_hz=1.0)
    assert r_true > 1 and f_true > max(f_fit, c_fit) + 1.0
    assert not LimitCycle(**cycle).confirms
    assert LimitCycle(**cycle, band_hz=(lo, hi)).confirms


def test_a_lag_fitted_short_of_the_onset_grows_over_its_spread_at_the_logs_cycle():
    """Near the onset the loop's growth turns on a few percent of the fitted values: a lag
    fitted 13 % short (2.26 ms against 2.6) with the motor inertia 4 % heavy and its viscous
    friction high (as on a clipped log, where both are fitted mostly at the cycle) leaves the
    point estimate's loop decaying, while the true loop grows. Over the lag's spread (its
    half-width of 3 standard errors holding the truth) the loop grows, and the band of the
    growing loops' mode and crossover holds the true loop's mode: the check confirms. A log
    cycling far from any growing loop's frequencies is not confirmed, though it lies between
    the decaying point estimate's low crossover and its mode; nor is a lag whose spread does
    not reach the onset."""
    gains = gains_rule(P["Jm"], P["JL"], P["K"], 1e9, T)
    k = (gains.kp, gains.kv, gains.ki, T)
    true = {**P, "lag_s": 2.6e-3}
    fitted = {**P, "Jm": 1.04 * P["Jm"], "FVm": 1.15, "lag_s": 2.26e-3}
    spread = {"lag_s": 0.88e-3}
    r_true, f_true = dominant_mode(closed_loop(true, *k[:3], T, true["lag_s"]), T)
    r_fit, f_fit = dominant_mode(closed_loop(fitted, *k[:3], T, fitted["lag_s"]), T)
    c_fit = crossover_hz(fitted, *k, fitted["lag_s"])
    assert r_true > 1 > r_fit
    largest, lo, hi = over_spread(fitted, *k, spread)
    assert largest > 1 and lo <= f_true <= hi
    point = dict(nominal_radius=0.998, extended_radius=r_fit, lag_s=fitted["lag_s"],
                 mode_hz=f_fit, crossover_hz=c_fit, resolution_hz=1.0)
    assert not LimitCycle(**point, cycle_hz=f_true).confirms
    assert LimitCycle(**point, cycle_hz=f_true, band_hz=(lo, hi),
                      spread_radius=largest).confirms
    # between the point estimate's low crossover and its mode, far from the growing loops'
    far = 0.5 * (lo + min(c_fit, f_fit))
    assert min(c_fit, f_fit) < far < lo - 1.0
    assert not LimitCycle(**point, cycle_hz=far, band_hz=(lo, hi),
                          spread_radius=largest).confirms
    short = {**fitted, "lag_s": 1.0e-3}
    largest, lo, hi = over_spread(short, *k, {"lag_s": 0.5e-3})
    assert largest < 1 and math.isnan(lo) and math.isnan(hi)
