"""The battery by visibility (bench.campaign.battery, .visibility, .detection; benchmarks/
battery.py), the independent simulator's hidden effects (testing.hidden_effects) and several
hidden effects at once (simulate --effect A=..,B=..): fast checks of the machinery."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointbench.bench.campaign.battery import BENCH_PLACES, BenchRunner, Spec, plan, run_spec
from jointbench.bench.campaign.detection import found_above, right, summary_lines
from jointbench.bench.campaign.visibility import SEARCH_TOLERANCE, strength_for, visibility
from jointbench.bench.cli import main
from jointbench.bench.effects import parse_effects
from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.log import read_log
from jointbench.testing import (FAMILIES, INDEP_PLACES, Hidden, IndepRunner, frictionless,
                                open_loop, parse_hidden, simulate)

BALANCED = FAMILIES["balanced"]


# ---- visibility and the strength search ----

def test_visibility_of_a_known_change():
    """A constant added to a zero-mean in-band sine: visibility = c / RMS(sine) = c sqrt(2)."""
    rate, f1 = 350.87, 5.0
    t = np.arange(20000) / rate
    clean = np.sin(2 * math.pi * 1.0 * t)
    assert visibility(clean, clean + 0.1, f1, rate) == pytest.approx(0.1 * math.sqrt(2), rel=2e-3)
    # a change far above the band (40 Hz against 1.4 f1 = 7 Hz), as large as the clean
    # command (ratio 1 unfiltered), is nearly invisible: only the filter's edge transients
    assert visibility(clean, clean + np.sin(2 * math.pi * 40.0 * t), f1, rate) < 0.01


def test_strength_search_power_law_and_failures():
    """On visibility = 0.02 s^1.5 the search meets the target within the tolerance; a strength
    that does not run (NaN) is treated as too strong."""
    calls = []

    def vis(s):
        calls.append(s)
        return math.nan if s > 30 else 0.02 * s ** 1.5

    found = strength_for(0.25, vis, 100.0)
    assert found.hit(0.25)
    assert math.isnan(found.tried[0][1]) and len(calls) <= 6
    assert strength_for(0.1, lambda s: 0.2 * abs(s), -3.0).strength < 0   # the sign is kept


def test_bench_case_hits_its_target_and_visibility_grows_with_strength():
    """An offset case on the prototype: the searched strength gives the target visibility
    within SEARCH_TOLERANCE; backlash's visibility grows with its width."""
    runner = BenchRunner(duration=8.0)
    spec = Spec(0, BENCH_PLACES[0], 11, True, True, ("offset",), (0.12,))
    out = run_spec(spec, runner)
    assert abs(out.visibilities[0] / 0.12 - 1) <= SEARCH_TOLERANCE
    assert out.log.meta["truth_effect"] == "offset"
    assert float(out.log.meta["truth_offset"]) == pytest.approx(out.strengths[0], rel=1e-9)
    again = run_spec(spec, BenchRunner(duration=8.0))                # same seed, fresh runner
    assert again.strengths == out.strengths and np.array_equal(again.log.tau_m, out.log.tau_m)
    tau_max, f1, _ = runner.scales(BENCH_PLACES[0])
    clean = runner.log(BENCH_PLACES[0], (), 3, False, False).tau_m
    v = [visibility(clean, runner.log(BENCH_PLACES[0], (("backlash", b, {}),), 3, False,
                                      False).tau_m, f1, runner.rate_hz)
         for b in (0.0005, 0.001, 0.002)]
    assert 0 < v[0] < v[1] < v[2]


def test_plan_counts_families_and_conditions():
    places = (*BENCH_PLACES, *INDEP_PLACES)
    specs = plan(places)
    kinds = [s.kind for s in specs]
    assert kinds.count("single") >= 60 and kinds.count("clean") >= 20
    assert kinds.count("pair") >= 20
    assert len({s.place.family for s in specs if s.kind == "pair"}) >= 3
    assert {(s.feedforward, s.noise) for s in specs} == {(True, True), (True, False),
                                                        (False, True), (False, False)}
    assert all(s.place.gravity for s in specs if "gravity" in s.effects)
    assert all(0.03 <= t <= 0.40 for s in specs for t in s.targets)
    assert all(min(s.targets) >= 0.10 for s in specs if s.kind == "pair")
    assert plan(places) == specs                                    # seeded


