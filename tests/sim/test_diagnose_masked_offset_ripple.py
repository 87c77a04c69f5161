"""An offset and a torque ripple that pass only together (identification.discrepancy.masked):
both named, each with its own passing test on top of the other.

On the prototype (velocity feedforward, torque noise) with a constant torque of 150 N m and a
ripple of 200 N m (about a third and a quarter of the in-band torque), the motor rests for
the last quarter of the log. There the residual is the offset plus the ripple frozen at the
resting angle: against the nominal (no ripple) the offset loses in those segments and wins in
the others, and the ripple tested without the offset fails the same way; no round names
either. The two best candidates alone are an asymmetric friction and the offset it reduces to
(while the motor moves its Coulomb part is the offset's constant): the masked pair leaves the
asymmetry out and tries offset and ripple, which pass together and each on top of the other
at the ordered pairs' level. Both are named, with those tests in JSON and in the text; the
asymmetry is listed as not named, with why. The ripple alone and a clean log of the same
draw name the ripple and nothing."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.analysis.diagnose.report import summary_text
from jointbench.bench.campaign.battery import BenchRunner, Place
from jointbench.identification.discrepancy.heldout import ALPHA
from jointbench.identification.output_values import finite_json

PROTO = Place("bench", "prototype", None, True)
SEED = 9601112
OFFSET, RIPPLE = 150.0, 200.0


@pytest.fixture(scope="module")
def runner():
    return BenchRunner(40.0)


@pytest.fixture(scope="module")
def pair(runner):
    log = runner.log(PROTO, (("offset", OFFSET, {}), ("torque_ripple", RIPPLE, {})), SEED,
                     True, True)
    return diagnose(log)


def test_both_named_each_with_its_passing_test(pair):
    assert pair.verdict == "named"
    assert {c.effect for c in pair.causes} == {"offset", "torque_ripple"}
    doc = finite_json(pair.to_json())
    assert failing_claims(doc) == []
    m = len([c for c in pair.inverse.candidates if c.testable])
    level = ALPHA / (m * (m - 1))   # the ordered pairs' Bonferroni level
    for c in doc["causes"]:
        other = ({"offset", "torque_ripple"} - {c["effect"]}).pop()
        assert c["after"] == [other]            # tested on top of the other
        t = c["test"]
        assert t["view"] == f"the masked pair, on top of {other}"
        assert t["passes"] and t["heldout_pct"] > 0 and t["p_heldout"] < t["alpha"]
        assert t["alpha"] == pytest.approx(level)
        assert (c["t"], c["p_heldout"], c["heldout_pct"]) == (t["t"], t["p_heldout"],
                                                                t["heldout_pct"])
    # no round named either alone: the first round's tests of both fail
    alone = {c["effect"]: c for c in doc["candidates"] if c["testable"]}
    assert not alone["offset"]["significant"] and not alone["torque_ripple"]["significant"]
    mp = doc["masked_pair"]
    assert mp["named"] and {mp["first"], mp["second"]} == {"offset", "torque_ripple"}
    assert [s["effect"] for s in mp["skipped"]] == ["asymmetric_friction"]


def test_the_values_are_the_hidden_torques(pair):
    """Each names its own torque: the offset and the ripple's amplitude within 20 % of the
    hidden ones (a check of what is named, not a precision figure; the drive chain's
    Coulomb friction takes up part of a constant while the motor moves)."""
    p = pair.extended_parameters
    assert abs(p["offset"]) == pytest.approx(OFFSET, rel=0.2)
    assert p["ripple_amplitude"] == pytest.approx(RIPPLE, rel=0.2)


def test_text_gives_each_test_and_what_was_not_named(pair):
    text = summary_text(pair)
    for c in pair.causes:
        assert f"t = {c.test.t:.3g}" in text and f"p = {c.test.p:.2g}" in text
        assert f"{c.test.view}: held out it explains {c.test.heldout_pct:.3g} %" in text
    asym = [n for n in pair.not_named if n.effect == "asymmetric_friction"]
    assert asym and "reduces to offset" in asym[0].why


def test_ripple_alone_and_clean_name_no_extra(runner):
    d = diagnose(runner.log(PROTO, (("torque_ripple", RIPPLE, {}),), SEED, True, True))
    assert [c.effect for c in d.causes] == ["torque_ripple"]
    clean = diagnose(runner.log(PROTO, (), SEED, True, True))
    assert clean.causes == () and clean.verdict == "none"


def test_clipped_split_keeps_both_or_neither(pair):
    """On a clipped log's every-row view each test is at 1/VIEWS of its level
    (bench.analysis.diagnose.clipped.split_level): the pair's two, each tested on top of the
    other, are named together or not at all; one alone would carry a test against a model
    holding a cause not named."""
    from dataclasses import replace

    from jointbench.bench.analysis.diagnose.clipped import split_level

    inv = pair.inverse
    assert [c.effect for c in split_level(inv).causes] == [c.effect for c in inv.causes]
    weak = replace(inv, causes=(inv.causes[0], replace(inv.causes[1], p_heldout=0.5)))
    out = split_level(weak)
    assert out.causes == ()
    assert {n.effect for n in out.not_named} >= {"offset", "torque_ripple"}
