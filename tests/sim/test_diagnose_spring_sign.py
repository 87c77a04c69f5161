"""A torque ripple and an offset on a soft-geared axis name no spring law beside them
(identification.effects.base.spring_sign, identification.discrepancy.candidates.
beyond_limit).

The independent simulator's balanced family, without velocity feedforward, with torque noise:
a ripple of 2 N m and a constant torque of 0.8 N m on the rotor, no backlash, no hardening.
Late in the sweep the ripple makes the link creep and stick, and at its reversals the link
friction holds the spring with the spring torque's sign, where the friction law claims
FS tanh(q' / v0) of the filtered speed. A dead band of a few link-encoder counts (or a
hardening engaged as near zero) adds K b s(qm - q), a torque of that sign, and against the
ripple and offset alone it explains a share of the held-out residual that passes its round's
bar. Against the reference that holds the column s(qm - q) (the spring law's first order in
its width), what the band itself adds fails: the ripple and the offset are named, no spring
law."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.campaign.battery import Place
from jointbench.identification.discrepancy.candidates import (_own_law, _searched,
                                                              beyond_limit, reference)
from jointbench.identification.discrepancy.nominal import nominal, with_link_law
from jointbench.identification.effects import EFFECTS
from jointbench.identification.output_values import finite_json
from jointbench.testing import IndepRunner

BALANCED = Place("indep", "balanced")
RIPPLE, OFFSET = 2.0, -0.8
SEED = 9961204

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def log():
    return IndepRunner(40.0).log(BALANCED, (("torque_ripple", RIPPLE, {}),
                                            ("offset", OFFSET, {})), SEED, False, True)


@pytest.fixture(scope="module")
def answer(log):
    return diagnose(log, forward=False)


def test_ripple_and_offset_named_and_no_spring_law(answer):
    named = [c.effect for c in answer.causes]
    assert named[0] == "torque_ripple"
    assert set(named) <= {"torque_ripple", "offset", "asymmetric_friction"}
    assert len(named) == 2
    assert answer.extended_parameters["ripple_amplitude"] == pytest.approx(RIPPLE, rel=0.2)
    assert failing_claims(finite_json(answer.to_json())) == []


def test_the_dead_band_passes_only_without_its_limit(log, answer):
    """On top of the two named causes, a dead band passes its round's bar against the
    reference without the spring-sign column and fails against it; its width is a few
    link-encoder counts (2 pi / 2^20 = 6 urad), well under the deflection's scale."""
    settings, _ = diagnosis_settings(log)
    nom = nominal(log, settings)
    model = tuple((c.effect, c.fixed) for c in answer.causes)
    m = len([c for c in answer.inverse.candidates if c.testable]) - len(model)
    ref = reference(nom, model, m=m)
    nom = with_link_law(nom, ref.base.design())
    ref = reference(nom, model, m=m)
    e = EFFECTS["backlash"]
    first = _searched(nom, e, ref, [])
    law = _own_law(nom, e, ref, first)   # the dead band's own link law, as candidate's
    plain = first if law is nom else _searched(law, e, ref, [])
    assert plain.significant and plain.fixed["backlash_rad"] < 1e-4
    held = beyond_limit(nom, e, ref, plain)
    assert not held.significant
    assert held.heldout_pct < plain.heldout_pct
