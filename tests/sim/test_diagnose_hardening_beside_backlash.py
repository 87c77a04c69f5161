"""A hardening beside a backlash, both named, each with its passing held-out test
(identification.discrepancy.candidates._test: a second cause of the spring law is tested over
the link equation too, the level split between the two sets of rows).

The case: the independent simulator's balanced family (f1 9 Hz, K 320 N m/rad), without
velocity feedforward, with torque noise, a backlash of half-width 3.02 mrad and a hardening
of ratio 0.274 engaged at 7.93 mrad. The backlash, named first, removes nearly nine tenths of
the nominal's held-out residual. What the hardening leaves is in the link equation (seven
tenths of its held-out residual there), while summed over both equations at the nominal's
block weights it is a few % of the residual, most of which is the motor torque's noise:
over every row its test fails, over the link equation it passes."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import Place
from jointbench.bench.campaign.visibility import visibility
from jointbench.identification.discrepancy.candidates import OWN_ROWS
from jointbench.identification.output_values import finite_json
from jointbench.testing import IndepRunner

BALANCED = Place("indep", "balanced")
BACKLASH = ("backlash", 0.00302, {})
HARDENING = ("hardening", 0.274, {"deflection": 0.00793})
SEED = 139084531
FEEDFORWARD = False


@pytest.fixture(scope="module")
def runner():
    return IndepRunner(40.0)


@pytest.fixture(scope="module")
def answer(runner):
    return diagnose(runner.log(BALANCED, (BACKLASH, HARDENING), SEED, FEEDFORWARD, True))


def test_both_effects_are_visible(runner):
    """Each effect alone changes the in-band motor torque by more than 15 % (the battery's
    visibility, noise-free runs of the same seed)."""
    _, f1, _ = runner.scales(BALANCED)
    clean = runner.log(BALANCED, (), SEED, FEEDFORWARD, False).tau_m
    for effect in (BACKLASH, HARDENING):
        tau = runner.log(BALANCED, (effect,), SEED, FEEDFORWARD, False).tau_m
        assert visibility(clean, tau, f1, runner.rate_hz) > 0.15, effect[0]


def test_the_hardening_is_named_beside_the_backlash(answer):
    assert [c.effect for c in answer.causes] == ["backlash", "hardening"]
    assert all(c.test.passes for c in answer.causes)
    doc = finite_json(answer.to_json())
    assert failing_claims(doc) == []
    assert [c["effect"] for c in doc["causes"]] == ["backlash", "hardening"]


def test_its_test_is_over_the_link_equation_at_a_split_level(answer):
    """The hardening's claim rests on the link equation's rows, at half its round's level or
    less (the two sets of rows split it, and the wide band's view), and there it removes
    more than half of the held-out residual; over every row, a few %."""
    h = answer.causes[1]
    assert h.test.view.endswith(OWN_ROWS)
    assert h.test.level <= h.alpha / 2
    assert h.test.acts_pct > 50 > 10 > h.test.heldout_pct > 0


def test_the_hardening_is_found_beyond_the_dead_band(answer):
    """The hardening's engagement and ratio within a quarter and a half of the simulated
    7.93 mrad and 0.274 (its grid's step and the dead band's width share the kink), beyond
    the backlash's half-width as simulated."""
    b, h = answer.causes
    assert h.parameters["deflection_rad"] == pytest.approx(0.00793, rel=0.25)
    assert h.parameters["hardening_ratio"] == pytest.approx(0.274, rel=0.5)
    assert h.parameters["deflection_rad"] > b.parameters["backlash_rad"]