def test_detection_summary_and_95_threshold():
    recs = [{"kind": "single", "effects": ["offset"], "visibilities": [v], "named": n,
             "family": "x"} for v, n in ((0.04, []), (0.06, ["offset"]), (0.2, ["offset"]),
                                         (0.3, ["offset"]))]
    recs.append({"kind": "pair", "effects": ["offset", "backlash"], "visibilities": [0.2, 0.2],
                 "named": ["backlash", "offset"], "family": "x"})
    assert found_above(recs, "offset") == 0.06 and right(recs[-1])
    text = "\n".join(summary_lines(recs))
    assert "two-effect cases with both named: 1/1" in text and "6.0 %" in text


def test_a_miss_with_the_hidden_effect_as_stated_alternative_is_counted_apart():
    from jointbench.bench.campaign.detection import alternative_stated
    amb = ["offset or asymmetric_friction: this log cannot tell them apart"]
    miss = {"kind": "single", "effects": ["asymmetric_friction"], "visibilities": [0.2],
            "named": ["offset"], "ambiguity": amb, "family": "x"}
    wrong = dict(miss, effects=["backlash"])
    hit = dict(miss, effects=["offset"])
    assert alternative_stated(miss) and not alternative_stated(wrong)
    assert not alternative_stated(hit) and right(hit) and not right(miss)   # never counted right
    text = "\n".join(summary_lines([miss, wrong, hit]))
    assert "named right: 1/3" in text and "(ambiguity): 1" in text
    assert "cannot separate" not in text          # no distinguishing visibility recorded


def test_a_stated_ambiguity_the_log_cannot_resolve_is_counted_on_its_own_line():
    """bench.campaign.detection.inseparable_stated: a miss that states the hidden effect as
    the alternative counts on the second line only where its distinguishing visibility is
    under SEPARABLE (5 %); the first line (named right) is unchanged."""
    from jointbench.bench.campaign.detection import inseparable_stated
    amb = ["offset or asymmetric_friction: this log cannot tell them apart"]
    low = {"kind": "single", "effects": ["asymmetric_friction"], "visibilities": [0.2],
           "named": ["offset"], "ambiguity": amb, "family": "x", "distinguishing": [0.012]}
    high = dict(low, distinguishing=[0.08])
    hit = dict(low, named=["asymmetric_friction"], ambiguity=[])
    other = {"kind": "single", "effects": ["backlash"], "visibilities": [0.2],
             "named": ["backlash"], "family": "x", "distinguishing": [None]}
    assert inseparable_stated(low) and not inseparable_stated(high)
    assert not inseparable_stated(hit) and not inseparable_stated(other)
    text = "\n".join(summary_lines([low, high, hit, other]))
    assert "at visibility >= 5 % named right: 2/4" in text
    assert ("2 named right, 1 stated ambiguity between two effects the log cannot separate "
            "(distinguishing visibility < 5 %), of 4 (75 % together)") in text


def test_cases_whose_torque_clips_are_listed_with_their_share_and_outcome():
    """A hidden effect can drive the loop into its torque limit (battery seed 2026 #62: a lag
    on the pendulum, 21 % of the samples at tau_max): the summary lists those cases, the
    counts above them are unchanged."""
    hit = {"index": 3, "kind": "single", "effects": ["offset"], "visibilities": [0.2],
           "named": ["offset"], "family": "x"}
    cut = dict(hit, index=7, effects=["torque_lag"], named=[], clipped_pct=21.4)
    quiet = dict(hit, index=9, clipped_pct=0.0)
    text = "\n".join(summary_lines([hit, cut, quiet]))
    assert "at visibility >= 5 % named right: 2/3" in text
    assert "(clipped samples): #7 21 % (missed)" in text and "#9" not in text
    assert "clipped" not in "\n".join(summary_lines([hit, quiet]))


