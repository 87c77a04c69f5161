"""The motor-only model with the link reconstructed from q_m (identification/link_sim.py,
identification/link_fit.py), on the independent simulator (jointbench.testing) where the truth
is known. Tolerances are a few times what was measured (2026-12-01, in each docstring)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import signal

from jointbench.identification import link_fit
from jointbench.identification.filter_choice import choose_filter
from jointbench.identification.filtering import decimate, decimate_parallel
from jointbench.identification.identify import identify
from jointbench.bench.sim.experiment import run_experiment
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.link_sim import inverse, link_response, simulate_link, spectra
from jointbench.testing import FAMILIES, frictionless, simulate

TS = 1 / 350.87


def link_params(log):
    """(a, b, c, gx, gy) of link_sim from a log's truth."""
    tr, g = log.truth(), log.gravity
    JL = tr["JL"]
    return tr["K"] / JL, tr["FV"] / JL, tr["FS"] / JL, g * tr["MX"] / JL, g * tr["MY"] / JL


def pct(value, truth):
    return 100 * (value / truth - 1)


def test_link_response_is_the_two_pole_filter():
    """H = 1 / (s^2 + b s + a) applied by FFT against scipy's lsim on a 20x finer grid, from
    rest (measured: 2.5e-4 of the output's rms), and its static gain 1 / a."""
    t = np.arange(0, 20, TS)
    u = np.sin(2 * np.pi * (0.2 * t + 0.2 * t ** 2)) * np.clip(t / 2, 0, 1) ** 2
    a, b = (2 * np.pi * 3) ** 2, 0.5
    y = link_response(u, a, b, TS)
    fine = np.arange(0, 20, TS / 20)
    _, yf, _ = signal.lsim(([1.0], [1.0, b, a]), np.interp(fine, t, u), fine)
    assert np.std(y - yf[::20][:len(y)]) < 1e-3 * np.std(y)
    assert link_response(np.full(100, 2.0), a, b, TS) == pytest.approx(np.full(100, 2.0 / a))


def test_the_link_sticks_while_the_spring_cannot_move_it():
    """A motor swing whose spring force a |qm| stays under the friction c: the link stays at
    rest, and the friction is the spring's force (|phi| <= 1) averaged over each step (its
    value at the step's end led the motor by half a sample: on an axis whose link sticks 75 %
    of the time, the truth was no fixed point of the fit, K -1.4 % from it, now +0.07 %)."""
    t = np.arange(0, 5, TS)
    a, c = 400.0, 2.0
    qm = 0.9 * c / a * np.sin(2 * np.pi * t)
    q, phi = simulate_link(qm, TS, a, 0.5, c)
    assert np.all(q == 0.0)
    assert np.abs(phi).max() <= 1.0
    assert phi[:-1] == pytest.approx(a * (qm[1:] + qm[:-1]) / 2 / c)


@pytest.mark.parametrize("family", [FAMILIES["heavy_link"], replace(FAMILIES["balanced"], MY=0.3)],
                         ids=["heavy_link", "balanced_with_gravity"])
def test_simulated_link_follows_the_independent_plant(family, indep_log):
    """The link driven by the logged q_m with the true parameters against the plant's own q
    (smoothed Coulomb, RK4): measured 0.07 % (heavy link, stick-slip) and 0.11 % (gravity) of
    the deflection's rms."""
    log = indep_log(family, 1, 20.0, "linear", True, ideal_sensors=True)
    q, _ = simulate_link(log.q_m, log.ts, *link_params(log))
    assert np.std(q - log.q) < 3e-3 * np.std(log.q_m - log.q)


def test_motor_only_exact_without_coulomb_friction():
    """Viscous frictions only, ideal sensors: the structure is exact (measured: K, Jm, JL
    within 1e-4 %); the eqs. (18)-(20) start is refined to the truth."""
    family = replace(frictionless(FAMILIES["heavy_link"]), FVm=0.75, FV=6.0)
    log = simulate(family, 1, 20.0, "linear", True, ideal_sensors=True)
    result, truth = identify(log, "motor-only"), log.truth()
    for name in ("K", "Jm", "JL", "FV"):
        assert abs(pct(result.physical[name], truth[name])) < 0.01, name
    assert any("link reconstructed from q_m" in n for n in result.notes)
    assert result.physical_eqs18_20["K"] > 0     # the start, kept for comparison


def test_gravity_kept_when_identified_left_out_otherwise(indep_log):
    """An axis with a link mass keeps MX, MY (measured: MY -1.0 %, K -0.03 %); a horizontal
    one leaves them out with a note, reported as 0 with the standard deviation the data gave
    them (measured on the heavy link: K +0.14 %, Jm +1.3 %)."""
    heavy = indep_log(FAMILIES["heavy_link"], 1, 20.0, "linear", True, ideal_sensors=True)
    flat = identify(heavy, "motor-only")
    assert flat.physical["MY"] == 0.0 and any("left out" in n for n in flat.notes)
    assert flat.physical_sigma_corrected["MY"] > 0
    tilted = indep_log(replace(FAMILIES["balanced"], MY=0.3), 1, 20.0, "linear", True,
                       ideal_sensors=True)
    result, truth = identify(tilted, "motor-only"), tilted.truth()
    assert abs(pct(result.physical["MY"], truth["MY"])) < 5
    for name, log, res in (("K", heavy, flat), ("JL", heavy, flat), ("K", tilted, result),
                           ("Jm", tilted, result), ("JL", tilted, result)):
        assert abs(pct(res.physical[name], log.truth()[name])) < 1, (name, res.physical[name])


