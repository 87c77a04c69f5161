"""A torque ripple fitted in the first step of its period grid, or at a period the span of the
motor angle does not hold twice, is unphysical (identification.effects.torque_ripple.check;
no MuJoCo)."""

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


def _moving_rows(stuck: float, fc: float = 14.0) -> SimpleNamespace:
    """A motor over 1 rad whose speed is 0 on a share `stuck` of the samples (it sticks) and
    spread over 0.05 to 0.5 rad/s on the others; the band's decimated cutoff `fc` [Hz]."""
    n = 3000
    rng = np.random.default_rng(1)
    v = rng.uniform(0.05, 0.5, n) * rng.choice([-1.0, 1.0], n)
    v[: int(stuck * n)] = 0.0
    qm = np.linspace(0.0, 1.0, n)
    return SimpleNamespace(sig=SimpleNamespace(
        qm=qm, qmd=v, sl=slice(None), settings=SimpleNamespace(decimated_cutoff_hz=fc)))


def test_a_motor_that_turns_keeps_the_encoder_scale_grid():
    rows = _moving_rows(0.0)
    g = torque_ripple._coarse(rows)
    assert g[0] == pytest.approx(max(1.0 / torque_ripple.SHORTEST, 1e-4))
    assert torque_ripple.check({"ripple_period_rad": 2 * np.pi / 600}, rows) == ""


def test_the_grid_starts_where_the_in_band_samples_are_mostly_moving_ones():
    # a third of the samples stuck: at the encoder-scale step the column is in the band on
    # those alone; the grid starts where it is in the band on twice as many
    rows = _moving_rows(1 / 3)
    fc = rows.sig.settings.decimated_cutoff_hz
    v = np.abs(rows.sig.qmd)
    g = torque_ripple._coarse(rows)
    # the first point of the encoder-scale grid where it is (the grid's points are kept)
    full = np.geomspace(1.0 / torque_ripple.SHORTEST, 1.0, torque_ripple.COARSE)
    assert np.any(np.isclose(full, g[0], rtol=1e-12))
    assert np.mean(v < fc * g[0]) >= torque_ripple.SEEN / 3
    assert np.mean(v < fc * g[0] * g[0] / g[1]) < torque_ripple.SEEN / 3
    # a fit in the first step ran to that bound: a sticking motor's misfit, not a ripple
    assert torque_ripple.check({"ripple_period_rad": g[0]}, rows)
    assert torque_ripple.check({"ripple_period_rad": g[1] * 1.001}, rows) == ""
    # the periodogram's fine periods keep to the coarse grid's range
    rows.residual, rows.block = None, None
    assert torque_ripple.grid(rows)[0] == g[0]


@pytest.mark.parametrize("span", [0.05, 0.118, 1.0])
def test_a_period_the_span_does_not_hold_twice_is_unphysical(span):
    """Every phase of a period p is seen at two angles a period apart only when the span of
    the motor angle holds REPEATS periods: a longer period, the grid's top (the span itself)
    included, is one arch over the travel, which a constant follows as well."""
    rows = _rows(span)
    assert torque_ripple.REPEATS == 2
    for p in (span, 0.9 * span, 0.501 * span):
        assert "fewer than 2 periods" in torque_ripple.check({"ripple_period_rad": p}, rows)
    assert torque_ripple.check({"ripple_period_rad": 0.5 * span}, rows) == ""
    # the grid's top is the span: a search that runs there names no ripple
    rows.residual, rows.block = None, None
    assert torque_ripple.check({"ripple_period_rad": torque_ripple.grid(rows)[-1]}, rows)