def test_distinguishing_visibility_is_what_the_reduced_effect_cannot_take():
    """An effect's change = a constant (what an offset takes) + an in-band sine of amplitude
    B; the reduced effect's change a constant of another size: the distinguishing visibility
    is the sine's alone, B / A for a clean sine of amplitude A; a change the reduced effect
    takes whole has none."""
    from jointbench.bench.campaign.detection import distinguishing_visibility
    rate, f1 = 350.87, 5.0
    t = np.arange(20000) / rate
    clean = 2.0 * np.sin(2 * math.pi * 1.0 * t)
    effect = clean + 0.7 + 0.1 * np.sin(2 * math.pi * 3.0 * t)
    d = distinguishing_visibility(clean, effect, clean - 0.25, f1, rate)
    assert d == pytest.approx(0.05, rel=5e-3)
    assert visibility(clean, effect, f1, rate) > 0.3 * math.sqrt(2)   # the whole change
    assert distinguishing_visibility(clean, clean + 0.7, clean + 0.1, f1, rate) < 1e-3


# ---- the independent simulator's effects ----

def test_indep_same_seed_same_log_bit_for_bit():
    a = simulate(BALANCED, seed=5, duration=3.0, effects="backlash=0.001,offset=1")
    b = simulate(BALANCED, seed=5, duration=3.0, effects="backlash=0.001,offset=1")
    assert np.array_equal(a.tau_m, b.tau_m) and np.array_equal(a.q, b.q)
    assert a.meta["truth_effect"] == "backlash,offset" and a.meta["truth_backlash_rad"] == "0.001"


def _accel(effects, x0, tau=0.0, family=None, tau_init=0.0):
    """Motor and link accelerations at x0 from one short open-loop tick (1 us)."""
    f = family or frictionless(BALANCED)
    x = open_loop(f, x0, np.array([tau]), sample_rate_hz=1e6, substeps=1, effects=effects,
                  tau_init=tau_init)
    return (x[1, 2] - x[0, 2]) * 1e6, (x[1, 3] - x[0, 3]) * 1e6


def test_indep_spring_effects_follow_their_laws():
    f, b = frictionless(BALANCED), 0.002
    am, al = _accel("backlash=0.002", (0.5 * b, 0.0, 0.0, 0.0))        # inside the dead zone
    assert am == pytest.approx(0.0, abs=1e-6) and al == pytest.approx(0.0, abs=1e-6)
    am, _ = _accel("backlash=0.002", (1.5 * b, 0.0, 0.0, 0.0))
    assert am == pytest.approx(-f.K * 0.5 * b / f.Jm, rel=1e-3)
    am, _ = _accel("hardening=2:deflection=0.001", (0.003, 0.0, 0.0, 0.0))
    assert am == pytest.approx(-(f.K * 0.003 + 2 * f.K * 0.002) / f.Jm, rel=1e-3)
    am, al = _accel("spring_damping=3", (0.0, 0.0, 1.0, 0.0))
    assert am == pytest.approx(-3.0 / f.Jm, rel=1e-3) and al == pytest.approx(3.0 / f.JL, rel=1e-3)


def test_indep_motor_and_link_effects_follow_their_laws():
    f = frictionless(BALANCED)
    withf = BALANCED
    am, _ = _accel("offset=2", (0.0, 0.0, 0.0, 0.0), tau=5.0)
    assert am == pytest.approx(3.0 / f.Jm, rel=1e-3)                  # the rotor gets tau - c
    period = 0.01
    am, _ = _accel(f"torque_ripple=4:period={period}", (period / 4, period / 4, 0.0, 0.0))
    assert am == pytest.approx(4.0 / f.Jm, rel=1e-3)                  # A sin(pi / 2)
    up, _ = _accel("asymmetric_friction=0.4", (0.0, 0.0, 1.0, 1.0), family=withf)
    down, _ = _accel("asymmetric_friction=0.4", (0.0, 0.0, -1.0, -1.0), family=withf)
    friction = withf.FVm + withf.FSm * math.tanh(1.0 / withf.v_s)
    assert -up * withf.Jm == pytest.approx(1.4 * friction, rel=1e-3)
    assert down * withf.Jm == pytest.approx(0.6 * friction, rel=1e-3)
    _, al = _accel("link_coulomb=0.5", (0.0, 0.0, 1.0, 1.0))
    assert -al * f.JL == pytest.approx(0.5, rel=1e-3)
    # torque lag: the rotor torque starts at tau_init and tends to the command
    am, _ = _accel("torque_lag=0.01", (0.0, 0.0, 0.0, 0.0), tau=5.0, tau_init=1.0)
    assert am == pytest.approx(1.0 / f.Jm, rel=1e-3)


