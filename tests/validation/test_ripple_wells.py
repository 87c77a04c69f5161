"""A strong torque ripple stops the motor in its wells: the still samples it makes raise the
period grid's start (torque_ripple.seen_from) above the ripple's own period, and the rests'
angles repeat at it (torque_ripple.rests_repeat: Rayleigh's test, and less at twice the
period, over rests that span two periods), which a presliding stiffness's do not, nor the
turning points of a motor settling about one angle, one rest (torque_ripple.rest_angles).
The ripple is then searched and named at its period (the independent simulator's lab rig;
diagnose without the forward view)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from jointbench.testing.simulator import LAB_RIG, simulate_lab_rig

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.identification.discrepancy.heldout import ALPHA
from jointbench.identification.effects import torque_ripple

SEED = 10291
DURATION = 20.0
RIPPLE = 0.15     # N m: strong enough that the motor rests in its wells for long


def test_rest_angles_at_wells_repeat_and_uniform_ones_do_not():
    rng = np.random.default_rng(3)
    period, n = 0.015, 200
    wells = period * (rng.integers(0, 70, n) + 0.5) + rng.normal(0.0, 0.1 * period, n)
    spread = rng.uniform(0.0, 70 * period, n)
    assert torque_ripple.rayleigh_p(wells, period) < ALPHA
    # uniform phases: p is uniform on (0, 1) under the null, a level-ALPHA miss is rare
    assert torque_ripple.rayleigh_p(spread, period) > ALPHA
    # the wells' period, not its harmonic (more at twice its own) nor its multiple
    assert torque_ripple.rests_repeat(wells, np.array([period, period / 2, 2 * period])
                                      ).tolist() == [True, False, False]
    assert not torque_ripple.rests_repeat(spread, np.array([period])).any()
    # rests in two wells a period apart span less than REPEATS periods: their phases agree at
    # the period, but as well at each of its divisors, and a settling motor's rests within
    # one period of each other cluster at any period longer than their scatter
    two = period * (rng.integers(0, 2, n) + 0.5) + rng.normal(0.0, 0.1 * period, n)
    assert torque_ripple.rayleigh_p(two, period) < ALPHA
    assert not torque_ripple.rests_repeat(two, np.array([period])).any()


def test_strong_lab_rig_ripple_named_at_its_period():
    log = simulate_lab_rig(LAB_RIG, SEED, DURATION, effects=f"torque_ripple={RIPPLE}")
    d = diagnose(log, forward=False)
    assert d.named_cause == "torque_ripple", [(x.effect, x.why) for x in d.inverse.not_named]
    period = d.extended_parameters["ripple_period_rad"]
    truth = 2 * math.pi / (6 * LAB_RIG.N)     # the simulator's default: 2 pi / (6 N)
    # below the grid's start set by the still samples
    assert truth < torque_ripple._coarse(d.inverse.nominal)[0]
    # the period search's resolution: a quarter period of drift over the motor's span,
    # dp = p^2 / (4 span) (torque_ripple._periodogram_peaks)
    span = float(np.ptp(log.q_m))
    assert abs(period - truth) <= truth ** 2 / (4 * span), (period, truth)


def test_a_settling_motor_rests_once_a_reversal_is_no_rest_and_a_return_no_new_one():
    # decimated rows over a 1 rad travel: the encoder-scale step is span / SHORTEST, and a
    # row is still where |qm'| is under the decimated cutoff times that step
    step = 1.0 / torque_ripple.SHORTEST
    moving, settle = 1.0, 1e-3 * step
    qm, qmd = [0.0], [moving]
    for k in range(10):         # settling about 0.2 rad: turning points within the step
        qm += [0.2 + settle * (-1) ** k, 0.2]
        qmd += [moving, 0.0]
    qm += [0.35, 0.5, 0.5, 0.5, 0.65, 0.8, 0.9, 1.0]     # a rest at 0.5, a reversal at 0.8
    qmd += [moving, 0.0, 0.0, 0.0, moving, 0.0, moving, moving]
    qm += [0.75, 0.5, 0.5]      # back to rest at 0.5: the same phase at every period
    qmd += [moving, 0.0, 0.0]
    qm, qmd = np.array(qm), np.array(qmd)
    sig = SimpleNamespace(qm=qm, qmd=qmd, index=np.arange(len(qm)), sl=slice(None),
                          settings=SimpleNamespace(decimated_cutoff_hz=10.0))
    rest = torque_ripple.rest_angles(SimpleNamespace(sig=sig))
    assert rest == pytest.approx([0.2, 0.5], abs=settle)
