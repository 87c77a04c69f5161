"""A link at rest held by its static friction is no evidence of gravity's rest
(identification.effects.gravity.free).

On the independent simulator's pendulum (gravity in the nominal, its rest at the start) with a
backlash of 7.3 mrad alone (no feedforward, torque noise): above the mode the motor rattles
inside the dead band while the link rests, held by friction at some angle q*, and the
friction law (0 at zero speed) leaves P g sin(q* - qs) as a constant in the link equation.
Against the model holding the backlash, Q g cos(q - qs) is that constant over the few mrad
the link moves; with those rows out of gravity's column, gravity adds nothing and is not
named beside the backlash. A gravity whose rest is away from the start loads the link
wherever the spring reads it, and stays named."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import Place
from jointbench.identification.discrepancy.candidates import candidate, reference
from jointbench.identification.discrepancy.nominal import with_link_law
from jointbench.identification.discrepancy.stacked import _Rows
from jointbench.identification.effects.gravity import free
from jointbench.identification.output_values import finite_json
from jointbench.testing import IndepRunner

PENDULUM = Place("indep", "pendulum", gravity=True)


@pytest.fixture(scope="module")
def runner():
    return IndepRunner(40.0)


@pytest.fixture(scope="module")
def backlash(runner):
    log = runner.log(PENDULUM, (("backlash", 0.0073435, {}),), 9302001, False, True)
    return diagnose(log)


def test_backlash_alone_named_not_gravity(backlash):
    assert [c.effect for c in backlash.causes] == ["backlash"]
    doc = finite_json(backlash.to_json())
    assert failing_claims(doc) == []
    assert "gravity" in {n["effect"] for n in doc["not_named"]}


def test_gravity_adds_nothing_on_top_of_the_backlash(backlash):
    """Against the model holding the backlash (its law searched again, as a later round
    has it), gravity's held-out share is not positive; the rows it leaves out are the link's
    rest inside the dead band, most of the sweep's top."""
    inv = backlash.inverse
    nom = inv.nominal
    b = inv.causes[0]
    model = (("backlash", b.fixed),)
    nom = with_link_law(nom, reference(nom, model).base.design())
    ref = reference(nom, model)
    g = candidate(nom, "gravity", ref)
    assert not g.significant
    assert g.heldout_pct < 1.0   # per cent of the held-out residual
    held = free(_Rows(ref.base)) == 0
    assert 0.3 < held.mean() < 1.0   # the link rests in the dead band for much of the log
    # and only where the spring transmits nothing
    d = ref.base.deflection
    assert np.all(d[held] == 0)


def test_gravity_away_from_the_start_still_named(runner):
    """A rest 31 mrad from the start (visibility 8 %, feedforward, no torque noise)."""
    log = runner.log(PENDULUM, (("gravity", -0.0313759, {}),), 9303004, True, False)
    d = diagnose(log)
    assert [c.effect for c in d.causes] == ["gravity"]
    assert failing_claims(finite_json(d.to_json())) == []
