"""A backlash beside a spring damping on a stiff axis (identification.discrepancy.masked: the
partner): both named, the width found on top of the damping.

On the prototype (no feedforward, torque noise) with a backlash of half-width 5 mrad and a
spring damping of 3500 N m s/rad, the damper D (qm' - q') carries torque inside the dead
band, where a dead band alone carries none: the backlash's width searched against the
nominal ends at 0, where its column is the nominal spring's and it explains nothing, and the
damping alone fails its round's test. The masked pair's partner is the candidate that
explains the most on top of the best one, its value searched there: the backlash on top of
the damping finds its width, and each passes on top of the other at the ordered pairs'
level."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import BenchRunner, Place
from jointbench.identification.discrepancy.candidates import ROW_VIEWS
from jointbench.identification.discrepancy.heldout import ALPHA
from jointbench.identification.band_choice import CONSISTENCY_Z
from jointbench.identification.discrepancy.lag_band import jackknife
from jointbench.identification.effects import backlash
from jointbench.identification.output_values import finite_json

PROTO = Place("bench", "prototype", None, True)
SEED = 10227
WIDTH, DAMPING = 0.005, 3500.0


@pytest.fixture(scope="module")
def pair():
    log = BenchRunner(40.0).log(PROTO, (("backlash", WIDTH, {}),
                                        ("spring_damping", DAMPING, {})), SEED, False, True)
    return diagnose(log)


@pytest.mark.slow
def test_alone_the_width_search_ends_at_the_nominal_spring(pair):
    alone = {c.effect: c for c in pair.inverse.rounds[0]}
    assert alone["backlash"].fixed["backlash_rad"] == 0.0
    assert not alone["backlash"].significant and not alone["spring_damping"].significant


@pytest.mark.slow
def test_both_are_named_each_on_top_of_the_other(pair):
    assert {c.effect for c in pair.causes} == {"backlash", "spring_damping"}
    mp = pair.inverse.masked
    assert {mp.first, mp.second} == {"backlash", "spring_damping"} and mp.named
    m = len([c for c in pair.inverse.candidates if c.testable])
    # the ordered pairs' level; the backlash on top of the damping, a second cause of the
    # spring, is tested over the link equation too, each of its two views at half of it
    # (candidates._test)
    level = {"backlash": ALPHA / (m * (m - 1)) / ROW_VIEWS,
             "spring_damping": ALPHA / (m * (m - 1))}
    for t, name in ((mp.second_on_first, mp.second), (mp.first_on_second, mp.first)):
        assert t.passes and t.level == pytest.approx(level[name])
    assert failing_claims(finite_json(pair.to_json())) == []


@pytest.mark.slow
def test_the_width_is_the_hidden_one(pair):
    """Within CONSISTENCY_Z jackknife spreads of the ten folds' widths plus the width grid's
    step there (what a search on that grid can tell apart)."""
    b = next(c for c in pair.causes if c.effect == "backlash")
    width = b.parameters["backlash_rad"]
    spread = jackknife(b.fold_values)
    step = backlash.grid_step(pair.inverse.nominal, width)
    assert abs(width - WIDTH) <= CONSISTENCY_Z * spread + step
