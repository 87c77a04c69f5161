"""A spring damping tested on top of a named backlash searches the dead band's width again
beside it (identification.discrepancy.candidates._beside).

The case: the bench's arm6 axis 2 with velocity feedforward, without torque noise, a backlash
of half-width 0.296 mrad and a spring damping of 695 N m s/rad (visibilities 29 % and 21 %).
Fitted alone, the dead band comes out narrower than it is (the damping's torque at the
reversals reads as a spring torque), and the damping on top of that width left a hardening
engaged near the band, with a damping beside it, predicting the held-out rows better: the
hardening was named in the backlash's place. With the width searched again beside the
damping, both simulated effects are named, the width at its simulated value.
"""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import BenchRunner, Place
from jointbench.identification.output_values import finite_json

ARM6 = Place("bench", "arm6", "axis2", True)
BACKLASH = ("backlash", 0.000296, {})
DAMPING = ("spring_damping", 694.7, {})
SEED = 281212185


@pytest.fixture(scope="module")
def answer():
    log = BenchRunner(40.0).log(ARM6, (BACKLASH, DAMPING), SEED, True, False)
    return diagnose(log, forward=False)


def test_the_backlash_and_the_damping_are_named(answer):
    assert [c.effect for c in answer.causes] == ["backlash", "spring_damping"]
    assert all(c.test.passes for c in answer.causes)
    assert failing_claims(finite_json(answer.to_json())) == []


def test_the_width_is_searched_again_beside_the_damping(answer):
    """The width the damping's fit holds is the simulated one within 10 % (the grid's step
    is 4 % of it); the width the backlash was named with, fitted alone, is narrower."""
    b, d = answer.causes
    width = dict(d.base)["backlash"]["backlash_rad"]
    assert width == pytest.approx(0.000296, rel=0.10)
    assert b.fixed["backlash_rad"] < width
