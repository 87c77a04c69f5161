"""identification/iv_check.py on synthetic rows (`compare`): the instrumental-variable
estimate held against least squares of the same rows, z = |X_IV - X_LS| / (sigma_IV +
sigma_LS) over K, Jm, JL against the Bonferroni normal quantile of the stated false-alarm
rate."""

from __future__ import annotations

from statistics import NormalDist

import numpy as np
import pytest

from jointbench.identification.estimate import least_squares
from jointbench.identification.iv_check import ALPHA, compare, z_threshold

NAMES = ("Jm", "K", "JL")
X_TRUE = np.array([2.0, 500.0, 5.0])
N = 2000


def _rows(rng: np.random.Generator, leak: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """y = W X + e with W exogenous (independent of e) and instruments Z = W plus their own
    first-stage noise, plus `leak` times the error e in every column: leak 0 gives valid
    instruments, leak > 0 instruments correlated with the equation error (biased IV)."""
    t = np.arange(N) / 100.0
    W = np.column_stack([np.sin(2.1 * t), 0.01 * np.cos(0.7 * t), np.sin(1.3 * t + 1.0)])
    W = W + 0.1 * W.std(axis=0) * rng.standard_normal(W.shape)
    e = rng.standard_normal(N)
    first_stage = 0.2 * W.std(axis=0) * rng.standard_normal(W.shape)
    Z = W + first_stage + leak * W.std(axis=0) * e[:, None]
    return W, W @ X_TRUE + e, Z


def _check(W, y, Z):
    return compare(least_squares(W, y, NAMES, instruments=Z), least_squares(W, y, NAMES))


def test_threshold_is_the_bonferroni_normal_quantile():
    assert z_threshold() == pytest.approx(NormalDist().inv_cdf(1 - ALPHA / 6), rel=1e-9)
    assert z_threshold(0.05, 1) == pytest.approx(1.959964, abs=1e-6)
    with pytest.raises(ValueError):
        z_threshold(0.0)


def test_valid_instruments_rarely_fire():
    """Both estimates consistent (exogenous W, valid Z): the false-alarm rate is at most
    ALPHA = 1e-3 per fit, so 200 draws fire at most twice with probability > 0.999
    (binomial(200, 1e-3)); the bound is conservative and the measured count is 0."""
    rng = np.random.default_rng(20)
    fired = [_check(*_rows(rng, leak=0.0)).fired for _ in range(200)]
    assert sum(fired) <= 2, sum(fired)


def test_instruments_correlated_with_the_error_fire():
    """Instruments that carry the equation error (IV biased on purpose, least squares
    consistent): the check fires and names a parameter of K, Jm, JL, with the two values."""
    rng = np.random.default_rng(21)
    W, y, Z = _rows(rng, leak=0.5)
    check = _check(W, y, Z)
    assert check.fired and check.z > check.threshold, check
    assert check.name in NAMES
    ls = least_squares(W, y, NAMES)
    assert check.b == ls.value(check.name)
    # least squares is the consistent one here: within 4 of its sigmas of the truth
    assert abs(ls.value(check.name) - X_TRUE[NAMES.index(check.name)]) < \
        4 * ls.std_corrected(check.name)
    assert "instruments from q_ref rejected" in check.warning(ls.value(check.name))


def test_nothing_to_test_without_the_parameters():
    rng = np.random.default_rng(22)
    W, y, Z = _rows(rng, leak=0.0)
    names = ("a", "b", "c")
    assert compare(least_squares(W, y, names, instruments=Z), least_squares(W, y, names)) is None


def test_warnings_name_the_values_and_the_rate():
    rng = np.random.default_rng(21)
    check = _check(*_rows(rng, leak=0.5))
    kept, rejected = check.kept_warning(1.0), check.warning(1.0)
    for text in (kept, rejected):
        assert f"{check.a:.4g}" in text and f"{check.b:.4g}" in text and "0.001" in text
    assert "instruments kept" in kept and "least squares kept" in rejected
    assert "their start" not in check.kept_warning(None)
