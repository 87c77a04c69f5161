"""The battery by visibility's plan (bench.campaign.battery.plan: which place, condition and
target each case gets) and its strength search's stop where the visibility stops growing
(bench.campaign.visibility.strength_for), on fake visibility laws with known answers."""

from __future__ import annotations

import math
from collections import Counter

import pytest

from jointbench.bench.campaign.battery import (BATTERY_EFFECTS, BENCH_PLACES, CONDITIONS,
                                               plan)
from jointbench.bench.campaign.visibility import (PLATEAU_SHARE, SATURATION_SLOPE,
                                                  SEARCH_EVALUATIONS, strength_for)
from jointbench.testing import INDEP_PLACES, LAB_PLACES

PLACES = (*BENCH_PLACES, *INDEP_PLACES, *LAB_PLACES)


@pytest.mark.parametrize("sizes", [(8, 24, 28), (2, 4, 4), (8, 24, 20), (5, 9, 13)])
def test_every_place_and_every_effect_sees_every_condition(sizes):
    """Each place with at least four cases, and each effect with at least four single-effect
    cases, runs under all four (feedforward, noise) conditions; the clean cases and the
    pairs too. (A plan that cycles four conditions over eight places gives each place one.)"""
    per_effect, clean, pairs = sizes
    specs = plan(PLACES, per_effect, clean, pairs, 2612)
    at = Counter(s.place for s in specs)
    for place, n in at.items():
        seen = {(s.feedforward, s.noise) for s in specs if s.place == place}
        assert n < 4 or seen == set(CONDITIONS), place.label
    for name in BATTERY_EFFECTS:
        seen = {(s.feedforward, s.noise) for s in specs if s.effects == (name,)}
        assert per_effect < 4 or seen == set(CONDITIONS), name
    for kind, n in (("clean", clean), ("pair", pairs)):
        seen = {(s.feedforward, s.noise) for s in specs if s.kind == kind}
        assert n < 4 or seen == set(CONDITIONS), kind


def test_the_lab_rig_sees_every_condition_in_the_default_plan():
    lab = [s for s in plan(PLACES, 8, 24, 28, 2612) if s.place in LAB_PLACES]
    assert Counter((s.feedforward, s.noise) for s in lab).keys() == set(CONDITIONS)


def test_the_plan_is_a_pure_function_of_its_seed():
    """Same arguments, the same plan; another seed changes the draw (case seeds, targets, the
    pairs' effects), not where a case runs nor its condition."""
    a, b = plan(PLACES, 8, 24, 28, 77), plan(PLACES, 8, 24, 28, 77)
    assert a == b
    c = plan(PLACES, 8, 24, 28, 78)
    assert [s.seed for s in a] != [s.seed for s in c]
    assert [s.targets for s in a] != [s.targets for s in c]
    assert [(s.place, s.feedforward, s.noise) for s in a] == \
        [(s.place, s.feedforward, s.noise) for s in c]


# ---- the strength search ----

def _counted(law):
    calls = []

    def vis(s):
        calls.append(s)
        return law(s)
    return vis, calls


def test_search_stops_where_the_visibility_saturates():
    """visibility = 0.025 (1 - exp(-s / 0.05)) never exceeds 2.5 %: asked for 20 %, the search
    stops once a step of the strength leaves the visibility nearly unchanged, flags the
    target out of reach and keeps the visibility reached (within 5 % of the ceiling)."""
    vis, calls = _counted(lambda s: 0.025 * (1.0 - math.exp(-abs(s) / 0.05)))
    found = strength_for(0.20, vis, 0.015)
    assert found.saturated and not found.hit(0.20)
    # the case keeps the start of the plateau: the smallest strength tried within
    # PLATEAU_SHARE of the largest visibility reached (the ceiling, 2.5 %)
    top = max(v for _, v in found.tried)
    assert top == pytest.approx(0.025, rel=0.05)
    assert found.visibility >= PLATEAU_SHARE * top
    assert abs(found.strength) == min(abs(s) for s, v in found.tried if v >= PLATEAU_SHARE * top)
    assert len(calls) < SEARCH_EVALUATIONS
    assert max(abs(s) for s in calls) < 100.0        # no search on to a huge strength
    # the last step's growth is below the stopping slope
    (s0, v0), (s1, v1) = found.tried[-2:]
    assert math.log(v1 / v0) / math.log(abs(s1 / s0)) < SATURATION_SLOPE


def test_search_on_a_reachable_law_is_not_flagged():
    """A power law with a slope under the clipped range still reaches its target, unflagged;
    an effect not yet engaged at the start (visibility 0) is not taken as saturated."""
    found = strength_for(0.25, lambda s: 0.05 * abs(s) ** 0.5, 1.0)
    assert found.hit(0.25) and not found.saturated
    engaged = strength_for(0.1, lambda s: max(0.0, 0.02 * (abs(s) - 2.0)), 1.0)
    assert engaged.hit(0.1) and not engaged.saturated


def test_search_at_the_largest_strength_below_the_target_is_flagged():
    """A law that would reach the target only beyond `largest`: the search stops at the
    bound, flagged, with the visibility there."""
    found = strength_for(0.3, lambda s: 0.001 * abs(s), 1.0, largest=100.0)
    assert found.saturated and abs(found.strength) <= 100.0
    assert found.visibility == pytest.approx(0.001 * abs(found.strength))
