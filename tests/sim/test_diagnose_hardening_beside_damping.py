"""A hardening beside a spring damping on the pendulum, with a noisy motor torque, is tested
over the link equation too (identification.discrepancy.candidates._test, second_of_spring).

The independent simulator's pendulum family, with velocity feedforward and noise: a spring
damping D (qm' - q'), the stronger, and a second spring of ratio RATIO engaged beyond
ENGAGEMENT. The damping is named first. Both act in the spring, the torque the homogeneous
link equation holds as its whole right-hand side; the hardening's torque stands in the motor
equation too, beside the measured motor torque and its noise. Over both equations the
hardening's held-out share is a few % and its segment test reads that noise; over the link
equation alone, where the damping's residual is what the spring law still misses, it
removes most of the held-out residual. Tested over both sets of rows, each at half its
level, it is named beside the damping, and its engagement is the hidden one. A dead band of
a fraction of a mrad, tested over the link equation as well, passes in the same round; the
choice between the two reads the link equation too, where the hardening explains more, and
the hardening is named, not the dead band."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.campaign.battery import Place
from jointbench.identification.band_choice import CONSISTENCY_Z
from jointbench.identification.discrepancy import nominal
from jointbench.identification.discrepancy.candidates import OWN_ROWS, candidate, reference
from jointbench.identification.discrepancy.heldout import evidence
from jointbench.identification.discrepancy.lag_band import grid_step, jackknife
from jointbench.identification.discrepancy.nominal import with_link_law
from jointbench.identification.output_values import finite_json
from jointbench.testing import IndepRunner

PENDULUM = Place("indep", "pendulum", gravity=True)
RATIO, ENGAGEMENT, D = 0.05, 0.025, 3.5
SEED = 51203
M = 7   # the effects a second round tests

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def log():
    return IndepRunner(30.0).log(PENDULUM, (("hardening", RATIO, {"deflection": ENGAGEMENT}),
                                            ("spring_damping", D, {})), SEED, True, True)


@pytest.fixture(scope="module")
def on_top(log):
    """The hardening tested against the model holding the spring damping (the second
    round's reference, with the link friction's law searched beside the damping)."""
    nom = nominal(log, diagnosis_settings(log)[0])
    model = (("spring_damping", {}),)
    nom = with_link_law(nom, reference(nom, model, m=M).base.design())
    return nom, candidate(nom, "hardening", reference(nom, model, m=M))


def test_the_link_equation_carries_it(on_top):
    """Over both equations the test fails at its level; over the link equation it passes."""
    nom, c = on_top
    n = len(nom.sig.index)
    both = evidence(c.reference_errors, c.heldout_errors, n, c.acts)
    link = evidence(c.reference_errors, c.heldout_errors, n, (1,))
    assert c.acts == (0, 1)
    assert both.p > c.level          # what a test over every row it acts in reads
    assert link.p < c.level
    assert c.rows == OWN_ROWS and c.significant


def test_the_engagement_and_ratio_are_the_hidden_ones(on_top):
    """The engagement within what the log tells apart (CONSISTENCY_Z jackknife spreads of the
    folds' values plus the search grid's step there), the ratio Kh / K within three of its
    folds' jackknife spreads."""
    nom, c = on_top
    value = c.fixed["deflection_rad"]
    allowed = CONSISTENCY_Z * jackknife(c.fold_values) + grid_step(nom, value)
    assert abs(value - ENGAGEMENT) <= allowed
    ratios = [f["Kh"] / f["K"] for f in c.fold_fits]
    spread = jackknife(tuple(ratios))
    assert abs(c.parameters["hardening_ratio"] - RATIO) <= CONSISTENCY_Z * spread


def test_damping_and_hardening_named(log):
    """The whole diagnosis (its inverse view): the damping, then the hardening, each with a
    passing test, and no dead band."""
    answer = diagnose(log, forward=False)
    assert [c.effect for c in answer.causes] == ["spring_damping", "hardening"]
    assert failing_claims(finite_json(answer.to_json())) == []