def test_indep_offset_shifts_the_mean_command_and_gravity_the_centre():
    """Closed loop: the integrator takes the offset, so the mean command moves by c; the
    gravity effect centres the experiment `strength` from the rest angle."""
    quiet = dict(seed=2, duration=6.0, torque_noise_std=0.0)
    clean = simulate(BALANCED, **quiet)
    shifted = simulate(BALANCED, effects="offset=1.5", **quiet)
    assert np.mean(shifted.tau_m - clean.tau_m) == pytest.approx(1.5, rel=0.02)
    runner = IndepRunner(duration=4.0)
    log = runner.log(INDEP_PLACES[3], (("gravity", 0.2, {}),), 1, True, False)
    assert float(log.meta["truth_center"]) == pytest.approx(0.2)
    assert np.mean(log.q) == pytest.approx(0.2, abs=0.02)
    with pytest.raises(ValueError, match="link mass"):
        simulate(BALANCED, duration=3.0, effects="gravity=0.1")


# ---- several hidden effects on the bench ----

def test_two_hidden_effects_on_the_bench(tmp_path, capsys):
    both = run_experiment("prototype", duration=5.0, seed=4,
                          effect=parse_effects("offset=100,backlash=0.002")).log
    one = run_experiment("prototype", duration=5.0, seed=4,
                         effect=parse_effects("offset=100")).log
    assert both.meta["truth_effect"] == "offset,backlash"
    assert both.meta["truth_offset"] == "100" and both.meta["truth_backlash_rad"] == "0.002"
    assert not np.array_equal(both.tau_m, one.tau_m)
    out = tmp_path / "two.csv"
    assert main(["simulate", "--duration", "5", "--quiet", "--out", str(out),
                 "--effect", "offset=100,backlash=0.002"]) == 0
    written = read_log(out)
    assert written.meta["truth_effect"] == "offset,backlash"
    assert written.meta["truth_backlash_rad"] == "0.002"
    for bad, why in (("offset=1,offset=2", "given twice"), ("offset=1,,backlash=0.1", "empty"),
                     ("offset=1,nope=2", "unknown effect")):
        assert main(["simulate", "--duration", "5", "--quiet", "--out", str(out),
                     "--effect", bad]) == 2
        assert why in capsys.readouterr().err
    with pytest.raises(ValueError, match="twice"):
        parse_hidden("offset=1,offset=2")
    with pytest.raises(ValueError, match="lie in"):
        Hidden("asymmetric_friction", 1.0)


def test_summary_counts_extra_causes_and_failing_claims():
    """The must-show lines: a log naming a cause it does not hide is counted, one naming two
    such causes is counted apart, and a case's failing claims are summed."""
    from jointbench.bench.campaign.detection import summary_lines

    base = {"kind": "clean", "effects": [], "visibilities": [], "family": "soft", "error": ""}
    recs = [dict(base, named=[]), dict(base, named=["offset"]),
            dict(base, named=["offset", "gravity"], failing_claims=["offset: p 0.2 >= alpha"]),
            dict(base, kind="single", effects=["offset"], visibilities=[0.1],
                 named=["offset"], family="wrist")]
    text = "\n".join(summary_lines(recs))
    assert "logs naming a cause not hidden in them: 2/4 (50.0 %); more than one such cause: 1" \
        in text
    assert "named causes without a passing test (claims.failing_claims over each case's " \
        "JSON): 1 in 1 logs" in text
    assert "axis families: 2" in text
