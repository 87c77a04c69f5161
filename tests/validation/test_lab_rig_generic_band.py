"""`diagnose` on a lab-rig log whose first mode is not found: the generic band (a tenth of the
rate, decimated cutoff 0.04 Fs = 20 Hz at 500 Hz) reaches twice the multisine's top (10 Hz),
where the log holds only the encoders' quantisation. The band stops at the excitation's top
measured on the log (identification.band_choice.excitation_capped), and a torque ripple
strong enough to hide the mode from the frequency responses is named with its period, and a
long drive lag with its time constant.

The seed was fixed before the first run of this file."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointbench.testing.simulator import LAB_RIG, simulate_lab_rig

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.identification.band_choice import WELCH_SEGMENT_S, excitation_capped
from jointbench.identification.effects.torque_lag import STEP
from jointbench.identification.filter_choice import generic_settings

SEED = 10247
DWELL_SEED = 10246            # a run whose ripple slows the motor enough to double its peak
DURATION = 20.0
RIPPLE = 0.12                 # N m: its motion hides the mode from q/tau_m, q_m/tau_m, q/q_m
MULTISINE_TOP_HZ = 10.0       # simulate_lab_rig's default multisine: 0.025-10 Hz
LAG_S = 0.5                   # s: a voltage drive under the P loop, corner 0.32 Hz


@pytest.fixture(scope="module")
def ripple_log():
    return simulate_lab_rig(LAB_RIG, SEED, DURATION, effects=f"torque_ripple={RIPPLE}")


def test_generic_band_stops_at_the_multisine_top(ripple_log):
    base = generic_settings(ripple_log.sample_rate_hz)
    capped, how = excitation_capped(ripple_log, base)
    # Nd is the smallest decimation whose cutoff stays at or under the measured top, which
    # lies within a Welch bin of the multisine's: one Nd step under it at most
    fc = capped.decimated_cutoff_hz
    assert MULTISINE_TOP_HZ * capped.Nd / (capped.Nd + 1) <= fc \
        <= MULTISINE_TOP_HZ + 1 / WELCH_SEGMENT_S, (fc, how)
    assert base.decimated_cutoff_hz > 1.5 * MULTISINE_TOP_HZ and "excitation's top" in how
    # a band already under the top stays as it is
    assert excitation_capped(ripple_log, capped) == (capped, "")


def test_ripple_named_when_no_mode_is_found(ripple_log):
    settings, how = diagnosis_settings(ripple_log)
    assert how.startswith("no resonance found") and "excitation's top" in how
    assert settings.decimated_cutoff_hz <= MULTISINE_TOP_HZ + 1 / WELCH_SEGMENT_S
    d = diagnose(ripple_log, forward=False)
    assert d.named_cause == "torque_ripple"
    period = d.extended_parameters["ripple_period_rad"]
    truth = 2 * math.pi / (6 * LAB_RIG.N)     # the simulator's default: 2 pi / (6 N)
    # the period search's resolution: a quarter period of drift over the motor's span,
    # dp = p^2 / (4 span) (torque_ripple._periodogram_peaks)
    span = float(np.ptp(ripple_log.q_m))
    assert abs(period - truth) <= truth ** 2 / (4 * span), (period, truth)


@pytest.mark.slow
def test_ripple_period_not_its_half():
    """A strong ripple slows the motor where it opposes it: the motor dwells longer at some
    phases of the period, and a periodogram summing the residual over the rows weighs each
    angle by that dwell time, the product of two sinusoids of the period, whose peak at half
    the period can outgrow the period's own and leave the period out of the search grid.
    Each angle bin's mean residual (torque_ripple._periodogram_peaks) is the residual as a
    function of the angle, and the ripple is named at its own period, within the search's
    resolution dp = p^2 / (4 span)."""
    log = simulate_lab_rig(LAB_RIG, DWELL_SEED, DURATION, effects=f"torque_ripple={RIPPLE}")
    d = diagnose(log, forward=False)
    assert d.named_cause == "torque_ripple"
    period = d.extended_parameters["ripple_period_rad"]
    truth = 2 * math.pi / (6 * LAB_RIG.N)
    span = float(np.ptp(log.q_m))
    assert abs(period - truth) <= truth ** 2 / (4 * span), (period, truth)


def test_long_lag_named_when_no_mode_is_found():
    """A drive lag of half a second (corner 0.3 Hz) hides the mode from the responses; in
    the generic band twice the multisine's top the led columns x + T x' carry the
    quantisation amplified by w T and nothing is named; at the top the lag is, with its
    time constant within half a step of its search grid (torque_lag.STEP)."""
    log = simulate_lab_rig(LAB_RIG, SEED, DURATION, effects=f"torque_lag={LAG_S}")
    _, how = diagnosis_settings(log)
    assert how.startswith("no resonance found") and "excitation's top" in how
    d = diagnose(log, forward=False)
    assert d.named_cause == "torque_lag"
    assert d.extended_parameters["lag_s"] == pytest.approx(LAG_S, rel=math.sqrt(STEP) - 1)
