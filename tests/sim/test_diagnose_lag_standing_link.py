"""A torque lag on the prototype is named alone: no dead band for the link that stands at
the end of the sweep (identification.discrepancy.candidates.beyond_limit, standing).

On the prototype (no feedforward, torque noise) with a current loop lagging by 14 ms, the
sweep ends far above the first mode and the axis stands for the last segments, motor and
link each on one encoder count, the link held by its friction against a spring deflected by
a few link-encoder counts. The nominal's friction law claims no torque there (tanh(0) = 0),
and the link equation keeps a constant misfit over each segment the link stands in. A dead
band just under that deflection removes it, and tested against the lag with the spring's
sign kept only where the deflection reverses, it passed its round with a width of a few
encoder counts: named beside the lag for the friction that holds a standing link. With the
spring's sign on the standing segments apart in the reference (one deflection there tells no
spring law), the band explains nothing beyond it."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import BenchRunner, Place
from jointbench.identification.discrepancy.candidates import standing
from jointbench.identification.discrepancy.heldout import segment_of_rows
from jointbench.identification.output_values import finite_json

PROTO = Place("bench", "prototype", None, True)
SEED = 1631458228
LAG = 0.0137

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def answer():
    log = BenchRunner(40.0).log(PROTO, (("torque_lag", LAG, {}),), SEED, False, True)
    return diagnose(log, forward=False)


def test_the_lag_alone_is_named(answer):
    assert [c.effect for c in answer.causes] == ["torque_lag"]
    assert failing_claims(finite_json(answer.to_json())) == []


def test_no_dead_band_passes_on_top_of_the_lag(answer):
    """The dead band tested on top of the lag fails its round's test."""
    later = [c for r in answer.inverse.rounds[1:] for c in r if c.effect == "backlash"]
    assert later and not any(c.significant for c in later)


def test_the_axis_stands_at_the_end(answer):
    """The last segment is one where the axis stands: each encoder within one count."""
    nom = answer.inverse.nominal
    still = standing(nom)
    seg = segment_of_rows(len(still))
    assert still[seg == seg[-1]].all() and not still.all()
