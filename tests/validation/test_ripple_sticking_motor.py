"""A motor that sticks shows no torque ripple (identification.effects.torque_ripple: the period
grid starts where the column's in-band samples are mostly ones where the motor turns).

On the independent simulator's balanced family without feedforward, an asymmetric friction of
-0.95 (one direction's friction nearly doubled) makes the motor stick for a third of the log:
there the column sin(2 pi qm / p) of a period a few hundred times shorter than the motion is
in the band whatever p, and follows the sticking friction's presliding misfit. Such a period
is not searched, and the log names the asymmetry alone; a ripple of the drive's own period on
the same axis is still named.
"""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.identification.discrepancy import diagnose_inverse
from jointbench.identification.effects import torque_ripple
from jointbench.testing import FAMILIES, simulate

DURATION = 40.0


def _inverse(effects: str):
    log = simulate(FAMILIES["balanced"], seed=1, duration=DURATION, feedforward=False,
                   torque_noise_std=0.0, effects=effects)
    settings, _ = diagnosis_settings(log)
    return diagnose_inverse(log, settings)


@pytest.fixture(scope="module")
def asymmetry():
    return _inverse("asymmetric_friction=-0.95")


def test_the_motor_sticks(asymmetry):
    # the premise: at the encoder-scale step the column is in the band on many samples
    nom = asymmetry.nominal
    sig = nom.sig
    grid = torque_ripple._coarse(nom)
    start = torque_ripple._encoder_step(float(np.ptp(sig.qm[sig.sl])))
    v = np.abs(np.nan_to_num(sig.qmd[sig.sl]))
    still = float(np.mean(v < sig.settings.decimated_cutoff_hz * start))
    assert still > 0.1
    assert grid[0] > 10 * start   # the grid starts well above the encoder-scale step


def test_asymmetry_alone_is_named_no_ripple(asymmetry):
    assert [c.effect for c in asymmetry.causes] == ["asymmetric_friction"]
    ripple = [n for n in asymmetry.not_named if n.effect == "torque_ripple"]
    assert len(ripple) == 1 and ripple[0].why


def test_a_drive_ripple_on_the_same_axis_is_still_named():
    inv = _inverse("torque_ripple=2")
    assert inv.named_cause == "torque_ripple"
    # the drive's period 2 pi / (6 N), N = 100, within a search grid step
    period = inv.named.parameters["ripple_period_rad"]
    assert period == pytest.approx(2 * np.pi / 600, rel=0.05)
