"""Unit tests of identification/estimate.py: least squares with the paper's statistics
(section 3.1) and the rank check, on synthetic W with known X (no MuJoCo)."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.identification.estimate import NotIdentifiable, block_weighted, least_squares

NAMES = ("a", "b", "c")
X_TRUE = np.array([2.0, -0.5, 30.0])


def _design(r: int = 300, seed: int = 0) -> np.ndarray:
    """A well-conditioned W whose columns differ in scale by 1e3 (as inertia, friction and
    stiffness columns do)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 10, r)
    return np.column_stack([np.sin(1.3 * t) + 0.1 * rng.standard_normal(r),
                            100.0 * np.cos(0.7 * t), 0.1 * rng.standard_normal(r)])


def test_exact_data_gives_x_and_zero_residual():
    W = _design()
    ls = least_squares(W, W @ X_TRUE, NAMES)
    # Noiseless, well-conditioned (cond ~ 10 after column scaling): rounding only.
    np.testing.assert_allclose(ls.X, X_TRUE, rtol=1e-10)
    assert ls.rms < 1e-10 and ls.unidentifiable == () and ls.r == len(W)
    assert ls.value("c") == pytest.approx(30.0)


def test_paper_sigma_matches_the_monte_carlo_spread():
    W = _design()
    noise = 0.2
    rng = np.random.default_rng(1)
    draws, sigmas, sigma2 = [], [], []
    for _ in range(200):
        y = W @ X_TRUE + noise * rng.standard_normal(len(W))
        ls = least_squares(W, y, NAMES, corrected=False)
        draws.append(ls.X)
        sigmas.append(ls.sigma)
        sigma2.append(ls.sigma2)
    draws = np.array(draws)
    spread = draws.std(axis=0, ddof=1)
    # The standard deviation of 200 draws is itself uncertain by 1/sqrt(2 x 199) = 5 %: 20 %
    # is four of those, so the test fails only if sigma = sqrt(sigma^2 diag (W^T W)^-1) is
    # wrong, not by chance.
    np.testing.assert_allclose(np.mean(sigmas, axis=0), spread, rtol=0.2)
    # sigma^2 = ||rho||^2 / (r - Np) is unbiased for the noise variance; its mean over 200
    # draws of r - Np = 297 degrees of freedom is within 0.6 % (1 sd), so 5 % is safe.
    assert np.mean(sigma2) == pytest.approx(noise ** 2, rel=0.05)
    # Unbiased estimate: the mean is within 4 standard errors of the truth.
    assert np.all(np.abs(draws.mean(axis=0) - X_TRUE) < 4 * spread / np.sqrt(200))


def test_relative_sigma_is_percent_of_the_estimate():
    W = _design()
    y = W @ X_TRUE + 0.2 * np.random.default_rng(2).standard_normal(len(W))
    ls = least_squares(W, y, NAMES, corrected=False)
    np.testing.assert_allclose(ls.rel_sigma_pct, 100 * ls.sigma / np.abs(ls.X))
    assert ls.std("b") == pytest.approx(float(ls.sigma[1]))


def test_corrected_covariance_agrees_with_the_paper_on_white_noise():
    W = _design()
    y = W @ X_TRUE + 0.2 * np.random.default_rng(3).standard_normal(len(W))
    ls = least_squares(W, y, NAMES)
    assert ls.cov_corrected is not None and ls.cov_corrected.shape == (3, 3)
    # With white residuals of one variance both covariances estimate the same thing; the
    # sandwich's own sampling spread on 300 rows is ~10 %, so 30 % is a safe bound.
    np.testing.assert_allclose(ls.sigma_corrected, ls.sigma, rtol=0.3)
    assert ls.std_corrected("a") == pytest.approx(float(ls.sigma_corrected[0]))


def test_without_correction_there_is_no_corrected_sigma():
    W = _design()
    ls = least_squares(W, W @ X_TRUE + 1e-3, NAMES, corrected=False)
    assert ls.cov_corrected is None and ls.hac is None
    assert np.isnan(ls.sigma_corrected).all()


def test_collinear_columns_drop_one_parameter_and_name_the_other():
    W = _design()
    W = np.column_stack([W, 3.0 * W[:, 0]])   # d duplicates a: only a + 3 d is identifiable
    names = NAMES + ("d",)
    ls = least_squares(W, W[:, :3] @ X_TRUE, names, corrected=False)
    assert len(ls.unidentifiable) == 1
    dropped = ls.unidentifiable[0]
    assert dropped in ("a", "d")
    other = "d" if dropped == "a" else "a"
    assert other in ls.reasons[dropped] and "combination" in ls.reasons[dropped]
    assert np.isnan(ls.value(dropped)) and np.isnan(ls.std(dropped))
    # The kept parameters carry the identifiable combination: a + 3 d = 2.
    kept_a = ls.value("a") if other == "a" else 3.0 * ls.value("d")
    assert kept_a == pytest.approx(2.0, rel=1e-9)
    assert ls.value("b") == pytest.approx(-0.5, rel=1e-9)
    assert ls.value("c") == pytest.approx(30.0, rel=1e-9)


def test_a_zero_column_is_reported_unexcited():
    W = _design()
    W[:, 1] = 0.0
    ls = least_squares(W, W @ X_TRUE, NAMES, corrected=False)
    assert ls.unidentifiable == ("b",)
    assert "zero" in ls.reasons["b"]
    assert ls.value("a") == pytest.approx(2.0) and ls.value("c") == pytest.approx(30.0)


def test_nothing_excited_raises_not_identifiable():
    with pytest.raises(NotIdentifiable, match="no parameter"):
        least_squares(np.zeros((50, 3)), np.ones(50), NAMES)


def test_too_few_rows_raise_not_identifiable():
    W = _design(r=3)
    with pytest.raises(NotIdentifiable, match="too few samples"):
        least_squares(W, W @ X_TRUE, NAMES)


def test_shape_mismatch_raises_value_error():
    W = _design()
    with pytest.raises(ValueError, match="names"):
        least_squares(W, W @ X_TRUE, NAMES[:2])
    with pytest.raises(ValueError):
        least_squares(W, np.ones(len(W) - 1), NAMES)


def test_block_weighted_trusts_the_precise_block_more():
    # Two equation blocks observed with noise 100 times apart (torque vs encoder residuals).
    W = _design(r=400)
    rng = np.random.default_rng(4)
    block = np.r_[np.zeros(200, int), np.ones(200, int)]
    y = W @ X_TRUE + np.where(block == 0, 1.0, 0.01) * rng.standard_normal(400)
    plain = least_squares(W, y, NAMES, corrected=False)
    ls = block_weighted(W, y, NAMES, block)
    # Weighting each block by 1 / its residual rms leans on the precise block: every
    # standard deviation shrinks (by about 10 here; 3 leaves room for the one-step weights).
    assert np.all(ls.sigma < plain.sigma / 3)
    # The estimate is within 4 of its own sigma of the truth (a 6e-5 chance per parameter).
    assert np.all(np.abs(ls.X - X_TRUE) < 4 * ls.sigma)
    # Residuals are returned unweighted: each block keeps its own scale.
    r0 = np.sqrt(np.mean(ls.residual[block == 0] ** 2))
    r1 = np.sqrt(np.mean(ls.residual[block == 1] ** 2))
    assert r0 == pytest.approx(1.0, rel=0.2) and r1 < 0.1 * r0
