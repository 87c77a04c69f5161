"""The Coulomb friction the motor feels under the log's own noise.

The closed loop's torque noise is not logged. Held over a sample interval it changes the
motor's velocity by n T / Jm within the interval, and the velocity at the interval's start
carries the earlier intervals' share that the chain's low-pass does not pass. Near a reversal
(or a stick) those decide which way, and whether, the friction acts: the friction the motor
feels is, on average, its state taken over that noise, a smoothed sign, and a column built
from the chain's velocity alone hands the difference, odd in v, to FVm (arm6 axis5, 240 s:
FVm +5.6 to +8.4 %; the independent simulator's heavy_link without feed-forward: FVm +262 %,
FSm -10.6 %).

Everything comes from the log, no width tuned:
- `torque_noise_sweep`: the noise's sd as the velocity change it makes in an interval, from
  the residual of the motor's equation between consecutive intervals (the previous pass's
  parameters), its quantiser share removed;
- `chain_jitter`: how much of that noise the chain's velocity misses at an interval's start,
  and how that miss correlates with the interval's own noise (the zero-phase chain sees part
  of it ahead), from the chain's filter and stencil alone;
- `noise_nodes`: Gauss-Hermite nodes of the pair (start-velocity miss, interval noise).
These hold for any plant. The regressors do not use them: averaging the motor's stick-slip
state (`friction_state`) over the nodes moved arm6's Jm by under 0.01 % and biased the
independent simulator's stiff axis (docs/design-notes.md, "Simulator-free estimator").

Pure numpy.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from jointbench.identification.filtering import FilterSettings, seen_velocity

GH_NODES = 3               # Gauss-Hermite nodes a noise dimension (exact for degree <= 5)
JITTER_TAIL = 4.0          # |v| / spread within which an interval counts as near a reversal
JITTER_PASSES = 3          # passes narrowing the samples to the reversals' neighbourhood
JITTER_MIN_SAMPLES = 200   # fewest intervals the residual's spread is taken from
CHAIN_SPAN = 512           # samples of the chain's response to one interval's noise
_GH_X, _GH_W = np.polynomial.hermite_e.hermegauss(GH_NODES)
_GH_W = _GH_W / _GH_W.sum()


def _spread(x: np.ndarray) -> float:
    """Robust standard deviation, 1.4826 times the median absolute deviation."""
    return 1.4826 * float(np.median(np.abs(x - np.median(x)))) if len(x) else 0.0


def _near(e: np.ndarray, vm: np.ndarray) -> np.ndarray:
    """The intervals near the reversals: |v| under JITTER_TAIL times the spread of the
    interval velocities e about the chain's there, found from the whole log's in a few passes."""
    near = np.ones(len(e), dtype=bool)
    for i in range(JITTER_PASSES):
        wider = np.abs(vm) < JITTER_TAIL * _spread(e[near])
        if i and wider.sum() < JITTER_MIN_SAMPLES:   # too few to narrow further
            break
        near = wider
    return near


def torque_noise_sweep(v: np.ndarray, raw: np.ndarray, tau: np.ndarray, defl: np.ndarray,
                       p: Mapping[str, float], ts: float, resolution: float = 0.0) -> float:
    """The sd [rad/s] of the velocity change n T / Jm that the unlogged torque noise n makes
    within a sample interval, from the motor's equation with the parameters p (Jm, FVm, FSm, K
    of eq. 13; 0 when Jm is missing), for the chain's velocity v and deflection defl at the
    samples, the raw motor positions and the logged (held) torque. With the acceleration a_k
    constant on interval k, the interval means r = diff(raw) / T satisfy r[k+1] - r[k] =
    (a_k + a_k+1) T / 2, so z_k = n_k + n_k+1 = 2 Jm (r[k+1] - r[k]) / T - (tau_k + tau_k+1)
    + FVm (v_k + v_k+1) + FSm (sign_k + sign_k+1) + K (defl_k + defl_k+1), taken away from
    the reversals (where sign is not the friction's state). The model's own error in z (a
    continuous plant's acceleration is not constant on an interval; the chain's deflection)
    is smooth: z_k+1 - z_k = n_k+2 - n_k keeps the white noise, variance 2 sd(n)^2, and drops
    most of it; the quantiser's share
    (2 Jm / T^2)^2 20 resolution^2 / 12 is removed."""
    Jm = p.get("Jm", 0.0)
    if not Jm > 0:
        return 0.0
    v, raw = np.asarray(v, dtype=float), np.asarray(raw, dtype=float)
    vm = 0.5 * (v[:-1] + v[1:])
    r = np.diff(raw) / ts
    e = r - vm
    ok = np.isfinite(e)
    tau, defl = np.asarray(tau, dtype=float), np.asarray(defl, dtype=float)
    both = ok[:-1] & ok[1:] & np.isfinite(defl[:-2]) & np.isfinite(defl[1:-1])
    far = both & ~_near(np.where(ok, e, 0.0), np.where(ok, vm, 0.0))[:-1]
    far &= np.sign(vm[:-1]) == np.sign(vm[1:])
    z = (2 * Jm * np.diff(r) / ts - (tau[:-2] + tau[1:-1])
         + p.get("FVm", 0.0) * (vm[:-1] + vm[1:]) + p.get("FSm", 0.0) * 2 * np.sign(vm[:-1])
         + p.get("K", 0.0) * (defl[:-2] + defl[1:-1]))
    dz = np.diff(z)[far[:-1] & far[1:]]
    if len(dz) < JITTER_MIN_SAMPLES:
        return 0.0
    quant2 = (2 * Jm / ts ** 2) ** 2 * 20.0 * resolution ** 2 / 12.0
    noise2 = max(0.0, _spread(dz) ** 2 - quant2) / 2.0
    return float(np.sqrt(noise2)) * ts / Jm


def chain_jitter(s: FilterSettings) -> tuple[float, float]:
    """(g, rho): the sd of the start velocity the chain misses, u_k - v_k, is g times the
    sweep, and rho its correlation with interval k's own noise. One interval's unit noise
    acceleration steps the velocity by T from the next sample on; the chain (`s`: Butterworth,
    stencil) sees that step smoothed, ahead and behind; the miss of independent intervals adds
    up, sum_k err_k^2 (a velocity driven by white noise, the loop's slower correction passed by
    the chain). Arm6's chain: g 0.31, rho -0.69."""
    ts, j = s.ts, CHAIN_SPAN // 2
    k = np.arange(CHAIN_SPAN)
    u = np.where(k > j, ts, 0.0)
    q = np.where(k > j, ts * ts / 2 + (k - j - 1) * ts * ts, 0.0)
    v = seen_velocity(q, s)
    err = (u - v)[CHAIN_SPAN // 8: -CHAIN_SPAN // 8]
    norm = float(np.sqrt(np.sum(err ** 2)))
    if not norm > 0:
        return 0.0, 0.0
    return norm / ts, float((u - v)[j]) / norm


@dataclass(frozen=True)
class NoiseNodes:
    """Nodes of the expectation over the noise: start-velocity miss dv [rad/s], drive noise
    da [rad/s^2] held over the interval, weights w summing to 1."""

    dv: np.ndarray
    da: np.ndarray
    w: np.ndarray


def noise_nodes(sweep: float, s: FilterSettings) -> NoiseNodes | None:
    """The pair (u_k - v_k, n_k / Jm) as a correlated Gaussian (`chain_jitter`) over
    GH_NODES^2 product nodes, for the sweep [rad/s] of `torque_noise_sweep`; None without noise."""
    if not sweep > 0:
        return None
    g, rho = chain_jitter(s)
    x1, x2 = np.meshgrid(_GH_X, _GH_X, indexing="ij")
    w = np.outer(_GH_W, _GH_W)
    dv = g * sweep * (rho * x1 + np.sqrt(max(0.0, 1.0 - rho * rho)) * x2)
    return NoiseNodes(dv.ravel(), (x1 * sweep / s.ts).ravel(), w.ravel())