def test_start_from_the_band_alone(indep_log):
    """Without the eqs. (18)-(20) start (their inversion fails on some logs without velocity
    feed-forward), the antiresonance scan starts within 25 % (measured: 3-9 %) and the fit
    ends where the usual start does (measured: K -0.03 %)."""
    log = indep_log(replace(FAMILIES["balanced"], MY=0.3), 1, 20.0, "linear", True,
                    ideal_sensors=True)
    truth = log.truth()
    s = choose_filter(log).settings
    start = link_fit.start_from_band(log, s)
    for name in ("K", "Jm", "JL"):
        assert abs(pct(start[name], truth[name])) < 25, (name, start[name])
    result = link_fit.fit(log, s, start, truth["f1_hz"])
    for name in ("K", "Jm", "JL"):
        assert abs(pct(result.physical[name], truth[name])) < 1, (name, result.physical[name])
    assert result.sigma_corrected["K"] > 0


def test_start_needs_a_stiffness():
    log = simulate(FAMILIES["balanced"], 1, 10.0, "linear", True, ideal_sensors=True)
    with pytest.raises(ValueError, match="positive K and JL"):
        link_fit.fit(log, choose_filter(log).settings, {"K": -1.0, "JL": 1.0})


def _rows_at_the_truth(log):
    """The link fit's parameters at the log's truth and its rows (`_Rows`) in the chooser's
    band."""
    truth, s = log.truth(), choose_filter(log).settings
    a, b = link_params(log)[:2]
    p = {"Jm": truth["Jm"], "FVm": truth["FVm"], "FSm": truth["FSm"], "K": truth["K"],
         "Kc": a * truth["FS"], "Kgx": a * truth["MX"], "Kgy": a * truth["MY"], "a": a, "b": b}
    return p, link_fit._Rows(log, s)


def test_jacobian_columns_are_the_model_derivatives():
    """The Jacobian's dm/da and dm/db (`_Rows.design`: the responses' sums decimated once)
    against central differences of the decimated model m = (LINEAR columns) X in a and b, the
    profiles held (step 1e-5 relative; measured: 4e-8 of the column for a, 3e-9 for b, the
    difference's truncation near the link's resonance; a missing term is of order 1)."""
    log = simulate(replace(FAMILIES["balanced"], MY=0.3), 1, 10.0, "linear", True,
                   ideal_sensors=True)
    p, rows = _rows_at_the_truth(log)
    rows.profiles(p)
    _, J, _ = rows.design(p)
    for col, name in ((link_fit.LINEAR, "a"), (link_fit.LINEAR + 1, "b")):
        h = 1e-5 * p[name]
        up, down = ({**p, name: p[name] + d} for d in (h, -h))
        fd = (link_fit._model(rows.linear(up)[1], p)
              - link_fit._model(rows.linear(down)[1], p)) / (2 * h)
        assert np.linalg.norm(J[:, col] - fd) < 1e-6 * np.linalg.norm(fd), name


def test_rows_are_those_of_decimate_parallel():
    """`_Rows.linear` keeps the rows filtering.decimate_parallel keeps, with the torque and the
    motor columns (qm'', qm', sign) decimated as it does (equal), and the link's responses
    H u_i decimated in the frequency domain (`_Rows._responses`): the same anti-alias filter
    applied to the response continued as the link's own past the record's ends (at rest
    before its first sample, the free response after its last one). Against
    filtering.decimate of that continued response (50 decimated rows each side, longer than
    the filter's transient; measured: 3e-8 of the column's largest value, the response's
    tail folded onto its start by the FFT and the stopband's bins left out)."""
    log = simulate(replace(FAMILIES["balanced"], MY=0.3), 1, 10.0, "linear", True)
    p, rows = _rows_at_the_truth(log)
    a, b, s = p["a"], p["b"], rows.s
    rows.profiles(p)
    y, L, idx = rows.linear(p)
    qm2, qm1 = np.nan_to_num(rows.qm[2]), np.nan_to_num(rows.qm[1])   # 0 at the ends
    inputs = (qm2 + b * qm1, rows.phi, rows.cos, rows.sin)
    W = np.column_stack([rows.qm[2], rows.qm[1], rows.sign]
                        + [link_response(u, a, b, s.ts) for u in inputs])
    W[rows.bad] = np.nan
    y0, W0, idx0 = decimate_parallel(rows.tau, W, s)
    assert np.array_equal(idx, idx0) and np.array_equal(y, y0)
    np.testing.assert_array_equal(L[:, :3], W0[:, :3])
    n, extra = len(log.t), 50 * s.Nd
    continued = []
    for u in inputs:
        sb, U, u0 = spectra([u], s.ts)
        response = inverse(U / (sb * sb + b * sb + a), sb, 2 * (len(sb) - 1))[0]
        continued.append(np.r_[np.zeros(extra), response[:n + extra]] + u0[0] / a)
    X = decimate(np.column_stack(continued)[rows.first:], s.Nd, axis=0)
    Xd = X[(idx - rows.first + extra) // s.Nd]
    np.testing.assert_allclose(L[:, 3:], Xd, rtol=0, atol=1e-6 * np.abs(Xd).max())
    # decimate_parallel's odd extension of each response differs from the continued one
    # within the filter's transient of the ends alone
    inside = slice(5, -40)
    np.testing.assert_allclose(L[inside, 3:], W0[inside, 3:], rtol=0,
                               atol=1e-4 * np.abs(W0[:, 3:]).max())
