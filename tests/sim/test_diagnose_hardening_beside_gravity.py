"""A hardening beside a gravity load on the pendulum is named beside the gravity, without an
offset or an asymmetric friction (identification.discrepancy.candidates.beyond_limit,
reversing).

The independent simulator's pendulum family, without velocity feedforward, quiet: a second
spring of 0.12 K engaged beyond 17 mrad, and the gravity's rest 60 mrad away from where the
nominal puts it. The sweep passes the mode in its first seconds; after them the link rests on
its spring against gravity, the deflection held on one side. The nominal's K, fitted where
the stiffer spring acts, is too stiff at that static deflection, and the motor equation keeps
a constant misfit over most of the log: the hardening's own image, which a stiffness that
rises at large deflections removes. The spring's sign s(qm - q) is a constant on those rows;
kept there in the reference the hardening is weighed against, it took that image up, the
hardening failed its round, and an asymmetric friction (an offset while the motor stands)
was named for it."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import Place
from jointbench.identification.band_choice import CONSISTENCY_Z
from jointbench.identification.discrepancy.candidates import reversing
from jointbench.identification.discrepancy.lag_band import grid_step, jackknife
from jointbench.identification.output_values import finite_json
from jointbench.testing import IndepRunner

PENDULUM = Place("indep", "pendulum", gravity=True)
RATIO, ENGAGEMENT, REST = 0.12, 0.017, -0.06
SEED = 190016424

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def log():
    return IndepRunner(40.0).log(PENDULUM, (("hardening", RATIO, {"deflection": ENGAGEMENT}),
                                            ("gravity", REST, {})), SEED, False, False)


@pytest.fixture(scope="module")
def answer(log):
    return diagnose(log, forward=False)


def test_gravity_and_hardening_named(answer):
    named = [c.effect for c in answer.causes]
    assert sorted(named) == ["gravity", "hardening"]
    assert failing_claims(finite_json(answer.to_json())) == []


def test_the_engagement_is_the_hidden_one(answer):
    """The engagement within what the log tells apart (lag_band's agreement of two bands):
    CONSISTENCY_Z jackknife spreads of the folds' values plus the search grid's step there;
    the spring's K is the hidden one, closer to it than to the K + Kh that a K taking up the
    second spring would be."""
    c = next(c for c in answer.causes if c.effect == "hardening")
    value = c.parameters["deflection_rad"]
    nom = answer.inverse.nominal
    allowed = CONSISTENCY_Z * jackknife(c.fold_values) + grid_step(nom, value)
    assert abs(value - ENGAGEMENT) <= allowed
    assert c.parameters["hardening_ratio"] > 0
    assert c.parameters["K"] == pytest.approx(float(answer.log.meta["truth_K"]), rel=RATIO / 2)


def test_the_spring_reverses_only_at_the_mode(answer):
    """The spring's sign reverses in the segments of the mode only: most of the log holds
    the deflection on the gravity's side, where the limit column is zero."""
    on = reversing(answer.inverse.nominal)
    assert 0 < on.mean() < 0.5
