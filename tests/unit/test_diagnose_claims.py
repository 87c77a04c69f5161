"""Naming is a claim with evidence (bench.analysis.diagnose.claims and the tests a named
cause carries, identification.discrepancy.candidates.HeldOutTest): the check over a diagnose JSON
flags every named cause whose test is missing or fails, and a cause's test is the view that
passed."""

from __future__ import annotations

import pytest

from jointbench.bench.analysis.diagnose.claims import claim_fails, failing_claims
from jointbench.identification.discrepancy import Candidate
from jointbench.identification.discrepancy.candidates import CHOOSER, SecondView, HeldOutTest
from jointbench.identification.discrepancy.heldout import t_bar
from jointbench.identification.discrepancy.inverse import (FLOOR, Alternative, _passes)

LEVEL = 1e-3 / 7   # a second round's Holm level (7 effects left)


def _test(t, p, share, level=LEVEL, view=CHOOSER):
    return HeldOutTest(view, share, t, p, level).to_json()


def _cause(effect, round_, test):
    return {"effect": effect, "round": round_, "parameters": {}, "test": test,
            **{k: test[k] for k in ("heldout_pct", "t", "p_heldout", "alpha")}}


def _doc(*causes, floor=100 * FLOOR):
    return {"named_cause": causes[0]["effect"] if causes else "none",
            "named_causes": [c["effect"] for c in causes], "causes": list(causes),
            "floor_pct": floor}


FIRST = _cause("spring_damping", 1, _test(17.9, 1e-16, 70.4, 1e-3 / 8))


def test_every_cause_with_a_passing_test_passes():
    lag = _cause("torque_lag", 2, _test(7.49, 2.8e-8, 6.19))
    assert failing_claims(_doc(FIRST, lag)) == []
    assert failing_claims(_doc()) == []


def test_a_cause_whose_own_test_fails_is_flagged():
    # the lab flexible joint's torque lag: second, its second-round test t = -0.46, 2.9 %
    lag = _cause("torque_lag", 2, _test(-0.46, 0.68, 2.9))
    (msg,) = failing_claims(_doc(FIRST, lag))
    assert msg.startswith("torque_lag:") and "not under its level" in msg


def test_a_cause_without_a_test_or_an_entry_is_flagged():
    old = dict(_cause("torque_lag", 2, _test(7.49, 2.8e-8, 6.19)))
    del old["test"]
    assert failing_claims(_doc(FIRST, old)) == ["torque_lag: no test"]
    doc = _doc(FIRST)
    doc["named_causes"].append("offset")
    assert any("offset: named without an entry" in m for m in failing_claims(doc))


def test_a_later_cause_under_the_floor_is_flagged_a_first_one_is_not():
    small = _test(6.0, 1e-8, 100 * FLOOR - 1)
    assert failing_claims(_doc(FIRST, _cause("torque_ripple", 2, small)))
    assert failing_claims(_doc(_cause("torque_ripple", 1, small))) == []


def test_the_entry_s_numbers_must_be_its_test_s():
    lag = _cause("torque_lag", 2, _test(7.49, 2.8e-8, 6.19))
    lag["t"] = 3.17   # the chooser's band's failing t shown beside the wide band's test
    (msg,) = failing_claims(_doc(FIRST, lag))
    assert "its t 3.17 is not its test's" in msg


def test_the_check_reads_the_numbers_not_the_flag():
    bad = _test(3.0, 2e-3, 6.0)
    bad["passes"] = True
    assert "not under its level" in claim_fails(bad)
    at_bar = _test(t_bar(LEVEL) - 0.01, LEVEL / 2, 6.0)
    assert "under its bar" in claim_fails(at_bar)


def test_runs_and_model_answers():
    lag = _cause("torque_lag", 2, _test(-0.46, 0.68, 2.9))
    runs = {"runs": [{"name": "a", **_doc(FIRST)}, {"name": "b", **_doc(FIRST, lag)}],
            "supported": ["spring_damping", "torque_lag"]}
    msgs = failing_claims(runs)
    assert any(m.startswith("run b: torque_lag") for m in msgs)
    assert "torque_lag: supported but not named on a" in msgs
    model = {"model": "x.xml", "extended_effects": [], "named_causes": ["link_coulomb",
                                                                         "spring_damping"],
             "parameter_errors": {"FS": {"significant": True}}, "causes": [FIRST]}
    assert failing_claims(model) == []
    model["parameter_errors"]["FS"]["significant"] = False
    assert failing_claims(model) == [
        "link_coulomb: named without a significant parameter error FS"]


def _lag(p, second=None):
    return Candidate(effect="torque_lag", testable=True, heldout_pct=2.9, t_stat=-0.46,
                     p_heldout=p, alpha=LEVEL, views=2, second=second, round=2)


def test_a_lag_confirmed_in_the_wide_band_is_named_on_that_band_s_test():
    wide = SecondView(band="wide band", heldout_pct=6.2, t_stat=7.5, p_heldout=2.8e-8,
                      value=5e-4, agree=True, detail="")
    c = _lag(0.68, wide)
    assert c.significant and c.test.view == "wide band" and c.test.passes
    assert c.test.level == LEVEL / 2 and c.test.t == 7.5
    # without the confirmation its test is the chooser's band's, failing
    c = _lag(0.68, SecondView(**{**wide.__dict__, "agree": False}))
    assert not c.significant and c.test.view == CHOOSER and not c.test.passes


@pytest.mark.parametrize("share,acts,round_,named", [
    (6.0, float("nan"), 2, True), (4.0, float("nan"), 2, False), (4.0, float("nan"), 1, True),
    (4.0, 8.0, 2, True),     # a link-side cause: 8 % of the link equation's residual
    (6.0, 4.0, 2, False)])
