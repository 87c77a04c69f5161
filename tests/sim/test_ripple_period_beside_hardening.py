"""The period search of a torque ripple tested beside a named hardening reads the residual
that the hardening leaves (identification.discrepancy.candidates._Left), on the independent
simulator's soft family (f1 = 4 Hz; no feed-forward, no torque noise; 40 s).

The hidden ripple has the family's default period 2 pi / (6 N) = 10.5 mrad (N = 100), about
11 periods over the motor's travel. The nominal's motor-equation residual holds the
hardening's own torque (the spring stiffer at large deflections, a function of the deflection
that the periodogram over the motor angle spreads over every wavenumber): its highest peaks
are elsewhere. What the model holding the hardening leaves is the ripple: its periodogram
peaks at the hidden period, within the periodogram's wavenumber step pi / (2 span)."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.identification.discrepancy.candidates import _Left, reference
from jointbench.identification.discrepancy.nominal import nominal
from jointbench.identification.effects.torque_ripple import _periodogram_peaks
from jointbench.testing import INDEP_PLACES, IndepRunner

SOFT = INDEP_PLACES[1]
SEED = 10336
HARDENING = (0.30, 0.032)     # ratio Kh / K and engagement [rad], about 27 % visibility
RIPPLE = 7.7                  # N m, about 16 % visibility
PERIOD = 2 * np.pi / (6 * 100)   # the simulator's default: 2 pi / (6 N), N = 100


@pytest.fixture(scope="module")
def pair():
    log = IndepRunner(40.0).log(SOFT, (("hardening", HARDENING[0],
                                         {"deflection": HARDENING[1]}),
                                        ("torque_ripple", RIPPLE, {})), SEED, False, False)
    settings, _ = diagnosis_settings(log)
    nom = nominal(log, settings)
    ref = reference(nom, (("hardening", {"deflection_rad": HARDENING[1]}),))
    return nom, ref


@pytest.mark.slow
def test_the_ripple_period_is_read_from_what_the_hardening_leaves(pair):
    nom, ref = pair
    sig = nom.sig
    span = float(np.ptp(sig.qm[sig.sl]))
    assert span >= 2 * PERIOD   # the log holds the period at least twice
    step = np.pi / (2 * span)   # the periodogram's wavenumber step
    k = 2 * np.pi / PERIOD
    left = _periodogram_peaks(_Left(nom, ref.base), span)
    assert np.min(np.abs(left - k)) <= step
    # the nominal's residual, which still holds the hardening, peaks elsewhere
    assert np.min(np.abs(_periodogram_peaks(nom, span) - k)) > step
