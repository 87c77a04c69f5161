"""A drive lag whose corner lies below the axis' locked first mode: the lab rig's voltage
drive under a P loop still drives the axis, and `diagnose` names the lag and finds its time
constant (the lag's corner is no physical bound; the held-out test and the replays decide)."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.testing import LAB_PLACES, LAB_RIG, LabRigRunner


@pytest.mark.parametrize("seed", [3, 11])
def test_a_lag_slower_than_the_first_mode_is_named(seed):
    # corner 1 / (2 pi T) at two thirds of the first mode f1: w1 T = 1.5 > 1
    T = 1.5 / (2 * np.pi * LAB_RIG.family.f1_hz)
    log = LabRigRunner(duration=40.0).log(LAB_PLACES[0], (("torque_lag", T, {}),), seed,
                                          True, True)
    d = diagnose(log)
    assert [c.effect for c in d.causes] == ["torque_lag"]
    # the named lag is one the first-mode prior refused: its corner lies below the mode
    # (the fit's T runs about a third above the rig's hidden one, a bias of the lead columns
    # on this voltage drive not yet explained, so the test bounds it by the mode and by twice
    # the truth, not to a per cent)
    lag = d.extended_parameters["lag_s"]
    assert 1.0 / (2 * np.pi * LAB_RIG.family.f1_hz) < lag < 2 * T
