"""A torque lag beside a constant torque offset on the pendulum (independent simulator,
3.73 ms and -2.48 N m, no feed-forward, no noise, drawn as the battery draws a pair of 17 %
and 13 % visibility): the lag drives the loop into its limit and a third of the torque
samples sit at tau_max. On every row, the clipped torque taken as applied, the offset passes
first and the lag on top of it. No closed-loop replay from rest reaches the limit cycle, with
the offset or with both, so the replay confirms neither (near the loop's stability onset it
does with the strengths rounded to five digits: whether a replay from rest starts the cycle
is not a property of the model); the loop linearised with the lag
grows where the nominal's decays, at the log's clipped frequency, and the offset passes again
on top of the model holding the lag (bench.analysis.diagnose.clipped.held_before_lag): the
loop's stability confirms the set, and both are named with their values. Without the on-top
test the loop's stability was asked of a lag named first only, and the answer was
"inconclusive", the offset judged alone by the replay."""

from __future__ import annotations

import json

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.analysis.diagnose.report import dumps
from jointbench.bench.analysis.diagnose.verdict import loop_cycle, replay_at_limit
from jointbench.testing import INDEP_PLACES, IndepRunner

pytestmark = pytest.mark.slow

PENDULUM = INDEP_PLACES[3]
LAG_S = 0.0037282201534464005
OFFSET = -2.475090102129145
SEED = 587854499


@pytest.fixture(scope="module")
def answer():
    log = IndepRunner(40.0).log(PENDULUM, (("torque_lag", LAG_S, {}), ("offset", OFFSET, {})),
                                SEED, False, False)
    d = diagnose(log)
    return d, json.loads(dumps(d))


def test_the_offset_and_the_lag_are_named_confirmed_by_the_loop(answer):
    d, doc = answer
    assert doc["verdict"] == "named"
    assert set(doc["named_causes"]) == {"offset", "torque_lag"}
    assert failing_claims(doc) == []
    clipped = doc["clipped"]
    assert clipped["clipped_pct"] > 20 and clipped["named_by"] == "every row"
    # the values: the folds' spread is a few percent of each (no noise)
    params = {c["effect"]: c["parameters"] for c in doc["causes"]}
    assert params["torque_lag"]["lag_s"] == pytest.approx(LAG_S, rel=0.1)
    assert params["offset"]["offset"] == pytest.approx(OFFSET, rel=0.1)
    # what confirms them: not a replay at the limit, the loop's stability with the lag, the
    # offset passing on top of the model holding the lag
    assert not replay_at_limit(d)
    cycle = loop_cycle(d)
    assert cycle is not None and cycle.confirms
    [held] = clipped["before_lag"]
    assert held["effect"] == "offset" and held["t"] > held["t_bar"]
    assert "on top of the model holding the lag" in doc["forward_note"]
