"""A lab rig (independent simulator's voltage drive under a P loop) with a torque lag and a
spring damping far beyond the spring's stiffness times the first mode (D w1 / K about 13, a
damping ratio of several): the two masses move as one, the deflection qm - q stays within a
few encoder counts, and eq. 13 fits K and JL of the wrong sign. The nominal is no physical
axis, and nothing is named; but the columns are not swapped, and the fit with q and q_m
swapped is no physical axis either, so the reason must not name that mislabelling
(verdict.swap_refuted). Before, the reason said "the columns q and q_m look swapped"."""

from __future__ import annotations

import math

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.testing import LAB_PLACES, LabRigRunner

LAG_S = 0.28
D = 0.6
SEED = 10297


@pytest.fixture(scope="module")
def answer():
    log = LabRigRunner(20.0).log(LAB_PLACES[0], (("torque_lag", LAG_S, {}),
                                                 ("spring_damping", D, {})), SEED, False, True)
    return diagnose(log, forward=False)


def test_an_unresolved_spring_is_not_called_a_swap(answer):
    d = answer
    m = d.log.meta
    K, f1 = float(m["truth_K"]), float(m["truth_f1_hz"])
    # the premise: the damping dwarfs the spring at the first mode; the truth's columns
    # are the right way round (its K, Jm, JL positive)
    assert D * 2 * math.pi * f1 / K > 5
    assert all(float(m[f"truth_{k}"]) > 0 for k in ("K", "Jm", "JL"))
    assert d.verdict == "inconclusive" and not d.causes
    assert d.nominal_parameters["K"] <= 0 or d.nominal_parameters["JL"] <= 0
    assert "look swapped" not in d.overruled
    assert "with q and q_m swapped the fit is no physical axis either" in d.overruled
