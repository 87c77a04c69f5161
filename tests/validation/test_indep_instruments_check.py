"""The joint-motor model with the reference's instruments on a log where they are not valid:
the independent simulator's heavy_link with no link Coulomb friction (FS = 0), without
velocity feed-forward, with ideal sensors (no torque noise, no quantisation).

The motor sticks at most reversals and no noise dithers it, so the first pass's Coulomb
column (sign of the velocity) is wrong over long stretches, and that error follows the motion
as deterministically as the reference's prediction of it does: the instruments are
correlated with it. Their oblique projection amplifies it along the scale that K, JL and FV
share (the link equation leaves it free), and the reversal passes build the stick phases from
that estimate; without the check the fit ends at K and JL about 0.28 times the truth, with
no warning. The chain without instruments is within 0.01 %, and the instrument passes
started from it within 0.3 %: their answer depends on their start. The check
(identification/iv_check.py, `identify._check_instruments`) rejects the instruments for
that and keeps least squares with a warning naming the cause; the bar is the issue's: K (and
Jm, JL) within 3 %, or a warning naming the cause (both hold here)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from jointbench.identification.identify import identify
from jointbench.testing import FAMILIES

CAUSE = "instruments from q_ref rejected"


@pytest.fixture(scope="module")
def frictionless_link(indep_log):
    return indep_log(replace(FAMILIES["heavy_link"], FS=0.0), seed=1, duration=60.0,
                     sweep="linear", feedforward=False, ideal_sensors=True)


def test_rejected_instruments_fall_back_to_least_squares(frictionless_link):
    log = frictionless_link
    result, truth = identify(log, "joint-motor"), log.truth()
    warned = [w for w in result.warnings if CAUSE in w]
    assert warned, result.warnings
    assert "correlated with the model's error" in warned[0]
    assert "started from least squares' estimate" in warned[0]
    assert "instruments" not in result.corrections and not result.ls.instrumental
    for p in ("K", "Jm", "JL"):
        assert abs(result.physical[p] / truth[p] - 1) < 0.03, (p, result.physical[p])


def test_fallback_is_the_chain_without_instruments(frictionless_link):
    """What the check keeps is the fit with the instruments switched off, number for number
    (the other corrections unchanged)."""
    from jointbench.identification.corrections import CORRECTIONS

    log = frictionless_link
    kept = identify(log, "joint-motor")
    plain_iv = identify(log, "joint-motor",
                        corrections=tuple(c for c in CORRECTIONS if c != "instruments"))
    assert kept.corrections == plain_iv.corrections
    for p in ("K", "Jm", "JL", "FVm", "FSm", "FV"):
        assert kept.physical[p] == pytest.approx(plain_iv.physical[p], rel=1e-12), p


def test_least_squares_own_bias_keeps_the_instruments(bench_log):
    """The six-axis arm's axis 3 in a 240 s log with the bench's torque noise: least squares'
    closed-loop bias (a fixed share of K while the sigmas shrink with the log's length) puts
    it 4.2 times the sum of the two sigmas from the instruments' K, over the first test's
    3.59; the instrument passes started from least squares end at the same estimate, so the
    instruments' fit is kept, unchanged, within the arm's 0.5 % (least squares alone: K
    -0.71 %, Jm +0.85 %), with a warning that names both explanations."""
    log = bench_log("arm6", "axis3", duration=240.0, seed=1)
    result, truth = identify(log, "joint-motor"), log.truth()
    assert not any(CAUSE in w for w in result.warnings), result.warnings
    kept = [w for w in result.warnings if w.startswith("instruments and least squares disagree")]
    assert kept and "closed-loop bias" in kept[0] and "instruments kept" in kept[0], \
        result.warnings
    assert "instruments" in result.corrections and result.ls.instrumental
    for p in ("K", "Jm", "JL"):
        assert abs(result.physical[p] / truth[p] - 1) < 0.005, (p, result.physical[p])
