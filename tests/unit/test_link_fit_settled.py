"""The convergence check of the link reconstruction's instrumental passes
(identification/link_fit.py, `_unsettled`): the last Gauss-Newton step against the estimate's
own covariance, d^T C^-1 d, compared with the chi-square quantile IV_SETTLED."""

from __future__ import annotations

import numpy as np
from scipy import stats

from jointbench.identification.estimate import LSResult
from jointbench.identification.link_fit import IV_SETTLED, NAMES, _unsettled


def _result(X: np.ndarray, C: np.ndarray) -> LSResult:
    return LSResult(NAMES, X, np.sqrt(np.diag(C)), C, 1.0, np.zeros(3), 3, 1.0, (), {},
                    cov_corrected=C)


def _point(x: np.ndarray) -> dict[str, float]:
    return {n: float(v) for n, v in zip(NAMES, x)}


def test_step_inside_and_outside_the_confidence_region():
    """With C = diag(s^2) and a step of u standard deviations in every parameter,
    d^T C^-1 d = 9 u^2: inside the region for 9 u^2 below chi2(IV_SETTLED, 9), outside above."""
    s = np.linspace(0.5, 4.0, len(NAMES))
    C = np.diag(s ** 2)
    X = np.arange(1.0, len(NAMES) + 1)
    bound = stats.chi2.ppf(IV_SETTLED, len(NAMES))
    u_edge = np.sqrt(bound / len(NAMES))
    assert _unsettled(_result(X, C), _point(X - 0.9 * u_edge * s)) is None
    q, b = _unsettled(_result(X, C), _point(X - 1.1 * u_edge * s))
    assert np.isclose(b, bound) and np.isclose(q, 1.21 * bound)


def test_correlated_covariance_and_a_missing_column():
    """A step along the long axis of a correlated covariance is inside where the same length
    across it is outside; a parameter without a column (NaN row and column, as least squares
    leaves an unidentifiable one) is left out and the degrees of freedom drop by one."""
    n = len(NAMES)
    C = np.eye(n)
    C[0, 1] = C[1, 0] = 0.99
    C[5, :] = C[:, 5] = np.nan
    X = np.zeros(n)
    X[5] = np.nan
    along, across = np.zeros(n), np.zeros(n)
    along[:2] = 3.0           # d^T C^-1 d = 2 * 9 / 1.99 = 9.05
    across[:2] = 3.0, -3.0    # 2 * 9 / 0.01 = 1800
    bound = stats.chi2.ppf(IV_SETTLED, n - 1)
    assert _unsettled(_result(X, C), _point(-along)) is None
    q, b = _unsettled(_result(X, C), _point(-across))
    assert np.isclose(b, bound) and np.isclose(q, 1800.0)
