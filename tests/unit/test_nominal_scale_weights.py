"""The block weights' scale test (identification.discrepancy.nominal.scale_shrunk) on a
stacked design of the two-mass form, pure numerics: a motor equation tau = K d + Jm qm'' and
a homogeneous link equation 0 = -K d + JL q'' whose measured acceleration is noisy.

With noise alone, weights of 1 / (each block's residual spread) keep K within its standard
error (here they even take out the errors-in-variables bias of the equal-weight fit), and the
test keeps them. With an unmodelled motor torque (a stand-in for a lag's or a ripple's
misfit) the motor residual's spread grows, the link rows get tens of times the weight, and
the weighted fit buys link residual by shrinking the whole link block: K near half its value,
which the test refuses."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.identification.discrepancy.nominal import scale_shrunk, solve

K, JM, JL = 2.0, 0.5, 0.1
N_ROWS = 4000


def _design(seed: int, misfit: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Wb (K, Jm, JL, the motor constant), y, block and the block weights 1 / spread."""
    rng = np.random.default_rng(seed)
    t = np.arange(N_ROWS) * 0.01
    d = np.sin(2 * np.pi * 0.7 * t) + 0.5 * np.sin(2 * np.pi * 1.9 * t + 1)
    qmdd = np.cos(2 * np.pi * 0.3 * t) + rng.normal(0, 0.3, N_ROWS)
    qdd = K * d / JL + rng.normal(0, 1.0, N_ROWS)
    tau = K * d + JM * qmdd + rng.normal(0, 0.02, N_ROWS) + misfit * np.sin(2 * np.pi * 3.1 * t)
    zero = np.zeros(N_ROWS)
    Wb = np.column_stack([np.r_[d, -d], np.r_[qmdd, zero], np.r_[zero, qdd],
                          np.r_[np.ones(N_ROWS), zero]])
    y = np.r_[tau, zero]
    block = np.r_[np.zeros(N_ROWS, int), np.ones(N_ROWS, int)]
    X, _ = solve(Wb, y, np.ones(len(y)))
    w = np.ones(len(y))
    for b in (0, 1):
        rows = block == b
        w[rows] = 1.0 / np.sqrt(np.mean((y[rows] - Wb[rows] @ X) ** 2))
    return Wb, y, block, w


@pytest.mark.parametrize("seed", range(5))
def test_weights_on_noise_alone_keep_the_scale(seed):
    Wb, y, block, w = _design(seed, 0.0)
    assert not scale_shrunk(Wb, y, block, w, 0)
    # the weighted K is the truth's to a few standard errors of the noise on q''
    assert solve(Wb, y, w)[0][0] == pytest.approx(K, rel=0.01)


def test_noise_alone_is_refused_at_about_the_test_s_rate():
    """SCALE_ALPHA is 1e-3: over 100 noise-only draws, more than 2 refusals would have a
    chance under 2e-4 (binomial)."""
    assert sum(scale_shrunk(*_design(seed, 0.0), 0) for seed in range(100, 200)) <= 2


@pytest.mark.parametrize("seed", range(5))
def test_a_motor_misfit_that_shrinks_the_link_block_is_refused(seed):
    Wb, y, block, w = _design(seed, 2.0)
    assert w[-1] / w[0] > 10   # the link rows outweigh the motor rows
    K_eq, K_w = solve(Wb, y, np.ones(len(y)))[0][0], solve(Wb, y, w)[0][0]
    assert K_eq == pytest.approx(K, rel=0.01) and K_w < 0.6 * K
    assert scale_shrunk(Wb, y, block, w, 0)
