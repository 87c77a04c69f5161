"""The torque lag's search grid (identification.effects.torque_lag.grid): the trials up to
50 sample periods are the same on every log, and past them the grid continues on the same
ratio up to D / 2 pi, D the record's length, where a lag's corner reaches the lowest
frequency the record holds."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from jointbench.identification.effects.torque_lag import STEP, grid


def rows(n: int, ts: float) -> SimpleNamespace:
    return SimpleNamespace(sig=SimpleNamespace(ts=ts, qm=np.zeros(n)))


@pytest.mark.parametrize("n, ts", [(20001, 1 / 500), (14036, 1 / 350.87), (60001, 1e-3)])
def test_short_trials_unchanged_and_long_ones_up_to_the_records_reach(n, ts):
    g = grid(rows(n, ts))
    assert g[0] == 0.0
    np.testing.assert_allclose(g[1:41], np.geomspace(0.2 * ts, 50 * ts, 40), rtol=1e-12)
    D = n * ts
    assert g[-1] <= D / (2 * np.pi) < g[-1] * STEP * (1 + 1e-9)
    np.testing.assert_allclose(g[2:] / g[1:-1], STEP, rtol=1e-9)


def test_a_record_shorter_than_fifty_periods_times_two_pi_keeps_the_short_grid():
    ts = 1 / 500
    g = grid(rows(int(2 * np.pi * 50) - 1, ts))
    assert len(g) == 41 and g[-1] == pytest.approx(50 * ts)
