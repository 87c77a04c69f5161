"""A torque lag beside a spring damping on the pendulum (independent simulator, 5.94 ms and
D = 3.97 N m s/rad, velocity feed-forward, no noise, drawn as the battery draws a pair of 26 %
and 23 % visibility): the lag drives the loop into its limit and two fifths of the torque
samples sit at tau_max. On the rows out of the clip's reach, a few per cent of the
experiment, the spring damping passes and nothing else does: there the motor swings slowly
and the lag, whose evidence grows with frequency, has nothing to show. Those rows cannot say
that the experiment holds no further cause (bench.analysis.diagnose.clipped.stopped_short),
so the every-row view is run too; it names the damping and the lag, and the forward view
confirms that reading (a replay at the limit, or the loop's stability with the lag after the
causes the first view names). The first view's answer alone is the spring damping."""

from __future__ import annotations

import json

import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.analysis.diagnose.report import dumps
from jointbench.testing import INDEP_PLACES, IndepRunner

pytestmark = pytest.mark.slow

PENDULUM = INDEP_PLACES[3]
LAG_S = 5.9385e-3
D = 3.9742
SEED = 1221369936


@pytest.fixture(scope="module")
def answer():
    log = IndepRunner(40.0).log(PENDULUM, (("torque_lag", LAG_S, {}), ("spring_damping", D, {})),
                                SEED, True, False)
    d = diagnose(log)
    return d, json.loads(dumps(d))


def test_the_first_view_names_the_damping_alone_on_few_rows(answer):
    _, doc = answer
    clipped = doc["clipped"]
    assert clipped["clipped_pct"] > 20 and clipped["rows_kept"] < 0.5 * clipped["rows"]
    # there the damping explains several times what the lag does
    assert clipped["heldout_pct"]["spring_damping"] > 3 * clipped["heldout_pct"]["torque_lag"]


def test_the_lag_beside_the_damping_is_named_on_every_row(answer):
    _, doc = answer
    assert doc["verdict"] == "named"
    assert sorted(doc["named_causes"]) == ["spring_damping", "torque_lag"]
    assert doc["clipped"]["named_by"] == "every row"
    assert failing_claims(doc) == []
    values = {c["effect"]: c["parameters"] for c in doc["causes"]}
    # the lag's time constant: its fold values' spread is a few percent
    assert values["torque_lag"]["lag_s"] == pytest.approx(LAG_S, rel=0.1)
    # the damping's fold fits agree within 2 % but its every-row value is biased up by a
    # fifth (the clipped torque taken as applied, the lag's joint fit): its size, not more
    assert values["spring_damping"]["D"] == pytest.approx(D, rel=0.25)
