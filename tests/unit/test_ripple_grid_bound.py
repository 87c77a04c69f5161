"""A torque ripple fitted in the first step of its period grid is unphysical
(identification.effects.torque_ripple.check): the search ran to its bound (no MuJoCo)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from jointbench.identification.effects import torque_ripple


def _rows(span: float) -> SimpleNamespace:
    qm = np.linspace(0.0, span, 1000)
    return SimpleNamespace(sig=SimpleNamespace(qm=qm, sl=slice(None)))


@pytest.mark.parametrize("span", [0.05, 1.0, 6.0])
def test_first_step_of_the_grid_is_unphysical(span):
    rows = _rows(span)
    g = np.geomspace(max(span / torque_ripple.SHORTEST, 1e-4), max(span, 2e-4),
                     torque_ripple.COARSE)
    assert torque_ripple.check({"ripple_period_rad": g[0]}, rows)
    assert torque_ripple.check({"ripple_period_rad": 0.5 * (g[0] + g[1])}, rows)
    assert torque_ripple.check({"ripple_period_rad": g[1] * 1.001}, rows) == ""
    # a drive's ripple, 2 pi / (6 N) with N = 100, is far above the first step
    assert torque_ripple.check({"ripple_period_rad": 2 * np.pi / 600}, rows) == ""


def test_grid_starts_at_the_bound_the_check_reads():
    rows = _rows(1.0)
    rows.residual, rows.block = None, None
    g = torque_ripple.grid(rows)
    assert torque_ripple.check({"ripple_period_rad": g[0]}, rows)
    assert torque_ripple.check({"ripple_period_rad": g[1]}, rows) == ""
