"""No named cause has a failing test (bench.analysis.diagnose.claims), over a few diagnosed
logs of the independent simulator: a clean wrist, a wrist with a torque ripple and a torque
lag, and a lab rig whose spring is damped and whose drive lags.

The lab rig reproduces a real lab flexible joint's diagnosis without q_ref: a spring damping
named first, then a torque lag whose second-round test in the chooser's band fails. The lag
is named on its test in the wide band (identification.discrepancy.lag_band), which passes at
a quarter of the round's level: the answer names it with that test, never with the failing
one."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

import jointbench.testing.simulator as indep
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.analysis.diagnose.report import dumps, summary_text
from jointbench.bench.analysis.diagnose.run import diagnose
from jointbench.identification.discrepancy.candidates import CHOOSER, ROW_VIEWS
from jointbench.identification.discrepancy.lag_band import WIDE_VIEWS
from jointbench.testing.hidden_effects import as_hidden, plant

jsonschema = pytest.importorskip("jsonschema")
SCHEMA = json.loads((Path(__file__).resolve().parents[2] / "docs" / "schemas"
                     / "diagnose.schema.json").read_text())

# the lab's spring: a damping ratio of 0.02 at its link mode, D = 2 zeta sqrt(K JL); a drive
# lagging by a quarter of a 500 Hz sample
LAB_EFFECTS = "spring_damping=0.0025,torque_lag=0.0005"


def _lab_rig_with(effects: str, seed: int, duration: float, monkeypatch):
    """A lab-rig run (jointbench.testing.simulator.simulate_lab_rig) whose plant carries
    hidden `effects`, without q_ref nor controller metadata (a log as the lab exports it)."""
    rig = indep.LAB_RIG
    hidden = plant(as_hidden(effects), rig.K, rig.N, False)
    stepper = indep.make_stepper
    monkeypatch.setattr(indep, "make_stepper",
                        lambda family, g, T, n, effects=None, tau_init=0.0:
                        stepper(family, g, T, n, hidden, tau_init))
    log = indep.simulate_lab_rig(seed=seed, duration=duration)
    keep = {k: v for k, v in log.meta.items() if k not in ("controller", "pid_kp", "feedback")}
    return replace(log, q_ref=None, meta=keep)


@pytest.fixture(scope="module")
def lab():
    with pytest.MonkeyPatch.context() as mp:   # the plain stepper back for the other logs
        log = _lab_rig_with(LAB_EFFECTS, 5, 80.0, mp)
    return diagnose(log, forward=False)


def _checked(d) -> dict:
    doc = json.loads(dumps(d))
    jsonschema.Draft202012Validator(SCHEMA).validate(doc)
    assert failing_claims(doc) == [], failing_claims(doc)
    return doc


def test_the_lab_rig_lag_is_named_on_the_test_that_passed(lab):
    doc = _checked(lab)
    assert doc["named_causes"] == ["spring_damping", "torque_lag"]
    lag = lab.causes[1]
    # its own band's test fails; the wide band's passes at an eighth of the round's level
    # (beside the damping the lag's level is split over the motor and the link equation,
    # candidates.lead_beside_parallel; each band's half of that, the wide band's shared by
    # its two views, lag_band), over every segment: the lab rig's multisine holds every
    # frequency in every segment
    assert not lag.own_test.passes and lag.own_test.view == CHOOSER
    assert lag.test.view.startswith("wide band") and lag.test.passes
    assert lag.test.level == pytest.approx(lag.alpha / ROW_VIEWS / 2 / WIDE_VIEWS)
    assert "over every segment" in lag.test.view
    entry = doc["causes"][1]
    assert entry["round"] == 2 and entry["t"] == lag.test.t > entry["test"]["t_bar"]
    assert "its test, round 2, wide band" in summary_text(lab)


@pytest.mark.parametrize("effects,seed,duration,named", [
    (None, 4, 40.0, []),
    ("torque_ripple=0.6,torque_lag=0.003", 3, 60.0, ["torque_lag", "torque_ripple"]),
])
def test_wrist_logs_name_only_causes_with_passing_tests(effects, seed, duration, named):
    log = indep.simulate(indep.FAMILIES["wrist"], seed, duration, feedforward=True,
                         effects=effects)
    d = diagnose(log, forward=False)
    doc = _checked(d)
    assert doc["named_causes"] == named
    tested = {n["effect"] for n in doc["not_named"]} | set(named)
    assert tested == {c["effect"] for c in doc["candidates"]}   # every effect accounted for
