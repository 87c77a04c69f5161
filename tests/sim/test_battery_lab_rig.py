"""The lab-rig family of the independent simulator in the battery by visibility
(jointbench.testing.LabRigRunner, benchmarks/battery.py's places): a voltage drive under a P
loop at 500 Hz, run through the battery's machinery (bench.campaign.battery.run_spec) clean and
with a hidden effect, and diagnosed."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.campaign.battery import BENCH_PLACES, Spec, plan, run_spec
from jointbench.bench.campaign.visibility import SEARCH_TOLERANCE
from jointbench.identification.discrepancy.inverse import diagnose_inverse
from jointbench.testing import (INDEP_PLACES, LAB_PLACES, LAB_RIG, LabRigRunner,
                                simulate_lab_rig)

ROOT = Path(__file__).resolve().parents[2]
DURATION = 20.0


def _battery_places():
    spec = importlib.util.spec_from_file_location("battery_bench", ROOT / "benchmarks" /
                                                  "battery.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.PLACES


def test_the_battery_covers_six_families_with_the_lab_rig():
    """benchmarks/battery.py's places: at least 6 axis families, the lab rig among them, and
    the plan gives the lab rig clean, single and two-effect cases."""
    places = _battery_places()
    assert set(LAB_PLACES) <= set(places)
    specs = plan(places)
    assert len({s.place.family for s in specs}) >= 6
    lab = [s for s in specs if s.place in LAB_PLACES]
    assert {s.kind for s in lab} == {"clean", "single", "pair"}


def test_no_effect_is_the_lab_rig_as_it_was():
    """An empty effect list changes nothing: the same log, bit for bit, as the rig without
    the argument (the lab-rig tests' logs stay what they were)."""
    a = simulate_lab_rig(seed=5, duration=2.0)
    b = simulate_lab_rig(seed=5, duration=2.0, effects=())
    assert np.array_equal(a.tau_m, b.tau_m) and np.array_equal(a.q, b.q)
    assert a.meta == b.meta


def test_an_offset_on_the_lab_rig_moves_the_mean_command():
    """The P loop holds the reference against the constant torque c on the rotor (tau - c):
    without an integrator it leaves a steady error c / kp, and the mean command moves by
    about c (the loop's gain over the plant's at the multisine's low end)."""
    quiet = LabRigRunner(duration=8.0)
    clean = quiet.log(LAB_PLACES[0], (), 3, True, False)
    c = 0.05 * LAB_RIG.family.tau_max
    shifted = quiet.log(LAB_PLACES[0], (("offset", c, {}),), 3, True, False)
    assert shifted.meta["truth_effect"] == "offset"
    assert np.mean(shifted.tau_m - clean.tau_m) == pytest.approx(c, rel=0.1)


@pytest.fixture(scope="module")
def runner():
    return LabRigRunner(duration=DURATION)


def test_clean_lab_rig_case_names_nothing(runner):
    spec = Spec(0, LAB_PLACES[0], 21, True, True)
    out = run_spec(spec, runner)
    assert out.strengths == () and out.log.meta["sample_rate_hz"] == "500"
    inv = diagnose_inverse(out.log, diagnosis_settings(out.log)[0])
    assert inv.causes == (), [c.effect for c in inv.causes]


def test_lab_rig_ripple_case_hits_its_target_and_is_named(runner):
    """A torque ripple searched to a visibility of 20 %: the search meets it within
    SEARCH_TOLERANCE and diagnose names the ripple."""
    spec = Spec(1, LAB_PLACES[0], 22, True, True, ("torque_ripple",), (0.20,))
    out = run_spec(spec, runner)
    assert abs(out.visibilities[0] / 0.20 - 1) <= SEARCH_TOLERANCE
    assert out.log.meta["truth_effect"] == "torque_ripple"
    inv = diagnose_inverse(out.log, diagnosis_settings(out.log)[0])
    assert [c.effect for c in inv.causes][:1] == ["torque_ripple"]


def test_a_shared_cache_keeps_each_seeds_multisine():
    """The battery shares one cache of clean commands across cases: the lab rig's reference
    is the seed's multisine, so a case of another seed must not take an earlier seed's clean
    command (its search would then see the other multisine as a visibility over 100 % at any
    strength)."""
    runner = LabRigRunner(duration=4.0)
    place = LAB_PLACES[0]
    cache: dict = {}
    first = Spec(0, place, 11, False, False)
    run_spec(first, runner, cache)
    other = Spec(1, place, 12, False, False, ("torque_ripple",), (0.10,))
    out = run_spec(other, runner, cache)
    assert abs(out.visibilities[0] - 0.10) <= SEARCH_TOLERANCE * 0.10 + 0.01, out.visibilities
    assert len(cache) == 2