def test_the_floor_holds_for_later_rounds_over_the_equations_it_acts_in(share, acts, round_,
                                                                         named):
    c = Candidate(effect="hardening", testable=True, heldout_pct=share, acts_pct=acts,
                  t_stat=6.0, p_heldout=1e-8, alpha=LEVEL, round=round_)
    assert _passes(c) is named
    doc = _doc(FIRST, _cause("hardening", round_, c.test.to_json()))
    assert (failing_claims(doc) == []) is (named or round_ == 1)


def test_one_of_a_or_b_is_not_said_twice():
    a = Alternative("offset", "asymmetric_friction", 79.2, 79.2, -0.43, 0.43)
    assert a.describe().startswith("one of offset or asymmetric_friction: held out offset "
                                   "explains 79.2 %, asymmetric_friction 79.2 %")
    assert a.stated_in(("offset or asymmetric_friction: this log cannot tell them apart",))
    assert not a.stated_in(("backlash or hardening: this log cannot tell them apart",))


def _named(effect, round_, before=()):
    return Candidate(effect=effect, testable=True, heldout_pct=40.0, t_stat=9.0,
                     p_heldout=1e-10, alpha=1e-3 / (9 - round_), round=round_,
                     base=tuple((b, {}) for b in before))


@pytest.mark.parametrize("weak,kept", [
    ((), ("offset", "backlash", "torque_ripple")),
    (("backlash",), ("offset", "torque_ripple")),
    (("backlash", "torque_ripple"), ("offset", "torque_ripple")),   # the weaker goes first
])
def test_more_than_two_causes_each_pass_against_all_the_others(monkeypatch, weak, kept):
    """The leave-one-out test (inverse._leave_one_out): a cause that does not pass against
    the model holding all the others is dropped, the weakest first, the others fitted again
    and tested again; with two left the rounds' own tests stand."""
    from jointbench.identification.discrepancy import inverse

    strength = {"backlash": 2.0, "torque_ripple": 3.0}

    def against(nom, c, others, band):
        alone = len(others) < 2   # in the refitted chain, or with two left
        fails = c.effect in weak and not alone
        t = strength.get(c.effect, 9.0) if fails else 9.0
        return Candidate(effect=c.effect, testable=True, heldout_pct=20.0, t_stat=t,
                         p_heldout=0.3 if fails else 1e-10, alpha=c.alpha, round=c.round,
                         base=tuple(others))

    monkeypatch.setattr(inverse, "_against", against)
    causes = (_named("offset", 1), _named("backlash", 2, ("offset",)),
              _named("torque_ripple", 3, ("offset", "backlash")))
    out, dropped = inverse._leave_one_out(None, causes, None)
    assert tuple(c.effect for c in out) == kept
    assert [d.effect for d in dropped] == [e for e in ("backlash",) if weak]
    assert all(d.kind == "left_out" and "all the others" in d.why for d in dropped)


def test_a_deflection_that_never_changes_is_refused_with_the_reason():
    """A link that moves with its motor as one body (q_m - q constant, e.g. a spring damped
    stiff) leaves eq. (5)'s effects untestable: a clear ValueError, not a division by zero."""
    import numpy as np

    from jointbench.identification.discrepancy.inverse import diagnose_inverse
    from jointbench.identification.filtering import FilterSettings
    from jointbench.identification.log import Log

    t = np.arange(4000) / 500.0
    qm = np.sin(2 * np.pi * 0.5 * t)
    log = Log(t=t, q_m=qm, q=qm - 0.01, tau_m=np.cos(2 * np.pi * 0.5 * t), path="rigid.csv")
    with pytest.raises(ValueError, match="rigid.csv: the deflection q_m - q never changes"):
        diagnose_inverse(log, FilterSettings(wn=100.0, m=4, Nd=10, ts=t[1]))


def test_one_of_a_or_b_reads_both_heads():
    from jointbench.identification.discrepancy.inverse import one_of
    pair = {"offset", "asymmetric_friction"}
    assert one_of("one of offset or asymmetric_friction: this log cannot tell them apart") \
        == pair
    assert one_of("offset or asymmetric_friction: this log carries a part of each") == pair
    assert one_of("no effect is significant: the best, offset or not") == frozenset()
    nested = Alternative("offset", "asymmetric_friction", 80.5, 80.7, -2.1, 1.19,
                         how="nested", text="one of offset or asymmetric_friction: ...")
    assert nested.describe() == nested.to_json()["text"] == nested.of_cause()["text"]
    assert nested.stated_in((nested.text,))
    assert nested.of_cause()["effect"] == "asymmetric_friction"


def _with_alternative(doc, named="spring_damping", other="offset", in_entry=True, top=True):
    alt = Alternative(named, other, 70.4, 70.1, 0.3, -0.2)
    if top:
        doc["alternatives"] = [alt.to_json()]
    for c in doc["causes"]:
        c["alternatives"] = [alt.of_cause()] if in_entry and c["effect"] == named else []
    return doc


def test_one_of_a_or_b_is_one_claim_stated_alike_at_the_top_and_in_the_entry():
    assert failing_claims(_with_alternative(_doc(FIRST))) == []
    (msg,) = failing_claims(_with_alternative(_doc(FIRST), in_entry=False))
    assert "not in spring_damping's entry" in msg
    (msg,) = failing_claims(_with_alternative(_doc(FIRST), top=False))
    assert "is not among the alternatives" in msg
    lag = _cause("torque_lag", 2, _test(7.49, 2.8e-8, 6.19))
    msgs = failing_claims(_with_alternative(_doc(FIRST, lag), other="torque_lag"))
    assert msgs == ["one of spring_damping or torque_lag: torque_lag is named as well"]
