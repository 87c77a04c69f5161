"""The weaker of a pair tested against the model holding the stronger, where it is visible
(identification.discrepancy.lag_band.where_visible, identification.discrepancy.masked: the
stronger, then the weaker on top of it).

On the independent simulator's soft family (f1 about 3 Hz, a linear chirp to 29 Hz), a
backlash of 10.3 mrad and a spring damping of 10.9 N m s/rad, about a third and a fifth of
the in-band torque, no feedforward, no torque noise. The spring damping is named first; on
top of it the dead band removes nearly all of the held-out residual, all of it in the
chirp's first segments, where the sweep passes the mode. Over every segment of both
equations its test fails: in the others the residual is what the numerics leave, and the
refit moves the prediction by a share of it that jumps from segment to segment (t about 3.7
against 4.18). Over the link equation, where the damping's residual is what the spring law
still misses (identification.discrepancy.candidates._test), or where its held-out
prediction changes most, the half of the segments that holds the mode, or in the wide band
with the dead band's harmonics, it passes at an eighth of the round's level (its two sets of
rows, two bands and two views share it), and the answer names both. Without those views the
answer named the spring damping alone.

The second case is the same pair at other strengths (a spring damping of 11.6 N m s/rad and
a dead band of 8.6 mrad, torque noise on) where no effect passes alone against the nominal:
the backlash passes on top of the spring damping at the ordered pairs' level and the
converse does not, so the backlash is named in the inverse view with that test and the
spring damping is tested on top of it, in round 2. Before, the inverse view named nothing."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import Place
from jointbench.identification.discrepancy.candidates import ROW_VIEWS
from jointbench.identification.discrepancy.heldout import ALPHA, SEGMENTS, evidence
from jointbench.identification.output_values import finite_json
from jointbench.testing import IndepRunner

SOFT = Place("indep", "soft")


@pytest.fixture(scope="module")
def runner():
    return IndepRunner(40.0)


def test_the_weaker_passes_where_it_is_visible(runner):
    log = runner.log(SOFT, (("backlash", 0.010319414881451437, {}),
                            ("spring_damping", 10.923960013665507, {})),
                     1045251274, False, False)
    d = diagnose(log)
    assert [c.effect for c in d.causes] == ["spring_damping", "backlash"]
    assert d.verdict == "named"
    bl = d.causes[1]
    assert bl.round == 2
    # its claim is a view beyond the chooser's band over every segment of both equations,
    # which it fails: the link equation's (candidates._test), the wide band's (lag_band.
    # second_view) or where it is visible (lag_band.where_visible); the round's Holm level
    # (7 effects left) split over its two sets of rows, two bands and two views
    t = bl.test
    assert (t.view == "chooser's band, over the link equation"
            or "where it is visible" in t.view and t.segments == SEGMENTS // 2
            or t.view.startswith("wide band") and "over every segment" in t.view)
    assert bl.level == pytest.approx(ALPHA / 7 / 8)
    assert t.passes
    n = len(d.inverse.nominal.sig.index)
    both = evidence(bl.reference_errors, bl.heldout_errors, n, bl.acts)
    assert bl.acts == (0, 1) and not both.p < bl.level
    assert failing_claims(finite_json(d.to_json())) == []


def test_the_stronger_of_a_masked_pair_is_named_then_the_weaker_tested_on_it(runner):
    log = runner.log(SOFT, (("spring_damping", 11.591230356428163, {}),
                            ("backlash", 0.008568073802729644, {})),
                     1773311433, False, True)
    d = diagnose(log)
    inv = d.inverse
    assert not any(c.significant for c in inv.rounds[0])   # none passes alone
    assert inv.masked is not None and inv.masked.lead is not None
    assert [c.effect for c in inv.causes][:1] == ["backlash"]
    lead = inv.causes[0]
    m = len([c for c in inv.candidates if c.testable])
    # at the ordered pairs' level, split over its two sets of rows (candidates._test)
    assert lead.test.view.startswith("the masked pair, on top of spring_damping")
    assert lead.test.passes
    assert lead.test.level == pytest.approx(ALPHA / (m * (m - 1)) / ROW_VIEWS)
    # the spring damping tested in round 2, against the model holding the backlash
    sd = next(c for c in inv.rounds[1] if c.effect == "spring_damping")
    assert sd.base and sd.base[0][0] == "backlash"
    assert failing_claims(finite_json(d.to_json())) == []
