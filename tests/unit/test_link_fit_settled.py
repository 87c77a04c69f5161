"""The convergence check of the link reconstruction's instrumental passes
(identification/link_fit.py, `_unsettled`): the last Gauss-Newton step and the one before it
against the estimate's own covariance, d^T C^-1 d, and the chi-square quantile IV_SETTLED."""

from __future__ import annotations

import numpy as np
from scipy import stats

from jointbench.identification.estimate import LSResult
from jointbench.identification.link_fit import IV_SETTLED, NAMES, _unsettled

N = len(NAMES)
S = np.linspace(0.5, 4.0, N)          # standard deviations, C = diag(S^2)
BOUND = stats.chi2.ppf(IV_SETTLED, N)
EDGE = np.sqrt(BOUND / N)             # a step of EDGE S in every parameter: d^T C^-1 d = BOUND


def _result(X: np.ndarray, C: np.ndarray) -> LSResult:
    return LSResult(NAMES, X, np.sqrt(np.diag(C)), C, 1.0, np.zeros(3), 3, 1.0, (), {},
                    cov_corrected=C)


def _point(x: np.ndarray) -> dict[str, float]:
    return {n: float(v) for n, v in zip(NAMES, x)}


def _check(last: float, prev: float):
    """Steps of `last` and `prev` times EDGE S to the estimate X (C = diag(S^2))."""
    X = np.arange(1.0, N + 1)
    p = X - last * EDGE * S
    return _unsettled(_result(X, np.diag(S ** 2)), _point(p), _point(p - prev * EDGE * S))


def test_last_step_inside_the_confidence_region_is_settled():
    """d^T C^-1 d = 0.81 BOUND: converged within the estimate's noise, even after a shorter
    step before it."""
    assert _check(0.9, 0.1) is None


def test_last_step_outside_and_not_shorter_is_unsettled():
    """d^T C^-1 d = 1.21 BOUND after a step of 0.25 BOUND (growing), or of the same length."""
    last, prev, bound = _check(1.1, 0.5)
    assert np.isclose(bound, BOUND) and np.isclose(last, 1.21 * BOUND)
    assert np.isclose(prev, 0.25 * BOUND)
    assert _check(3.0, 3.0) is not None


def test_last_step_outside_but_shrinking_is_converging():
    """Outside the region (9 BOUND) but shorter than the step before (16 BOUND)."""
    assert _check(3.0, 4.0) is None


def test_correlated_covariance_and_a_missing_column():
    """A step along the long axis of a correlated covariance is inside where the same length
    across it is outside; a parameter without a column (NaN row and column, as least squares
    leaves an unidentifiable one) is left out and the degrees of freedom drop by one."""
    C = np.eye(N)
    C[0, 1] = C[1, 0] = 0.99
    C[5, :] = C[:, 5] = np.nan
    X = np.zeros(N)
    X[5] = np.nan
    along, across = np.zeros(N), np.zeros(N)
    along[:2] = 3.0           # d^T C^-1 d = 2 * 9 / 1.99 = 9.05
    across[:2] = 3.0, -3.0    # 2 * 9 / 0.01 = 1800
    assert _unsettled(_result(X, C), _point(-along), _point(-along)) is None
    last, prev, bound = _unsettled(_result(X, C), _point(-across), _point(-across))
    assert np.isclose(bound, stats.chi2.ppf(IV_SETTLED, N - 1))
    assert np.isclose(last, 1800.0) and prev == 0.0
