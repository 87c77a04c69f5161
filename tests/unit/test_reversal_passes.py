"""The reversal passes' stopping rule (identify.ReversalPasses, pass_move) and the wide band's
look from the chooser's Coulomb columns (identify._wide_fit), against the fixed passes and
the two bands fitted in full, on the independent simulator's logs (numpy, no MuJoCo)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import jointbench.identification.identify as identify_module
from jointbench.identification.estimate import LSResult
from jointbench.identification.identify import (REVERSAL_PARAMS, REVERSAL_PASSES,
                                                REVERSAL_SETTLED, ReversalPasses, identify,
                                                pass_move)
from jointbench.identification.paper_tables import to_json
from jointbench.testing import FAMILIES

NAMES = ("Jm", "FVm", "FSm", "K", "JL", "MX", "MY", "FV", "FS")


def _ls(X, sigma, unidentifiable=()) -> LSResult:
    X, sigma = np.asarray(X, float), np.asarray(sigma, float)
    return LSResult(NAMES, X, sigma, np.diag(sigma ** 2), 1.0, np.zeros(3), 100, 1.0,
                    tuple(unidentifiable), {})


def test_pass_move_is_the_largest_move_of_the_five_in_the_new_sigmas():
    old = _ls(np.ones(9), np.ones(9))
    X = np.ones(9)
    X[NAMES.index("K")] += 0.3       # 0.3 / 2 = 0.15 of the new sigma
    X[NAMES.index("Jm")] -= 0.1      # 0.1 / 1
    X[NAMES.index("MX")] += 50.0     # the link's gravity term: not read
    sigma = np.ones(9)
    sigma[NAMES.index("K")] = 2.0
    assert pass_move(_ls(X, sigma), old) == pytest.approx(0.15)
    assert set(REVERSAL_PARAMS) == {"K", "Jm", "JL", "FVm", "FSm"}


def test_pass_move_skips_unidentified_parameters_and_is_inf_without_any():
    old = _ls(np.ones(9), np.ones(9))
    X = np.ones(9)
    X[NAMES.index("K")] = 9.0
    assert pass_move(_ls(X, np.ones(9), ("K",)), old) == 0.0
    assert pass_move(_ls(X, np.ones(9), REVERSAL_PARAMS), old) == math.inf
    assert pass_move(_ls(X, np.full(9, np.nan)), old) == math.inf


def test_json_of_the_passes():
    out = ReversalPasses(2, (0.8, 0.05), "settled").to_json()
    assert out == {"passes": 2, "stop": "settled", "moves_sigma": [0.8, 0.05],
                   "settled_below_sigma": REVERSAL_SETTLED, "max_passes": REVERSAL_PASSES}
    assert ReversalPasses(1, (math.inf,), "cap").to_json()["moves_sigma"] == [None]


def _sigmas_apart(a, b, names=("K", "Jm", "JL")) -> float:
    return max(abs(a.physical[n] - b.physical[n]) / a.physical_sigma[n] for n in names)


@pytest.mark.parametrize("family,feedforward,sweep", [("soft", True, "log"),
                                                      ("heavy_link", False, "linear")])
def test_the_passes_stop_where_the_rule_says_and_hold_the_fixed_passes(
        indep_log, monkeypatch, family, feedforward, sweep):
    log = indep_log(FAMILIES[family], 1, 60.0, sweep, feedforward)
    result = identify(log, "joint-motor")
    passes = result.reversals
    assert passes is not None and "reversals" in result.corrections
    assert 1 <= passes.passes == len(passes.moves) <= REVERSAL_PASSES
    assert all(m >= REVERSAL_SETTLED for m in passes.moves[:-1])
    if passes.stop == "settled":
        assert passes.moves[-1] < REVERSAL_SETTLED
    else:
        assert passes.stop == "cap" and passes.passes == REVERSAL_PASSES
    assert to_json(result)["reversals"]["passes"] == passes.passes
    # the fixed passes (the rule never met): each pass after the settled one moves the five
    # by under REVERSAL_SETTLED sigma, and there are two at most
    monkeypatch.setattr(identify_module, "REVERSAL_SETTLED", 0.0)
    fixed = identify(log, "joint-motor")
    assert fixed.reversals.passes == REVERSAL_PASSES and fixed.reversals.stop == "cap"
    assert fixed.band.used == result.band.used
    assert _sigmas_apart(fixed, result) < (REVERSAL_PASSES - 1) * REVERSAL_SETTLED


def test_no_passes_without_the_reversals(indep_log):
    log = indep_log(FAMILIES["soft"], 1, 60.0, "log", True)
    result = identify(log, "joint-motor", corrections=("instruments", "stencil5", "zoh"))
    assert result.reversals is None and "reversals" not in to_json(result)


@pytest.mark.parametrize("family,sweep", [("balanced", "linear"), ("soft", "log"),
                                          ("heavy_link", "linear")])
def test_the_look_at_the_wide_band_picks_what_the_full_fits_pick(indep_log, monkeypatch,
                                                                  family, sweep):
    # balanced linear: the wide band kept; soft log: the wide band more precise but 4 sigma
    # of the difference off the chooser's (the chooser's kept, a warning); heavy_link: the
    # wide band kept
    log = indep_log(FAMILIES[family], 1, 60.0, sweep, True)
    looked = identify(log, "joint-motor")

    def full(log, model, wide, chosen, candidate, f1_hz, wanted, made):
        return identify_module._identify(log, model, wide, [], f1_hz, wanted, made)

    monkeypatch.setattr(identify_module, "_wide_fit", full)
    both = identify(log, "joint-motor")
    assert looked.band.used == both.band.used
    assert looked.band.alternative is not None
    assert bool(looked.band.warning) == bool(both.band.warning)
    if looked.band.used == "wide":
        assert "wide_band" in looked.corrections
        # the same band, its passes started elsewhere: within their settling
        assert _sigmas_apart(both, looked) < (REVERSAL_PASSES - 1) * REVERSAL_SETTLED
