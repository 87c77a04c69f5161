"""A nominal whose link equation collapses towards 0 = 0 (identification.discrepancy.nominal,
COLLAPSED): a spring damping of 341 N m s/rad beside a 1.45 ms torque lag on arm6 axis4,
without feedforward (seed 12, 30 s at the paper's rate). Eq. (13) alone then fits K = 0.13
and JL = 0, a spring torque of 3e-6 of the motor torque, and weighted by that fit's spread
the link equation pinned every extended fit to it: only the lag was named. With equal weights
both causes are named and the damping found at its size (D 335 in the generic band the log
got before its mode was measured from the motor response; 282 in the band of that 15.5 Hz
mode, which the damping flattens; without the rule 2.4)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.campaign.battery import BENCH_PLACES, BenchRunner
from jointbench.identification.discrepancy import diagnose_inverse, nominal

NOMINAL = sys.modules["jointbench.identification.discrepancy.nominal"]   # the module


@pytest.fixture(scope="module")
def damped():
    axis4 = next(p for p in BENCH_PLACES if p.joint == "axis4")
    log = BenchRunner(30.0).log(axis4, (("spring_damping", 341.0, {}),
                                        ("torque_lag", 0.00145, {})), 12, False, False)
    return log, diagnosis_settings(log)[0]


def test_a_collapsed_link_equation_gets_equal_weights_and_both_causes_are_named(damped):
    log, s = damped
    nom = nominal(log, s)
    assert np.all(nom.weights == 1.0)
    causes = diagnose_inverse(log, s).causes
    assert [c.effect for c in causes] == ["torque_lag", "spring_damping"]
    assert causes[1].parameters["D"] == pytest.approx(341.0, rel=0.2)


def test_without_the_rule_the_collapse_hides_the_damping(damped, monkeypatch):
    log, s = damped
    monkeypatch.setattr(NOMINAL, "COLLAPSED", 0.0)
    nom = nominal(log, s)
    K, JL = nom.value("K"), nom.value("JL")
    assert K < 1.0 and JL < 1e-3 and nom.reference_rms[1] < 1e-5 * nom.reference_rms[0]
    assert "spring_damping" not in [c.effect for c in diagnose_inverse(log, s).causes]
