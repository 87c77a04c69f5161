"""The parsimony rule's materiality exception (identification.discrepancy.inverse._material):
a richer candidate goes first, although what it adds to a simpler one fails the segment test,
when it removes more than MATERIAL (5 %) of what the simpler leaves held out and its fit on
top of the simpler is physical. Shares from the seed-7 development battery (docs/effects.md)."""

from __future__ import annotations

import pytest

from jointbench.identification.discrepancy import Candidate
from jointbench.identification.discrepancy.heldout import MATERIAL
from jointbench.identification.discrepancy.inverse import _apart, _material, beyond


def _c(effect, share):
    return Candidate(effect=effect, testable=True, heldout_pct=share)


def test_beyond_is_the_share_of_what_the_simpler_leaves():
    # 1 - (1 - 0.579) / (1 - 0.352): the hardening beside the soft family's asymmetry
    assert beyond(_c("hardening", 57.9), _c("backlash", 35.2)) == pytest.approx(0.35031, abs=1e-5)
    assert beyond(_c("backlash", 35.2), _c("hardening", 57.9)) < 0
    assert beyond(_c("hardening", 50.0), _c("backlash", 100.0)) == 0.0


def test_material_only_beyond_the_margin_and_for_a_physical_fit():
    hard, back = _c("hardening", 57.9), _c("backlash", 35.2)
    assert _material(hard, back, physical=True)
    assert not _material(hard, back, physical=False)
    # an asymmetry 2.5 points over an offset (balanced family): 4.4 % of what it leaves
    asym, off = _c("asymmetric_friction", 45.3), _c("offset", 42.8)
    assert beyond(asym, off) == pytest.approx(0.0437, abs=1e-4) and beyond(asym, off) < MATERIAL
    assert not _material(asym, off, physical=True)


def test_the_note_says_which_is_named_and_why():
    hard, back = _c("hardening", 57.9), _c("backlash", 35.2)
    note = _apart(back, hard, 0.0919, 1.25e-4, more=True)
    assert note.startswith("backlash or hardening: this log cannot tell them apart")
    assert note.endswith("hardening, which removes 35 % of what backlash leaves, is named")
    note = _apart(back, hard, 41.2, 1.25e-4, unphysical=True)
    assert "t = 41.2 (an unphysical fit)" in note
    assert note.startswith("one of backlash or hardening: this log cannot tell them apart")
    assert note.endswith("the simpler, backlash, is named for the two")


def _established(effect, share):
    # significant at a first round's level (8 effects: 1.25e-4)
    return Candidate(effect=effect, testable=True, heldout_pct=share, t_stat=9.0,
                     p_heldout=1e-9, alpha=1.25e-4)


@pytest.mark.parametrize("t_asym,t_offset,named,note", [
    (3.67, 1.14, "asymmetric_friction", ""),      # its viscous part passes, the offset's not
    (1.26, 3.61, "offset", ""),                   # the offset's own part passes
    (-0.40, 0.20, "offset", "cannot tell them apart"),   # neither: the simpler, stated
    (2.50, 2.50, "offset", "carries a part of each"),   # both: stated, the asymmetry
    #                                                     tested again in the next round
    (5.00, 2.50, "asymmetric_friction", ""),      # its part passes the round's own level
])
def test_offset_or_asymmetry_is_a_two_way_choice_at_its_own_level(monkeypatch, t_asym,
                                                                   t_offset, named, note):
    """inverse._which: once one of the two is established, the asymmetric friction is named
    when what it adds to the offset passes at DECIDE (one-sided 5 %: t > 1.71 on the 26
    degrees of freedom of 40 segments) and what the offset adds to it does not; the same
    answer whichever of the two explains more (ranked first). _on_top is replaced by the
    t values given (from the seed-2026 battery's misses, docs/effects.md)."""
    from scipy import stats

    from jointbench.identification.discrepancy import inverse
    from jointbench.identification.discrepancy.heldout import SEGMENTS, dof, t_bar

    assert t_bar(inverse.DECIDE) == pytest.approx(1.706, abs=1e-3)
    given = {"asymmetric_friction": t_asym, "offset": t_offset}

    def on_top(nom, richer, simpler, m):
        return given[richer.effect], float(stats.t.sf(given[richer.effect], dof(SEGMENTS))), True

    monkeypatch.setattr(inverse, "_on_top", on_top)
    off, asym = _established("offset", 40.0), _established("asymmetric_friction", 40.2)
    for ranked in ([off, asym], [asym, off]):
        order, why, alt = inverse._simplest_first(list(ranked), None, 8)
        assert order[0].effect == named and (note in why if note else why == "")
        # the log cannot choose: one of the two, the other the named one's alternative
        cannot = note == "cannot tell them apart"
        assert why.startswith("one of offset or asymmetric_friction: ") is cannot
        assert (alt is not None) is cannot
        if cannot:
            assert (alt.named, alt.other, alt.how) == ("offset", "asymmetric_friction",
                                                       "nested")
            assert (alt.named_pct, alt.other_pct) == (40.0, 40.2) and alt.describe() == why
            assert (alt.t, alt.t_back) == (t_offset, t_asym)
    if note:
        assert "the bar t > 1.71" in why and "the simpler, offset, is named" in why
    # an asymmetry that is not significant on its own is never named for an established offset
    weak = Candidate(effect="asymmetric_friction", testable=True, heldout_pct=40.2,
                     p_heldout=0.01, alpha=1.25e-4)
    assert inverse._simplest_first([off, weak], None, 8)[0][0].effect == "offset"
