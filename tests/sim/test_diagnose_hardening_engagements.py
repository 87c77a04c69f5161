"""A hardening beside a stronger torque ripple on a low-f1 axis (identification/discrepancy/
heldout.py, an engaging spring's units; lag_band.py, the unit of the hardening's view): the
independent simulator's soft family, whose mode the 40 s sweep passes in its first seconds,
with a ripple of 57 % visibility and a hardening of 23 % (drawn for this test as the battery
draws a pair: bench.campaign.battery, draw_strength and the strengths its search found). Only
a few segments reach the hardening's engagement: counted by segments, its t has few degrees of
freedom (in the wide band's view, 2.25 over 4 segments) and fails its bar. Counted by the
spring's engagements (a run of engaged instants each), it passes, and both are named."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.campaign.battery import Place, draw_strength
from jointbench.identification.discrepancy import diagnose_inverse
from jointbench.identification.discrepancy.heldout import SEGMENTS, evidence
from jointbench.identification.discrepancy.lag_band import LagBand, engaged, large_deflections
from jointbench.identification.discrepancy.candidates import candidate, reference

SEED = 1064514893
# (effect, strength) as the battery's search found them for their target visibilities
EFFECTS = (("hardening", 0.2801646248500593), ("torque_ripple", 8.526840263796522))


@pytest.fixture(scope="module")
def log():
    from jointbench.testing import IndepRunner
    runner = IndepRunner(40.0)
    place = Place("indep", "soft")
    tau_max, f1, K = runner.scales(place)
    effects = tuple((name, s, draw_strength(name, np.random.default_rng([SEED, k]), tau_max,
                                            f1, K)[1])
                    for k, (name, s) in enumerate(EFFECTS))
    return runner.log(place, effects, SEED, False, True)


def test_the_hardening_beside_a_ripple_is_named_over_its_engagements(log):
    settings = diagnosis_settings(log)[0]
    inv = diagnose_inverse(log, settings)
    assert {c.effect for c in inv.causes} == {"hardening", "torque_ripple"}
    h = next(c for c in inv.causes if c.effect == "hardening")
    test = h.test
    # named on the chooser's band's test over its engagements (heldout.engagement_units), at
    # half its level (the view at large deflections holds the other half)
    assert test.passes and "each engagement apart" in test.view and test.p < h.alpha / 2
    assert test.segments > SEGMENTS and test.heldout_pct > 50
    # the same rows counted by the segments that reach the engagement: too few to pass
    band = LagBand(log, settings)
    nom = band.nominal()
    ref = reference(nom, tuple((c.effect, c.fixed) for c in inv.causes if c is not h)
                    if h is not inv.causes[0] else ())
    w = candidate(nom, "hardening", ref)
    within = large_deflections(nom, w.fold_values)
    ev = evidence(w.reference_errors, w.heldout_errors, len(nom.sig.index), w.acts, within,
                  engaged(nom, w.fold_values))
    assert ev.segments == within.sum() <= 6
    assert ev.p > h.level            # the segments' test fails at the view's level
    assert test.segments > 2 * ev.segments and test.p < h.level
