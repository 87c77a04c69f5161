"""The motor-only model (no q) on short prototype logs (20-40 s instead of 60 s).

The motor response q_m / tau_m measures the first mode that the band of section 3.2 is
designed from. On a short record its Welch estimate averages few segments, and a coherence
test over few segments lets noise bins through: above the antiresonance dip their scattered
|H| f^2 can outbid the mode's peak, putting f1 five times too high, the band far above the
mode, and eqs. (18)-(20) and the link reconstruction out of any physical region
(`first_mode.motor_segments`). Checked here: a motor mode that is found lies within 3 sigma
of the truth (one that is not is reported, and the generic band is used), and K, Jm, JL meet
the motor-only bars of the 60 s logs (3 % on K and Jm, 8 % on JL:
test_indep_accuracy.py) widened by sqrt(60 / T), the standard deviation growing as the
inverse square root of the record's length.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from jointbench.identification.first_mode import measure_first_mode
from jointbench.identification.identify import identify
from jointbench.identification.physical import InversionError

BARS_60S = {"K": 3.0, "Jm": 3.0, "JL": 8.0}   # percent, motor-only, 60 s logs


def true_f1(truth: dict[str, float]) -> float:
    """The locked first mode of eqs. (5)-(6): sqrt(K (1 / Jm + 1 / JL)) / 2 pi."""
    return math.sqrt(truth["K"] * (1 / truth["Jm"] + 1 / truth["JL"])) / (2 * math.pi)


@pytest.mark.parametrize("duration, seed", [(30.0, s) for s in range(1, 9)] + [(20.0, 2),
                                                                            (40.0, 3)])
def test_short_prototype_log_motor_only(bench_log, duration, seed):
    log = bench_log("prototype", duration=duration, seed=seed)
    motor = replace(log, q=None)
    truth = log.truth()
    mode = measure_first_mode(motor)
    if mode.found:
        assert abs(mode.f1_hz - true_f1(truth)) < 3 * mode.sigma_hz, mode
    result = identify(motor, "motor-only")
    if not mode.found:
        assert any(w.startswith("no resonance found") for w in result.warnings), result.warnings
    scale = math.sqrt(60.0 / duration)
    for name, bar in BARS_60S.items():
        err = 100 * (result.physical[name] / truth[name] - 1)
        assert abs(err) < bar * scale, (name, err, result.warnings)


def test_a_band_without_the_mode_is_named(bench_log):
    """A first mode given above the axis' (26.7 Hz for 3.7 Hz: what the stray bins of a
    four-segment motor response gave) puts the band far above the mode; eqs. (18)-(20)
    then start the link reconstruction from K and JL orders of magnitude off, and it leaves
    the physical region: the error says so and names the band and f1."""
    log = replace(bench_log("prototype", duration=30.0, seed=2), q=None)
    with pytest.raises(InversionError, match=r"left the physical region .*band that does not "
                       r"hold the first mode \(wn = .*f1 26.7 Hz"):
        identify(log, "motor-only", f1_hz=26.74)
