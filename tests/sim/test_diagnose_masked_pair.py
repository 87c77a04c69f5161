"""Two effects that mask each other (identification.discrepancy.masked): no silence.

On the independent simulator's soft family, a backlash of 10.9 mrad and a spring damping of
18.1 N m s/rad (about a third of the in-band torque each, no feedforward, torque noise): both
shape the link equation in the segments where the sweep passes the mode, and there each
one's misfit hides what the other removes. Alone neither passes its round's test; fitted
together they explain about half of the held-out residual, and the backlash passes on top
of the spring damping at the level of the ordered pairs. The answer is "inconclusive", with
the pair's share and its tests; a clean log of the family stays "none"."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import Place
from jointbench.identification.discrepancy.candidates import ROW_VIEWS
from jointbench.identification.discrepancy.heldout import ALPHA
from jointbench.identification.output_values import finite_json
from jointbench.testing import IndepRunner

SOFT = Place("indep", "soft")


@pytest.fixture(scope="module")
def runner():
    return IndepRunner(40.0)


@pytest.fixture(scope="module")
def pair(runner):
    log = runner.log(SOFT, (("backlash", 0.0109044, {}), ("spring_damping", 18.1181, {})),
                     9301001, False, True)
    return diagnose(log)


def test_the_pair_is_inconclusive_not_none(pair):
    assert pair.causes == ()
    assert pair.verdict == "inconclusive"
    doc = finite_json(pair.to_json())
    assert failing_claims(doc) == []
    m = doc["masked_pair"]
    assert {m["first"], m["second"]} == {"backlash", "spring_damping"}
    assert m["passes"]
    # the pair explains a large share of the held-out residual (each effect alone about a
    # third of the in-band torque), more than either alone
    alone = {c["effect"]: c["heldout_pct"] for c in doc["candidates"] if c["testable"]}
    assert m["pair"]["heldout_pct"] > max(alone["backlash"], alone["spring_damping"]) + 10
    assert "backlash" in doc["reason"] and "spring_damping" in doc["reason"]


def test_the_tests_are_at_the_pairs_levels(pair):
    """Bonferroni over the m (m - 1) ordered pairs of the m effects tested, and over the
    unordered pairs for the pair's own test; a passing test is one under its level. The
    backlash on top of the damping, a second cause of the spring, is tested over the link
    equation too, each of its two sets of rows at half its level (candidates._test)."""
    m = len([c for c in pair.inverse.candidates if c.testable])
    mp = pair.inverse.masked
    rows = {"backlash": ROW_VIEWS, "spring_damping": 1}
    for t, name in ((mp.second_on_first, mp.second), (mp.first_on_second, mp.first)):
        assert t.level == pytest.approx(ALPHA / (m * (m - 1)) / rows[name])
        assert t.passes == (t.heldout_pct > 0 and t.p < t.level)
    assert mp.pair.level == pytest.approx(2 * ALPHA / (m * (m - 1)))
    assert any(t.passes for t in (mp.pair, mp.second_on_first, mp.first_on_second))


def test_clean_log_stays_none(runner):
    d = diagnose(runner.log(SOFT, (), 9301013, False, True))
    assert d.causes == ()
    assert d.verdict == "none"
