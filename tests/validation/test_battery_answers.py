"""The measuring battery's record (docs/battery_cases.json, written by benchmarks/battery.py
and copied there with its figures) carries each case's `diagnose --json` answer: no named
cause in it may lack a passing test (bench.analysis.diagnose.claims.failing_claims, redone
here on the stored numbers rather than read from the record's own verdict)."""

import json
from pathlib import Path

import pytest

from jointbench.bench.analysis.diagnose.claims import failing_claims

RECORD = Path(__file__).resolve().parents[2] / "docs" / "battery_cases.json"


@pytest.fixture(scope="module")
def cases() -> list[dict]:
    doc = json.loads(RECORD.read_text())
    assert isinstance(doc.get("battery", {}).get("seed"), int), "the record names its seed"
    return doc["cases"]


def test_every_case_that_ran_keeps_its_answer(cases):
    ran = [c for c in cases if not c["error"]]
    assert ran, "the record holds cases"
    for c in ran:
        assert c["answer"].get("named_causes") == c["named"], f"case #{c['index']}"


def test_no_named_cause_of_the_battery_fails_its_test(cases):
    failing = {f"#{c['index']}": failing_claims(c["answer"]) for c in cases if not c["error"]}
    assert {k: v for k, v in failing.items() if v} == {}


def test_the_check_reads_a_failing_claim_in_the_record_form(cases):
    """The same check, on a case of the record whose first named cause's p-value is put
    above its level, finds it: the test above can fail."""
    named = [c for c in cases if not c["error"] and c["named"]]
    assert named, "the record names causes somewhere"
    answer = json.loads(json.dumps(named[0]["answer"]))
    first = answer["causes"][0]
    first["test"]["p_heldout"] = first["p_heldout"] = 2 * first["test"]["alpha"]
    assert failing_claims(answer)
