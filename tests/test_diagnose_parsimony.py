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
    assert "t = 41.2 (an unphysical fit)" in note and note.endswith("the simpler, backlash, is named")
