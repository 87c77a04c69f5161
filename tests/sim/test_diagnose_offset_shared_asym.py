"""An offset beside an asymmetric friction whose motor never rests (identification.
discrepancy.inverse._shared).

On arm6's axis 4 (motor friction FVm = 1.5 N m s/rad, FSm = 4 N m) a constant torque of
2.5 N m beside an asymmetric friction a = -0.9 ((1 + a sign qm') on the motor friction),
no feedforward, torque noise on. While the motor moves the asymmetry's Coulomb part a FSm is
a constant torque, and the filtered motor speed is never exactly 0 on this log: the offset's
column lies in the span of the asymmetry's two parts (|qm'|, |sign qm'|) on every row, so the
log cannot say whether the constant it carries is that Coulomb part or an offset. The
asymmetry's viscous part is what is named; the offset, which passes its own test against the
nominal, must be stated beside it as "one of asymmetric_friction or offset", not left out
silently."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import BENCH_PLACES, BenchRunner
from jointbench.identification.discrepancy import inverse
from jointbench.identification.output_values import finite_json

OFFSET = 2.5        # [N m]
ASYMMETRY = -0.9    # (1 + a sign qm') on FVm = 1.5 N m s/rad, FSm = 4 N m
FSM = 4.0


@pytest.fixture(scope="module")
def answer():
    axis4 = next(p for p in BENCH_PLACES if p.joint == "axis4")
    log = BenchRunner(40.0).log(axis4, (("asymmetric_friction", ASYMMETRY, {}),
                                        ("offset", OFFSET, {})), 10281, False, True)
    return diagnose(log)


@pytest.mark.slow
def test_the_offset_is_stated_beside_the_asymmetry(answer):
    named = [c.effect for c in answer.causes]
    assert "asymmetric_friction" in named
    if "offset" in named:   # both named: nothing is left to state
        return
    alts = answer.alternatives_of("asymmetric_friction")
    shared = [a for a in alts if a.other == "offset"]
    assert shared, [a.describe() for a in alts]
    doc = finite_json(answer.to_json())
    assert failing_claims(doc) == []
    offset = next(n for n in doc["not_named"] if n["effect"] == "offset")
    assert offset["kind"] == "alternative"
    entry = next(c for c in doc["causes"] if c["effect"] == "asymmetric_friction")
    assert any(a["effect"] == "offset" for a in entry["alternatives"])


@pytest.mark.slow
def test_no_row_tells_the_offset_from_the_coulomb_part(answer):
    """The offset's information beside the asymmetry's parts is nil on a log whose motor
    never rests (the Cramer-Rao t is exactly 0: rank), and the constant the asymmetry carries
    is the sum of the two, c + a FSm, within its Coulomb part's own size (the share the
    split between the viscous and Coulomb parts can move)."""
    assert inverse._apart_t(answer.inverse.nominal, "asymmetric_friction", "offset") == 0.0
    p = answer.extended_parameters
    constant = p.get("offset", 0.0) + p["coulomb_asymmetry"] * FSM
    assert abs(constant - (OFFSET + ASYMMETRY * FSM)) < abs(ASYMMETRY) * FSM
