"""bench.results.runs.pool: the inverse-variance mean of several runs, its sigma widened by
the Birge ratio when the runs scatter beyond their own sigmas, computed by hand."""

from __future__ import annotations

import math

import pytest

from jointbench.bench.results.runs import pool


def test_runs_that_agree_keep_the_internal_sigma():
    p = pool([1.0, 1.001, 0.999], [0.01, 0.01, 0.01], ["a", "b", "c"])
    assert p.value == pytest.approx(1.0)
    assert p.sigma_internal == pytest.approx(0.01 / math.sqrt(3))
    assert p.birge < 1 and p.sigma == p.sigma_internal
    assert p.outliers == ()


def test_scattered_runs_widen_the_pooled_sigma_to_cover_the_spread():
    x = [1.00, 1.05, 0.97, 1.02]
    p = pool(x, [0.001] * 4, list("abcd"))
    sd = float(__import__("numpy").std(x, ddof=1))
    assert p.spread == pytest.approx(sd)
    # equal sigmas: s_int R = sd / sqrt(n), the standard error of the runs' mean
    assert p.sigma == pytest.approx(sd / 2)
    assert set(p.outliers) == {"a", "b", "c", "d"}      # every run is off by > 3 sigma


def test_weights_and_one_run():
    p = pool([1.0, 2.0], [1.0, 2.0], ["a", "b"])
    assert p.value == pytest.approx((1.0 + 2.0 / 4) / (1 + 1 / 4))
    one = pool([3.0], [0.1], ["a"])
    assert one.value == 3.0 and one.sigma == 0.1 and math.isnan(one.spread)
    with pytest.raises(ValueError, match="positive finite sigma"):
        pool([1.0, 2.0], [0.0, 1.0], ["a", "b"])
