"""torque_ripple's period grid: a short period with many periods over the motion span is
resolved by the residual's periodogram against the motor angle (effects.torque_ripple)."""

from types import SimpleNamespace

import numpy as np
import pytest

from jointbench.identification.effects import torque_ripple as tr


def _rows(period: float, amplitude: float, seed: int = 3):
    # a chirp-like motion over 1.2 rad sampled at 2000 rows; the residual a ripple plus noise
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, 2000)
    qm = 0.6 * np.sin(2 * np.pi * (1 + 6 * t) * t)
    r = amplitude * np.sin(2 * np.pi * qm / period + 0.4) + rng.normal(0, 1, len(t))
    sig = SimpleNamespace(qm=qm, sl=slice(0, len(t)), index=np.arange(len(t)))
    return SimpleNamespace(sig=sig, residual=r, block=np.zeros(len(t), int)), float(np.ptp(qm))


@pytest.mark.parametrize("period", [2 * np.pi / (6 * 70), 2 * np.pi / (6 * 100), 0.05])
def test_grid_holds_a_point_within_a_quarter_period_drift(period):
    rows, span = _rows(period, 0.5)
    g = tr.grid(rows)
    # a period off by dp drifts span dp / p^2 periods over the span: a quarter at most
    drift = span * np.min(np.abs(g - period)) / period ** 2
    assert drift < 0.25
    # the coarse grid alone does not (its step is a few % of the period: many periods' drift)
    coarse = np.geomspace(span / tr.SHORTEST, span, tr.COARSE)
    if period < 0.02:
        assert span * np.min(np.abs(coarse - period)) / period ** 2 > 0.25


def test_grid_without_a_residual_is_the_coarse_grid():
    rows, span = _rows(0.015, 0.5)
    bare = SimpleNamespace(sig=rows.sig)
    assert len(tr.grid(bare)) == tr.COARSE
