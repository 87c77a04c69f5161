"""`diagnose` on real data (EMPS, tests/data/emps): identify and extend on the estimation file,
cross-validate on the other file (issue: real measured data).

References: the EMPS README's published figures. The reference inverse model leaves 4.12 % on
the estimation data; its direction-dependent friction variant 3.19 %. Our nominal model has no
offset (`offset` is one of the candidate effects), so it starts higher.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from jointbench.bench.cli import main
from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose import cross_validate
from jointbench.identification.log import read_log

DATA = Path(__file__).parent / "data" / "emps"
GTAU = 35.15065188   # N/V: the pulses column holds volts at the drive input (EMPS README)


@pytest.fixture(scope="module")
def emps():
    est = read_log(DATA / "emps_estimation.csv")
    val = read_log(DATA / "emps_validation_pulses.csv")
    return est, val, diagnose(est)


def test_emps_named_cause_is_asymmetric_friction(emps):
    _, _, d = emps
    assert d.named_cause == "asymmetric_friction"
    untested = {c.effect for c in d.inverse.candidates if not c.testable}
    assert untested == {"gravity", "link_coulomb", "backlash", "spring_damping", "hardening"}
    before, after = d.inverse_before_after
    # The published asymmetric variant (5 parameters) leaves 3.19 %; ours (4) within 0.3 %.
    assert after == pytest.approx(3.19, abs=0.3)
    assert before / after >= 2.0
    # The forward view (closed-loop replay) improves on the estimation file too.
    assert d.forward_extended.tau_rel_pct < d.forward_nominal.tau_rel_pct


def test_emps_cross_validated_gain(emps):
    est, val, d = emps
    xv = cross_validate(d, val, GTAU * val.extra["pulses_N"], "motor")
    inv_n, inv_e = xv["inverse"]["nominal"]["motor"], xv["inverse"]["extended"]["motor"]
    assert inv_n / inv_e >= 1.5
    fwd_n, fwd_e = xv["forward"]["nominal"], xv["forward"]["extended"]
    assert fwd_e["tau_rel_pct"] < fwd_n["tau_rel_pct"]
    assert fwd_e["q_m_rms"] < fwd_n["q_m_rms"]


def test_emps_cli_cross_validation_json(tmp_path, capsys):
    code = main(["diagnose", str(DATA / "emps_estimation.csv"), "--json", "--no-forward",
                 "--validate", str(DATA / "emps_validation_pulses.csv"),
                 "--disturbance-column", "pulses_N", "--disturbance-gain", str(GTAU),
                 "--disturbance-at", "motor"])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["named_cause"] == "asymmetric_friction"
    assert set(doc["cross_validation"]) == {"file", "inverse", "forward"}
    assert set(doc["untested"]) == {"gravity", "link_coulomb", "backlash", "spring_damping",
                                    "hardening"}


def test_emps_names_both_causes(emps):
    """Issue 15: on the estimation file asymmetric friction and an offset are both there; the
    offset, tested on top of the asymmetric friction, is named second (measured: held out
    22 % of what remains, t = 4.1, motor equation 3.23 % -> 2.95 %)."""
    _, _, d = emps
    assert [c.effect for c in d.causes] == ["asymmetric_friction", "offset"]
    second = d.causes[1]
    assert second.base[0][0] == "asymmetric_friction" and second.gain > 1


def test_emps_extended_model_holds_both_causes_from_one_fit(emps):
    """Issue 15: extended.xml holds every named cause with its values from one fit of the
    nominal extended by all of them. Fitted alone, the asymmetric friction takes up part of
    the offset (-0.091); with the offset beside it, -0.177. The joint values are those of the
    last cause's fit (its columns stack the first's), and the forward view with both improves
    on the estimation file (measured 7.83 % -> 4.49 %, against 4.65 % with the first alone)."""
    from jointbench.identification.discrepancy.candidates import joint_parameters
    _, _, d = emps
    joint = dict(joint_parameters(d.inverse.nominal, d.causes))
    assert set(joint) == {"asymmetric_friction", "offset"}
    first_alone = d.causes[0].parameters["asymmetry"]
    assert joint["asymmetric_friction"]["asymmetry"] != pytest.approx(first_alone, rel=0.2)
    assert d.extended_parameters["asymmetry"] == joint["asymmetric_friction"]["asymmetry"]
    assert d.extended_parameters["offset"] == joint["offset"]["offset"]
    assert joint["offset"]["offset"] == d.causes[1].parameters["offset"]
    assert d.forward_extended.tau_rel_pct < 0.6 * d.forward_nominal.tau_rel_pct
