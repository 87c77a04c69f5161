"""The clipped log's pieces of `diagnose` (bench.analysis.diagnose.clipped and forward):
the segments the forward view judges before the loop reaches its limit, how differently a
replay reaches it, and the inverse view's tests at half their level."""

from types import SimpleNamespace

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.clipped import VIEWS, split_level
from jointbench.bench.analysis.diagnose.forward import before_limit, limit_mismatch
from jointbench.identification.discrepancy import InverseDiagnosis
from jointbench.identification.discrepancy.candidates import Candidate
from jointbench.identification.discrepancy.heldout import SEGMENTS

N = 40 * 50   # 50 samples a segment


def _log(tau, tau_max=10.0):
    return SimpleNamespace(tau_m=np.asarray(tau, float), meta={"tau_max": repr(tau_max)})


def test_before_limit_stops_at_the_first_segment_at_the_limit():
    tau = np.ones(N)
    assert before_limit(_log(tau)) is None
    hit = tau.copy()
    hit[12 * 50 + 7] = -10.0          # segment 12 of the log
    hit[30 * 50] = 10.0
    keep = before_limit(_log(hit))
    assert keep.tolist() == [k < 12 for k in range(SEGMENTS)]
    assert before_limit(_log(hit, tau_max=10.5)) is None
    assert before_limit(SimpleNamespace(tau_m=hit, meta={})) is None   # no tau_max


def test_limit_mismatch_counts_per_segment_not_per_sample():
    tau = np.zeros(N)
    tau[::10] = 10.0                 # 5 samples a segment at the limit
    shifted = np.roll(tau, 3)        # the same clips at another phase: no mismatch
    assert limit_mismatch(_log(tau), shifted) == 0.0
    assert limit_mismatch(_log(tau), np.zeros(N)) == pytest.approx(10.0)   # 200 of 2000
    assert np.isnan(limit_mismatch(SimpleNamespace(tau_m=tau, meta={}), tau))


def _cand(effect, p, round_=1, alpha=1e-3 / 8):
    return Candidate(effect=effect, testable=True, heldout_pct=40.0, t_stat=5.0, p_heldout=p,
                     alpha=alpha, round=round_)


def test_split_level_keeps_the_causes_that_pass_at_half_their_level():
    level = 1e-3 / 8
    strong, weak = _cand("torque_lag", level / 10), _cand("offset", 0.7 * level, 2)
    inv = InverseDiagnosis(nominal=None, candidates=(strong, weak), causes=(strong, weak),
                           rounds=((strong, weak), (weak,)))
    out = split_level(inv)
    assert [c.effect for c in out.causes] == ["torque_lag"]
    assert out.causes[0].level == pytest.approx(level / VIEWS)
    dropped = {n.effect: n for n in out.not_named}
    assert dropped["offset"].kind == "failed" and "1/2 of its level" in dropped["offset"].why
    # the first cause failing at half its level leaves nothing named: the later ones were
    # tested on top of it
    first, then = _cand("torque_lag", 0.7 * level), _cand("backlash", level / 10, 2)
    inv = InverseDiagnosis(nominal=None, candidates=(first, then), causes=(first, then))
    assert split_level(inv).causes == ()
