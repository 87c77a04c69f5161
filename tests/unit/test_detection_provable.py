"""bench.campaign.detection: the counts of what the data proves, beside the strict ones. A
hidden effect stated as the alternative of a named cause ("one of A or B") counts as found,
and that named cause as no extra one, only where the log's distinguishing visibility between
the two is under SEPARABLE; the strict counts never move."""

from __future__ import annotations

from jointbench.bench.campaign.detection import (SEPARABLE, extra_causes, found_or_inseparable,
                                                 right, stated_inseparable, stated_pairs,
                                                 summary_lines)

ONE_OF = ("one of offset or asymmetric_friction: held out offset explains 80.5 %, "
          "asymmetric_friction 80.7 % of the residual")
LOW, HIGH = 0.4 * SEPARABLE, 2.0 * SEPARABLE


def _pair(**kw) -> dict:
    rec = {"kind": "pair", "effects": ["spring_damping", "asymmetric_friction"],
           "visibilities": [0.3, 0.25], "named": ["offset", "spring_damping"],
           "ambiguity": [ONE_OF], "distinguishing": [None, LOW], "family": "wrist",
           "error": ""}
    return {**rec, **kw}


def test_stated_pairs_from_texts_and_structured_alternatives():
    assert stated_pairs(_pair()) == {frozenset(("offset", "asymmetric_friction"))}
    old = _pair(ambiguity=["offset or asymmetric_friction: this log cannot tell them apart"])
    assert stated_pairs(old) == {frozenset(("offset", "asymmetric_friction"))}
    rec = _pair(ambiguity=[], alternatives=[["offset", "asymmetric_friction"]])
    assert stated_pairs(rec) == {frozenset(("offset", "asymmetric_friction"))}
    assert stated_pairs(_pair(ambiguity=["something else entirely"])) == set()


def test_pair_found_only_where_the_log_cannot_separate_them():
    low = _pair()
    assert not right(low) and found_or_inseparable(low)
    assert stated_inseparable(low, "asymmetric_friction") == "offset"
    high = _pair(distinguishing=[None, HIGH])          # the log could tell them apart
    assert not found_or_inseparable(high)
    silent = _pair(ambiguity=[])                       # named without stating the other
    assert not found_or_inseparable(silent)
    unknown = _pair(distinguishing=[None, None])       # nothing recorded: not credited
    assert not found_or_inseparable(unknown)


def test_both_hidden_uses_the_reducing_effects_distinguishing_visibility():
    """Offset and asymmetric friction both hidden, the asymmetry named with the offset as
    its alternative: the offset's entry has no distinguishing visibility (it reduces to
    nothing), the asymmetry's says whether the log can separate the two."""
    rec = _pair(effects=["offset", "asymmetric_friction"], named=["asymmetric_friction"],
                ambiguity=["one of asymmetric_friction or offset: ..."],
                distinguishing=[None, LOW])
    assert not right(rec) and found_or_inseparable(rec)
    assert not found_or_inseparable(dict(rec, distinguishing=[None, HIGH]))


def test_single_found_when_the_first_named_states_it():
    rec = {"kind": "single", "effects": ["asymmetric_friction"], "visibilities": [0.2],
           "named": ["offset"], "ambiguity": [ONE_OF], "distinguishing": [LOW],
           "family": "x", "error": ""}
    assert not right(rec) and found_or_inseparable(rec)
    assert not found_or_inseparable(dict(rec, distinguishing=[HIGH]))
    other = dict(rec, effects=["backlash"], distinguishing=[None])
    assert not found_or_inseparable(other)
    clean = {"kind": "clean", "effects": [], "visibilities": [], "named": [], "family": "x"}
    assert found_or_inseparable(clean) and not found_or_inseparable(dict(clean,
                                                                         named=["offset"]))


def test_extra_causes_strict_and_provable():
    low = _pair(named=["offset", "spring_damping", "torque_ripple"])
    assert extra_causes(low) == ["offset", "torque_ripple"]
    assert extra_causes(low, provable=True) == ["torque_ripple"]
    high = _pair(distinguishing=[None, HIGH])
    assert extra_causes(high) == extra_causes(high, provable=True) == ["offset"]
    # an offset named beside the asymmetry it stands for is extra whatever it states
    both = _pair(named=["offset", "spring_damping", "asymmetric_friction"])
    assert extra_causes(both) == extra_causes(both, provable=True) == ["offset"]


def test_summary_reports_the_provable_counts_apart():
    recs = [_pair(), _pair(distinguishing=[None, HIGH]),
            _pair(named=["spring_damping", "asymmetric_friction"], ambiguity=[])]
    text = "\n".join(summary_lines(recs))
    # strict counts as they are
    assert "two-effect cases with both visibilities >= 10 %: 3, both named in 1" in text
    assert "logs naming a cause not hidden in them: 2/3 (66.7 %)" in text
    # and apart, what the data proves
    assert "both found in 2/3 (67 %)" in text
    assert "is not extra): 1/3 (33.3 %); more than one such cause: 0" in text
