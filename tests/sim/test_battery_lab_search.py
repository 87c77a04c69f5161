"""The battery's strength search on the lab rig (jointbench.testing.LabRigRunner): effects
whose visibility saturates below the target (a spring damping that locks the link to the
motor, a hardening that acts as a stop) end their search at the visibility reached, flagged,
without running on to strengths whose simulation takes minutes; and a case whose log the
diagnosis refuses is recorded with the reason, not a traceback."""

from __future__ import annotations

import importlib.util
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from jointbench.bench.campaign.battery import Spec, run_spec
from jointbench.bench.campaign.visibility import SEARCH_EVALUATIONS
from jointbench.bench.effects.hardening import LARGEST
from jointbench.testing import LAB_PLACES, LabRigRunner

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def runner():
    return LabRigRunner(duration=8.0)


def test_a_spring_damping_out_of_reach_stops_where_the_visibility_saturates(runner):
    """The springs' damping D (qm' - q') couples the link to the motor; once it is locked the
    command changes no more, a few per cent in band: asked for 30 %, the search stops there,
    flagged, at a damping far below the thousands of N m s/rad a secant would reach."""
    spec = Spec(0, LAB_PLACES[0], 21, False, False, ("spring_damping",), (0.30,))
    out = run_spec(spec, runner)
    search = out.searches[0]
    assert search.saturated and out.visibilities[0] < 0.30 / 2
    assert len(search.tried) < SEARCH_EVALUATIONS
    assert max(abs(s) for s, _ in search.tried) < 50.0
    # the visibility reached is the plateau's: a stronger damping adds little
    assert out.visibilities[0] > 0.5 * max(v for _, v in search.tried)


def test_a_hardening_search_stays_under_its_largest_ratio(runner):
    """A second spring engaging beyond the rig's usual deflection: a target of 30 % is out of
    reach; the search stops at or under LARGEST times K, flagged."""
    spec = Spec(0, LAB_PLACES[0], 21, False, False, ("hardening",), (0.30,))
    out = run_spec(spec, runner)
    assert out.searches[0].saturated
    assert max(abs(s) for s, _ in out.searches[0].tried) <= LARGEST


def _battery():
    spec = importlib.util.spec_from_file_location("battery_lab_search", ROOT / "benchmarks" /
                                                  "battery.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class RigidLab(LabRigRunner):
    """The lab rig with its link welded to the motor: q = q_m in every log."""

    def log(self, *args, **kwargs):
        log = super().log(*args, **kwargs)
        return replace(log, q=np.array(log.q_m))


def test_a_case_whose_log_is_refused_is_recorded_with_the_reason():
    """A log whose deflection never changes (the link moves with the motor) has no spring to
    test: the case's record carries the diagnosis's reason, as one line, and the battery
    goes on."""
    battery = _battery()
    battery._RUNNERS["lab"] = RigidLab(duration=4.0)
    rec = battery.run_one(Spec(0, LAB_PLACES[0], 5, False, False))
    assert rec["error"].startswith("ValueError: ") and "never changes" in rec["error"]
    assert "Traceback" not in rec["error"] and "\n" not in rec["error"]
    assert rec["named"] == []
