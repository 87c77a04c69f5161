"""The log's own noise as the Coulomb state sees it (identification/coulomb_noise.py), against
synthetic plants whose noise is known."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.identification.filtering import FilterSettings, derivatives, lowpass
from jointbench.identification.coulomb_noise import chain_jitter, noise_nodes, torque_noise_sweep

TS = 1 / 350.87


def _inertia(n: int, J: float, sigma: float, seed: int = 1) -> tuple[np.ndarray, ...]:
    """A pure inertia under a held torque (a slow sine plus a constant that keeps it moving one
    way) and white torque noise held over each interval: samples of (q, v, tau)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * TS
    tau = 0.5 * J * np.sin(2 * np.pi * 0.7 * t)
    acc = (tau + rng.normal(0.0, sigma, n)) / J
    v = 1.0 + np.concatenate([[0.0], np.cumsum(acc[:-1] * TS)])
    q = np.concatenate([[0.0], np.cumsum(v[:-1] * TS + acc[:-1] * TS ** 2 / 2)])
    return q, v, tau


def test_torque_noise_sweep_recovers_the_noise_and_ignores_a_smooth_model_error():
    J, sigma, n = 2.0, 0.3, 20000
    q, v, tau = _inertia(n, J, sigma)
    truth = sigma * TS / J
    p = {"Jm": J, "K": 0.0, "FVm": 0.0, "FSm": 0.0}
    got = torque_noise_sweep(v, q, tau, np.zeros(n), p, TS)
    assert got == pytest.approx(truth, rel=0.03)   # robust sd of 20 000 differences: ~1 %
    # a wrong parameter leaves a smooth error in the motor equation (here 40 % of the
    # noise's sd): the difference of consecutive residuals drops it
    wrong = dict(p, K=0.12 * sigma / np.std(q - q.mean()))
    assert torque_noise_sweep(v, q, tau, q - q.mean(), wrong, TS) == pytest.approx(truth,
                                                                                     rel=0.03)
    # the quantiser's share is taken out: a rounding error uniform in +-res/2, independent
    # from sample to sample (the noise dithers a real encoder; here 57 % of the variance)
    res = 5e-7
    qq = q + np.random.default_rng(2).uniform(-res / 2, res / 2, n)
    assert torque_noise_sweep(v, qq, tau, np.zeros(n), p, TS) > 1.2 * truth
    assert torque_noise_sweep(v, qq, tau, np.zeros(n), p, TS, res) == pytest.approx(truth,
                                                                                      rel=0.05)
    assert torque_noise_sweep(v, q, tau, np.zeros(n), {}, TS) == 0.0   # no Jm: no estimate


def test_chain_jitter_is_the_chains_miss_of_a_noise_driven_velocity():
    # Monte Carlo: the velocity a white noise drives, seen by the chain (Butterworth + stencil
    # of the positions), misses u - v with the sd and correlation chain_jitter predicts
    n, sigma = 60000, 1.0
    rng = np.random.default_rng(3)
    for s in (FilterSettings(wn=300.0, m=4, Nd=5, ts=TS, stencil=5),
              FilterSettings(wn=176.0, m=4, Nd=26, ts=TS, stencil=3)):
        a = rng.normal(0.0, sigma, n)
        u = np.concatenate([[0.0], np.cumsum(a[:-1] * TS)])
        q = np.concatenate([[0.0], np.cumsum(u[:-1] * TS + a[:-1] * TS ** 2 / 2)])
        v = derivatives(lowpass(q, s.wn, s.ts, s.m), s.ts, 1, s.stencil)[1]
        mid = slice(2000, n - 2000)
        miss = (u - v)[mid]
        g, rho = chain_jitter(s)
        assert np.std(miss) == pytest.approx(g * sigma * TS, rel=0.03)
        assert np.corrcoef(miss, a[mid])[0, 1] == pytest.approx(rho, abs=0.02)


def test_noise_nodes_have_the_pairs_moments():
    s = FilterSettings(wn=300.0, m=4, Nd=5, ts=TS, stencil=5)
    sweep = 2e-3
    nodes = noise_nodes(sweep, s)
    g, rho = chain_jitter(s)
    w = nodes.w
    assert w.sum() == pytest.approx(1.0)
    assert np.sum(w * nodes.dv) == pytest.approx(0.0, abs=1e-15)
    assert np.sqrt(np.sum(w * nodes.dv ** 2)) == pytest.approx(g * sweep)
    assert np.sqrt(np.sum(w * nodes.da ** 2)) == pytest.approx(sweep / TS)
    cov = np.sum(w * nodes.dv * nodes.da) / (g * sweep * sweep / TS)
    assert cov == pytest.approx(rho)
    assert noise_nodes(0.0, s) is None
