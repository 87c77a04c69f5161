"""A hardening on a low-f1 axis (identification/discrepancy/heldout.py, an engaging spring's
units; lag_band.py): the spring engages in a few segments of the sweep only, and the
chooser's band has a few rows each there. Counted by the segments its t is capped by how many
engage; counted by the spring's engagements the chooser's band names it, with a test that
passes at half its level (its second view, at large deflections in the wide band, holds the
other half). The independent simulator's soft family (f1 about 4 Hz, the chooser's band to
5.4 Hz), a hardening of ratio 0.16 engaged at 22 mrad (the deflection reaches 0.27 rad at the
mode)."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.identification.discrepancy import diagnose_inverse
from jointbench.identification.discrepancy.candidates import CHOOSER
from jointbench.identification.discrepancy.heldout import (ALPHA, FOLDS, SEGMENTS, bar,
                                                           evidence, segment_of_rows, t_bar)
from jointbench.identification.discrepancy.lag_band import LagBand, large_deflections

DURATION = 30.0
RATIO, ENGAGED = 0.16, 0.022


def _soft(effects: str):
    from jointbench.testing import FAMILIES, simulate
    return simulate(FAMILIES["soft"], seed=2, duration=DURATION, effects=effects)


def _hardening(inv):
    return next(c for c in inv.candidates if c.effect == "hardening")


def _named_over_engagements(inv, engaged: float):
    named = next(c for c in inv.causes if c.effect == "hardening")
    test = named.test
    assert test.passes and test.p < named.alpha / 2          # half the hypothesis' level
    # a test that counts the engagements of the spring (heldout.engagement_units in the
    # chooser's band, lag_band.engagements at large deflections in the wide band), its
    # degrees of freedom from their number: its bar is the one of that many values
    assert test.segments >= 3 and "engagement" in test.view
    assert test.t > test.bar == pytest.approx(t_bar(named.level, test.segments))
    # the engagement found within a grid step or two of the true one (the filtered deflection
    # the columns see is the measured one's low-passed version)
    assert named.fixed["deflection_rad"] == pytest.approx(engaged, rel=0.3)
    return named


@pytest.fixture(scope="module")
def hardened():
    """The soft family with the hardening, its diagnosis settings and inverse view."""
    log = _soft(f"hardening={RATIO}:deflection={ENGAGED}")
    settings = diagnosis_settings(log)[0]
    return log, settings, diagnose_inverse(log, settings)


def test_a_hardening_is_named_over_its_engagements_in_the_chooser_band(hardened):
    """The spring engages in 9 or so of the 40 segments, with a few decimated rows each:
    over every segment the chooser's band's t is under the bar of a first round of 8 (the
    other segments dilute the mean, the engaged ones' jumps count as noise). Counted by the
    spring's engagements (heldout.over_engagements) its own test passes at half the level,
    with the bar of that many values, and the engagement and ratio are the simulator's."""
    _, _, inv = hardened
    assert [c.effect for c in inv.causes] == ["hardening"]
    named = inv.causes[0]
    test = named.test
    assert test is not None and test.passes and test.p < named.alpha / 2
    assert test.view.startswith(CHOOSER) and "each engagement apart" in test.view
    assert 3 <= test.segments != SEGMENTS
    assert test.t > test.bar == pytest.approx(t_bar(named.level, test.segments))
    # the same held-out errors counted by the segments: diluted under the bar
    n = len(named.heldout_errors) // 2
    over = evidence(named.reference_errors, named.heldout_errors, n, named.acts)
    assert over.segments == SEGMENTS and over.t < t_bar(bar(8)) < test.t
    # the engagement within a grid step or two of the true one (the columns see the filtered
    # deflection), the ratio within the fit's spread on a 30 s log
    assert named.fixed["deflection_rad"] == pytest.approx(ENGAGED, rel=0.3)
    assert named.parameters["hardening_ratio"] == pytest.approx(RATIO, rel=0.5)


def test_a_hardening_at_large_deflections_is_seen_in_its_band(hardened):
    """Its view at large deflections in the wide band, over the segments whose largest
    deflection passes their fold's engagement, a few segments of the sweep."""
    log, settings, inv = hardened
    h = _hardening(inv)
    nom = LagBand(log, settings).nominal()
    within = large_deflections(nom, h.fold_values)
    sig = nom.sig
    d = np.abs((sig.qm - sig.q)[sig.index])
    seg = segment_of_rows(len(d))
    top = np.array([d[seg == s].max() for s in range(SEGMENTS)])
    assert np.array_equal(within, top > np.asarray(h.fold_values)[np.arange(SEGMENTS) % FOLDS])
    assert 3 <= within.sum() < SEGMENTS // 2        # a few segments of the sweep


def test_a_hardening_beside_a_backlash_is_named_over_its_engagements():
    """A backlash of 2 mrad beside a stronger hardening (ratio 0.5 at 30 mrad): both are
    named, the hardening with a test over its engagements (first or second: both pass in
    the first round, and which the look-ahead puts first is not what this test is about)."""
    log = _soft("backlash=0.002,hardening=0.5:deflection=0.03")
    inv = diagnose_inverse(log, diagnosis_settings(log)[0])
    assert sorted(c.effect for c in inv.causes) == ["backlash", "hardening"]
    _named_over_engagements(inv, 0.03)


def test_the_hardening_and_the_lag_split_their_level():
    """On a log with a wide band the three effects with a second view (a lag, a hardening, a
    backlash) test their hypothesis twice, each at half its level; every other effect keeps
    the round's level (Holm)."""
    from jointbench.testing import FAMILIES, simulate
    log = simulate(FAMILIES["soft"], seed=2, duration=DURATION)
    inv = diagnose_inverse(log, diagnosis_settings(log)[0])
    assert inv.causes == ()
    tested = {c.effect: c for c in inv.candidates if c.testable}
    assert {c.alpha for c in tested.values()} == {ALPHA / 8}
    assert {e for e, c in tested.items() if c.views == 2} == {"torque_lag", "hardening",
                                                                  "backlash"}
    assert all(c.level == c.alpha / c.views for c in tested.values())


def test_a_hardening_view_confirms_only_at_large_deflections():
    """The guard: a view at its level, physical and agreeing confirms a hardening whose
    chooser's-band share over every row is lost to a cause beside it (a diluted view); a
    lag's view still asks for a positive share there; an engagement in the first step of
    its grid is a stiffness and a sign of the deflection, unphysical, never confirmed."""
    from jointbench.identification.discrepancy.candidates import Candidate, SecondView
    alpha = ALPHA / 7
    seen = SecondView(band="wide, at large deflections", heldout_pct=30.0, t_stat=12.0,
                      p_heldout=1e-6, value=0.02, agree=True, detail="", diluted=True)
    h = Candidate(effect="hardening", testable=True, heldout_pct=-1.0, t_stat=-3.0,
                  p_heldout=0.99, alpha=alpha, views=2)
    assert not h.significant
    named = Candidate(**{**h.__dict__, "second": seen})
    assert named.significant and named.test.passes and named.test.heldout_pct == 30.0
    edge = SecondView(**{**seen.__dict__, "unphysical": "engagement in the first step"})
    assert not Candidate(**{**h.__dict__, "second": edge}).significant
    lag = Candidate(**{**h.__dict__, "effect": "torque_lag",
                       "second": SecondView(**{**seen.__dict__, "diluted": False})})
    assert not lag.significant
