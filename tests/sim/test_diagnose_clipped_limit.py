"""`diagnose` on logs whose loop reaches its torque limit (bench.analysis.diagnose.clipped): a
torque lag that drives the independent simulator's pendulum into a limit cycle at tau_max is
named, with a passing test, where `identify` refuses the log; a clean loop driven into its
limit names nothing; a torque clipped after the fact (a sensor's range written as tau_max) is
not read as applied. Every answer validates against docs/schemas/diagnose.schema.json."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.campaign.battery import Place
from jointbench.bench.sim.controller import gains_rule
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.saturation import MAX_CLIPPED_SHARE, clipped_samples
from jointbench.testing import BATTERY_FAMILIES, IndepRunner, default_reference, simulate

jsonschema = pytest.importorskip("jsonschema")

SCHEMA = Path(__file__).resolve().parents[2] / "docs" / "schemas" / "diagnose.schema.json"
PENDULUM = Place("indep", "pendulum", gravity=True)
DURATION = 30.0
LAG = 0.005   # [s], 0.19 / (2 pi f1) at the pendulum's f1 = 6 Hz (the battery draws 0.15-0.3)


def _answer(d) -> dict:
    doc = json.loads(json.dumps(d.to_json(), allow_nan=False, default=float))
    jsonschema.Draft202012Validator(json.loads(SCHEMA.read_text())).validate(doc)
    return doc


@pytest.fixture(scope="module")
def lagged():
    return IndepRunner(DURATION).log(PENDULUM, (("torque_lag", LAG, {}),), 7, True, True)


def _clean_clipped(tau_share: float, amplitude: float, acceleration: float):
    """The pendulum's clean chirp with the controller's limit at `tau_share` of the
    family's and the reference `amplitude` and `acceleration` times the default: the loop
    is driven into its limit without any effect."""
    f = BATTERY_FAMILIES["pendulum"]
    ref = default_reference(f, DURATION)
    ref = dataclasses.replace(ref, amplitude=amplitude * ref.amplitude,
                              max_acceleration=acceleration * ref.max_acceleration)
    fam = dataclasses.replace(f, tau_max=tau_share * f.tau_max)
    gains = gains_rule(f.Jm, f.JL, f.K, fam.tau_max, 1.0 / PAPER_RATE)
    return simulate(fam, 5, DURATION, sample_rate_hz=PAPER_RATE, reference=ref, gains=gains)


def test_a_lag_that_drives_the_loop_into_its_limit_is_named(lagged):
    """Over a third of the samples at tau_max (identify refuses the log): the rows out of
    reach of the clip are a few percent of the experiment and nothing passes on them; on
    every row, the torque at tau_max taken as applied, the lag passes at half its level, and
    its replay reaches the limit as the log does while the nominal's does not."""
    clip = clipped_samples(lagged)
    assert clip.share > MAX_CLIPPED_SHARE                  # measured 43 %
    d = diagnose(lagged)
    doc = _answer(d)
    assert doc["verdict"] == "named" and doc["named_causes"] == ["torque_lag"]
    assert failing_claims(doc) == []
    cause = doc["causes"][0]
    assert cause["p_heldout"] < cause["alpha"] <= 1e-3 / 8 / 2 / 2   # lag's two bands, two views
    # the lag's time constant: measured 1.4 % off; its fold values' spread is a few percent
    assert cause["parameters"]["lag_s"] == pytest.approx(LAG, rel=0.1)
    clipped = doc["clipped"]
    assert clipped["named_by"] == "every row"
    assert clipped["rows_kept"] < 0.5 * clipped["rows"]
    assert clipped["clipped_pct"] == pytest.approx(100 * clip.share)
    assert any("answer rests on every row" in w for w in doc["warnings"])


def test_a_clean_loop_driven_into_its_limit_names_nothing():
    """63 % of the samples clipped by the controller, no effect: nothing passes in either
    view; the answer is inconclusive with the clipped share and each candidate's held-out
    share in both views (measured: at most 0.2 % on every row)."""
    log = _clean_clipped(0.15, 3.0, 6.0)
    assert clipped_samples(log).share > 0.5
    d = diagnose(log)
    doc = _answer(d)
    assert doc["named_causes"] == [] and doc["verdict"] == "inconclusive"
    assert "of the torque samples are clipped" in doc["reason"]
    tested = {c["effect"] for c in doc["candidates"] if c["testable"]}
    assert set(doc["clipped"]["heldout_pct"]) == tested
    assert set(doc["clipped"]["heldout_pct_every_row"]) == tested
    assert "named_by" not in doc["clipped"]
    assert failing_claims(doc) == []


def test_a_clean_loop_at_its_limit_now_and_then_names_nothing():
    """A few percent clipped: the rows out of reach of the clip decide, "none"."""
    log = _clean_clipped(0.12, 1.0, 1.0)
    assert 0 < clipped_samples(log).share < 0.1            # measured 3.4 %
    doc = _answer(diagnose(log, forward=False))
    assert doc["verdict"] == "none" and doc["named_causes"] == []
    assert doc["clipped"]["rows_kept"] > 0.5 * doc["clipped"]["rows"]
    assert "heldout_pct_every_row" not in doc["clipped"]


def test_a_torque_clipped_after_the_fact_is_not_read_as_applied():
    """The clean pendulum's logged torque clipped at its 70 % quantile, written as tau_max
    (a sensor's range, not the controller's clip: the axis received the whole torque). On
    every row the missing torque reads as an effect; the replay, which applies the clip,
    does not confirm it: nothing is named."""
    log = _clean_clipped(1.0, 1.0, 1.0)
    assert clipped_samples(log).count == 0
    lim = float(np.quantile(np.abs(log.tau_m), 0.7))
    cut = dataclasses.replace(log, tau_m=np.clip(log.tau_m, -lim, lim),
                              meta={**log.meta, "tau_max": repr(lim)})
    doc = _answer(diagnose(cut))
    assert doc["named_causes"] == [] and doc["verdict"] == "inconclusive"
    assert "of the torque samples are clipped" in doc["reason"]
