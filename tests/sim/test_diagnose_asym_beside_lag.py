"""An asymmetric friction near its bound beside a torque lag (identification.discrepancy.
inverse._redecided, _held).

The bench's arm6 axis 2 (FVm 25, FSm 40) with one direction's motor friction a tenth of the
other's (a = -0.9) and a 5 ms torque lag. Against the nominal alone the lag's phase error in
the motor equation takes the fitted Coulomb friction down to about 24 N m while the
direction-dependent Coulomb part stays near a FSm = -36 N m (measured 21.0 and -35.4 N m):
the asymmetry looks unphysical and an offset is named for the two. Against the model holding
the lag the fitted FSm is back near 40 N m (measured 39.6) and the asymmetry is physical; the two-way choice then names it, and the pair
holds with each of its causes passing on top of the other, though neither the asymmetry
(unphysical) nor the lag (the constant unmodelled) passes against the nominal alone.
"""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.campaign.battery import BenchRunner, Place
from jointbench.identification.discrepancy.candidates import joint_parameters
from jointbench.identification.discrepancy.inverse import diagnose_inverse

A, LAG = -0.9, 0.005


@pytest.fixture(scope="module")
def inv():
    log = BenchRunner(20.0).log(Place("bench", "arm6", "axis2"),
                                (("asymmetric_friction", A, {}), ("torque_lag", LAG, {})),
                                10125, False, True)
    return diagnose_inverse(log, diagnosis_settings(log)[0])


def test_the_asymmetry_is_named_in_the_offsets_place(inv):
    """Both hidden effects named, no offset; the offset is listed as left out, with why."""
    assert sorted(c.effect for c in inv.causes) == ["asymmetric_friction", "torque_lag"]
    left = [n for n in inv.not_named if n.effect == "offset"]
    assert left and left[0].kind == "left_out"


def test_each_named_cause_passes_on_top_of_the_other(inv):
    """The claim: each cause's own test passes at its round's level."""
    for c in inv.causes:
        assert c.test.passes, c.effect


def test_the_values_are_the_hidden_ones(inv):
    """The joint fit's asymmetry and lag against the truth (measured -0.908 for -0.9 and
    5.26 ms for 5 ms). The asymmetry within 0.15: about one standard error of its Coulomb
    part over FSm (the folds' jackknife, 4.8 N m over 40 N m); the lag within a fifth."""
    params = dict(joint_parameters(inv.nominal, inv.causes))
    assert params["asymmetric_friction"]["asymmetry"] == pytest.approx(A, abs=0.15)
    assert params["torque_lag"]["lag_s"] == pytest.approx(LAG, rel=0.2)
