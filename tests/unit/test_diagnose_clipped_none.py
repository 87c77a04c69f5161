"""'none' is not said from a minority of the experiment (bench.analysis.diagnose.verdict.
clipped_reason): when the rows out of reach of clipped torque samples are under half of the
log's, a diagnosis without a cause is 'inconclusive' (seed-2026 battery #62: a torque lag that
drives the pendulum's loop into its torque limit keeps 60 of 820 rows)."""

from types import SimpleNamespace

import numpy as np

from jointbench.bench.analysis.diagnose.verdict import USABLE_MIN, clipped_reason


def _diagnosis(keep, causes=()):
    sig = SimpleNamespace(keep=None if keep is None else np.asarray(keep, bool))
    return SimpleNamespace(inverse=SimpleNamespace(causes=tuple(causes),
                                                   nominal=SimpleNamespace(sig=sig)))


def test_none_from_a_minority_of_the_rows_is_inconclusive():
    keep = np.zeros(820, bool)
    keep[:60] = True
    why = clipped_reason(_diagnosis(keep))
    assert "only 60 of 820 regression rows (7.32 %)" in why


def test_none_stands_on_a_majority_or_an_unclipped_log():
    n = 264
    at_bar = np.arange(n) < int(np.ceil(USABLE_MIN * n))     # exactly the bar: kept
    assert clipped_reason(_diagnosis(at_bar)) == ""
    assert clipped_reason(_diagnosis(None)) == ""


def test_a_named_cause_is_not_overruled_by_the_clipping():
    keep = np.zeros(100, bool)
    keep[:10] = True
    assert clipped_reason(_diagnosis(keep, causes=("torque_lag",))) == ""
