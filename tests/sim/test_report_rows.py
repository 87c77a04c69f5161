"""Rows of the reports on real identifications: the parameter table beside a near-zero truth
(columns never run together), and the demo's discrepancy rows (diagnose's candidates), which
must stay on their branch across the differences another machine makes in a quantised
simulation."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from jointbench.identification.paper_tables import parameter_table

# An unphysical fit's branch: what encoder flips (another machine's last bits) move it by, a
# few 1e-3, is well inside; the nearest other branch, a factor of 2 or more away, is far outside.
BRANCH = 1e-2


def test_near_zero_truth_does_not_run_columns_together(prototype_log, prototype_joint_motor):
    result = prototype_joint_motor
    truth = {**prototype_log.truth(), "MY": -2.33147e-15, "MX": 0.0}
    rows = {line.split()[0]: line for line in parameter_table(result, truth).splitlines()[2:]}
    for name in ("MX", "MY"):
        fields = rows[name].split()
        # name, X, 2 sigma, % sigma_r, truth, error % ('-': no % of a zero truth), unit
        assert fields[5] == "-" and fields[-2:] == ["kg", "m"] and len(fields) == 8, rows[name]
    assert re.search(r"\s-2\.331e-15\s+-\s", rows["MY"])  # shortened to fit, then a space
    huge = parameter_table(result, {**truth, "MY": -1e-9})  # a tiny truth: a huge error %
    line = [x for x in huge.splitlines() if x.startswith("MY")][0]
    assert len(line.split()) == 8 and "e+" in line.split()[5]


@pytest.fixture(scope="module")
def backlash_log():
    from jointbench.bench.effects import HiddenEffect
    from jointbench.bench.sim.experiment import run_experiment

    return run_experiment("prototype", duration=60.0, seed=1,
                          effect=HiddenEffect("backlash", 0.002)).log


def _candidates(log) -> dict[str, dict[str, float]]:
    from jointbench.bench.analysis.diagnose import diagnose

    return {c.effect: {k: float(v) for k, v in c.parameters.items()}
            for c in diagnose(log, forward=False).inverse.candidates}


def test_demo_discrepancy_rows_survive_machine_level_differences(backlash_log):
    """The demo's example (README): the hardening fit, unphysical (K < 0 along the direction
    where a hardening with K -> 0 is a backlash), stays on its branch after one-count encoder
    flips at 40 samples (what another CPU's last bits can do to a quantised simulation); the
    README's older row (ratio +14.63, K +1306) is another branch.

    The branch is told by what the truth fixes, not by the fit's printed digits: the fit is
    unphysical (K < 0, a negative hardening ratio, the other branch has both positive), and
    its deflection is the hidden backlash's 0.002 rad (the hardening sets in where the gap
    closes; measured 3 % short) within 10 %, about one and a half steps of the geometric
    search grid (6.4 % apart, identification/effects/hardening.py) that the bounded
    refinement starts from. The flips are told apart at
    BRANCH (1 %): a quantised closed loop simulated on another CPU (another SIMD path in
    MuJoCo, another BLAS kernel) flips encoder counts as the flips below do, and those move
    this fit by a few 1e-3 (measured 4e-3); the other branch is over a factor of 10 away
    in the ratio and in K, with the opposite sign."""
    rows = _candidates(backlash_log)
    hardening = rows["hardening"]
    assert hardening["K"] < 0 and hardening["hardening_ratio"] < 0, hardening
    assert hardening["deflection_rad"] == pytest.approx(0.002, rel=0.1), hardening
    rng = np.random.default_rng(3)
    q, qm = backlash_log.q.copy(), backlash_log.q_m.copy()
    for x, res in ((q, 2 * np.pi / 2**20), (qm, 2 * np.pi / (2**17 * 100))):
        idx = rng.choice(len(x), 20, replace=False)
        x[idx] += rng.choice([-1.0, 1.0], 20) * res
    flipped = _candidates(dataclasses.replace(backlash_log, q=q, q_m=qm))
    # Since issue 14's nominal (FS, the chain's column q(4)) the unphysical hardening fit sits
    # on a flatter branch: the flips move it by 4e-3 (measured), still far from another branch
    # (the older one is over a factor of 10 away in K).
    for effect, rel in (("hardening", BRANCH), ("backlash", 1e-4)):
        assert flipped[effect] == pytest.approx(rows[effect], rel=rel), effect
