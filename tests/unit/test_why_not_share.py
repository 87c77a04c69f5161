"""A candidate whose segment t passes its bar but whose held-out share over every row is not
positive is not significant, and its `why_not` says which rule failed it."""

from __future__ import annotations

from jointbench.identification.discrepancy.candidates import Candidate
from jointbench.identification.discrepancy.heldout import bar, t_bar


def _candidate(share: float, t: float, p: float) -> Candidate:
    return Candidate(effect="offset", testable=True, heldout_pct=share, acts_pct=share,
                     t_stat=t, p_heldout=p, alpha=bar(7))


def test_t_above_bar_without_share_states_the_share_rule():
    level = bar(7)
    c = _candidate(-0.104, t_bar(level) + 3.5, level / 1e4)
    assert not c.significant
    assert not c.test.passes
    assert "its t passes the bar, but a cause must also explain a positive share" in c.why_not


def test_failing_t_has_no_share_note():
    level = bar(7)
    for share in (-0.5, 2.0):
        c = _candidate(share, t_bar(level) - 1.0, level * 10)
        assert not c.significant
        assert "positive share" not in c.why_not
    assert _candidate(2.0, t_bar(level) + 1.0, level / 10).why_not == ""
