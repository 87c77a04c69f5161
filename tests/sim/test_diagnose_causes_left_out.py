"""Several named causes whose extended model the forward view rejects (issue 15 item 2): the
later causes are left out in turn, and the answer keeps the ones before them, instead of
naming nothing (bench.analysis.diagnose.run). The forward verdict is replaced here by one that
rejects every model holding a given cause, so that the control flow is tested on a real
two-cause log (a hidden backlash and a 10 N m sensor offset, test_diagnose_heldout)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose import diagnose, run
from jointbench.bench.campaign.battery import Case, run_case
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.discrepancy import Candidate, InverseDiagnosis


@pytest.fixture(scope="module")
def two_causes():
    log = run_case(Case(0, "prototype", None, PAPER_RATE, 4, "backlash", 0.002), duration=30.0)
    return dataclasses.replace(log, tau_m=np.asarray(log.tau_m) + 10.0)


def _rejecting(effect):
    real = run.gain_reason

    def gain_reason(d, before=None):
        if any(c.effect == effect for c in d.causes):
            return f"{effect}'s extended model is worse in the forward view (test)"
        return real(d, before)
    return gain_reason


def test_a_rejected_last_cause_is_left_out_and_the_first_kept(two_causes, monkeypatch):
    # the inverse view names backlash, then offset, on this log: test_diagnose_heldout.py's
    # test_two_causes_are_named_in_order (the same log, diagnosed without the forward view)
    monkeypatch.setattr(run, "gain_reason", _rejecting("offset"))
    d = diagnose(two_causes)
    assert d.verdict == "named" and [c.effect for c in d.causes] == ["backlash"]
    assert "offset left out: offset's extended model is worse" in d.forward_note
    assert "backlash_rad" in d.extended_parameters and "offset" not in d.extended_parameters
    assert d.forward_extended is not None and d.forward_nominal is not None


def test_a_rejected_first_cause_still_names_nothing(two_causes, monkeypatch):
    monkeypatch.setattr(run, "gain_reason", _rejecting("backlash"))
    d = diagnose(two_causes)
    assert d.verdict == "inconclusive" and d.causes == () and d.extended_parameters == {}
    assert "backlash's extended model is worse" in d.overruled


def test_notes_about_a_left_out_cause_go_with_it():
    a, b = (Candidate(effect=e, testable=True) for e in ("offset", "hardening"))
    inv = InverseDiagnosis(nominal=None, candidates=(), causes=(a, b),
                           notes=("offset or asymmetric_friction: ...",
                                  "backlash or hardening: ..."))
    out = run._without_last(inv)
    assert [c.effect for c in out.causes] == ["offset"]
    assert out.notes == ("offset or asymmetric_friction: ...",)
