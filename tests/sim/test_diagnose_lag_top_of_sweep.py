"""A torque lag whose evidence is all at the top of the sweep: the independent simulator's
soft family (f1 = 4 Hz, swept to 30 Hz) with torque noise and a 23.5 ms lag (about 28 %
visibility). The chooser's band (to 5.4 Hz) holds the bottom of the sweep only, and in the
wide band most segments lie below the frequencies where the lag's phase w T is material:
over every segment their log-ratios carry the MATERIAL margin and nothing else. The wide
band's test over the half of the segments where the lag's held-out prediction changes most
(identification.discrepancy.lag_band.top_of_sweep, chosen from the fold fits and the
regressors, never the held-out torque) sees it, at a quarter of the lag's level. On the same
axis without the lag that view stays under its bar."""

from __future__ import annotations

import json

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.analysis.diagnose.report import dumps
from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.identification.band_choice import CONSISTENCY_Z
from jointbench.identification.discrepancy.candidates import candidate, reference
from jointbench.identification.discrepancy.heldout import SEGMENTS, bar, evidence, t_bar
from jointbench.identification.discrepancy.lag_band import (WIDE_VIEWS, LagBand, jackknife,
                                                            top_of_sweep)
from jointbench.testing import INDEP_PLACES, IndepRunner

SOFT = INDEP_PLACES[1]
SEED = 9310
LAG_S = 0.0235   # about 28 % visibility on this axis


@pytest.fixture(scope="module")
def runner():
    return IndepRunner(40.0)


@pytest.fixture(scope="module")
def lagged(runner):
    return diagnose(runner.log(SOFT, (("torque_lag", LAG_S, {}),), SEED, False, True))


def test_the_lag_is_named_on_its_test_at_the_top_of_the_sweep(lagged):
    assert [c.effect for c in lagged.causes] == ["torque_lag"]
    lag = lagged.causes[0]
    test = lag.test
    assert test.passes and test.t > test.bar and test.heldout_pct > 0
    # not in the chooser's band (the bottom of the sweep): in the wide band at the top of
    # the sweep, at that band's share of the level
    assert not lag.own_test.passes
    assert "at the top of the sweep" in test.view and test.segments < SEGMENTS
    assert test.level == pytest.approx(lag.level / WIDE_VIEWS)
    # the chooser's value: the hidden time constant within 3 sigma of its delete-a-fold
    # jackknife spread (band_choice's CONSISTENCY_Z)
    assert abs(lag.fixed["lag_s"] - LAG_S) < CONSISTENCY_Z * jackknife(lag.fold_values)
    doc = json.loads(dumps(lagged))
    assert failing_claims(doc) == []
    entry = next(c for c in doc["causes"] if c["effect"] == "torque_lag")
    assert entry["test"]["passes"] and entry["t"] > entry["test"]["t_bar"]


def test_the_top_of_the_sweep_stays_under_its_bar_without_a_lag(runner):
    log = runner.log(SOFT, (), SEED, False, True)
    assert diagnose(log).causes == ()
    band = LagBand(log, diagnosis_settings(log)[0])
    assert band.settings is not None
    nom = band.nominal()
    w = candidate(nom, "torque_lag", reference(nom))
    n = len(nom.sig.index)
    top = top_of_sweep(w, n)
    # the median's split: half the segments, chosen without the held-out torque
    assert SEGMENTS // 2 <= top.sum() <= SEGMENTS // 2 + 1
    ev = evidence(w.reference_errors, w.heldout_errors, n, w.acts, top)
    # a quarter of the lag's level in a first round of 8, with the view's own degrees of
    # freedom; a margin of one unit of t (the segment t's spread under the null)
    assert ev.t < t_bar(bar(8) / 2 / WIDE_VIEWS, ev.segments) - 1.0
