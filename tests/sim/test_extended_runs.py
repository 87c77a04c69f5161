"""Every model `diagnose` writes runs (issue 15, item 3): an extended MJCF holding any effect
of docs/effects.md, or several, on a revolute two-mass axis or a prismatic rigid one (EMPS),
runs under `jointbench simulate --model X.xml` and `simulate --replay LOG --model X.xml`,
and the units follow the axis (m and N on a slide)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from jointbench.bench.analysis.diagnose import diagnose, summary_text
from jointbench.bench.analysis.diagnose.run import extended_parameters
from jointbench.bench.cli import main
from jointbench.bench.effects import axis_key, write_effects
from jointbench.bench.sim import nominal as nominal_axes
from jointbench.identification.discrepancy import RIGID_TESTS
from jointbench.identification.effects import EFFECTS
from jointbench.identification.log import read_log

EMPS = Path(__file__).parents[1] / "data" / "emps"
# The prototype's Table 1 values (models/prototype_axis.xml, rounded).
PROTOTYPE = dict(Jm=174.8, FVm=235.9, FSm=41.4, K=20341.0, JL=47.45, FV=83.15, FS=8.46,
                 MX=-0.724, MY=-53.42)
# Identified parameters of each effect as `diagnose` reports them (identification.effects),
# at a strength the bench hides: every effect of docs/effects.md.
EFFECT_PARAMETERS = {
    "gravity": {"MX": -0.724, "MY": -53.42},
    "link_coulomb": {"FS": 8.46},
    "torque_ripple": {"ripple_amplitude": 40.0, "ripple_period_rad": 0.0166,
                      "ripple_phase_rad": 0.3},
    "backlash": {"backlash_rad": 0.002},
    "spring_damping": {"D": 300.0},
    "torque_lag": {"lag_s": 0.008},
    "hardening": {"hardening_ratio": 1.5, "deflection_rad": 0.003},
    "offset": {"offset": 20.0},
    "asymmetric_friction": {"asymmetry": 0.3, "FVm": 235.9, "FSm": 41.4},
}


def _run(*args: str) -> int:
    return main(["simulate", "--quiet", *args])


@pytest.fixture(scope="module")
def prototype_log(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("log") / "proto.csv"
    assert _run("--model", "prototype", "--duration", "6", "--out", str(out)) == 0
    return out


def _two_mass(effects: list[tuple[str, dict]]):
    spec = nominal_axes.two_mass_axis(**PROTOTYPE, timestep=1 / 350.87, tau_max=3000.0,
                                      name="axis1")
    write_effects(spec, "axis1", effects, PROTOTYPE["K"])
    return spec


def test_every_case_is_a_registered_effect():
    assert set(EFFECT_PARAMETERS) <= set(EFFECTS)


@pytest.mark.parametrize("effect", list(EFFECT_PARAMETERS))
def test_extended_model_of_every_effect_runs(effect, prototype_log, tmp_path):
    xml = tmp_path / "extended.xml"
    nominal_axes.write_xml(_two_mass([(effect, EFFECT_PARAMETERS[effect])]), xml)
    sim = tmp_path / "sim.csv"
    assert _run("--model", str(xml), "--duration", "4", "--out", str(sim)) == 0
    assert read_log(sim).q is not None
    assert _run("--replay", str(prototype_log), "--model", str(xml),
                "--out", str(tmp_path / "replay.csv")) == 0


def test_several_effects_in_one_model_run(prototype_log, tmp_path):
    xml = tmp_path / "extended.xml"
    names = ["backlash", "torque_ripple", "asymmetric_friction", "offset", "torque_lag"]
    nominal_axes.write_xml(_two_mass([(n, EFFECT_PARAMETERS[n]) for n in names]), xml)
    text = xml.read_text()
    for element in ("axis1_ripple", "axis1_asymmetry", "axis1_offset", "filterexact"):
        assert element in text
    assert _run("--replay", str(prototype_log), "--model", str(xml),
                "--out", str(tmp_path / "replay.csv")) == 0
    with pytest.raises(ValueError, match="named twice"):
        _two_mass([("offset", {"offset": 1.0}), ("offset", {"offset": 2.0})])


def test_zero_lag_writes_no_filter(prototype_log, tmp_path):
    # diagnose reports lag_s = 0 when no lag fits (EMPS): MuJoCo's filter with a zero time
    # constant diverged at the first step before.
    xml = tmp_path / "extended.xml"
    nominal_axes.write_xml(_two_mass([("torque_lag", {"lag_s": 0.0})]), xml)
    assert "filterexact" not in xml.read_text()
    assert _run("--replay", str(prototype_log), "--model", str(xml),
                "--out", str(tmp_path / "replay.csv")) == 0


def test_position_names_follow_the_axis():
    assert axis_key("backlash_rad", True) == "backlash_m"
    assert axis_key("ripple_period_rad", True) == "ripple_period_m"
    assert axis_key("ripple_phase_rad", True) == "ripple_phase_rad"   # a phase stays in rad
    assert axis_key("backlash_rad", False) == "backlash_rad"


@pytest.fixture(scope="module")
def emps_diagnosis(tmp_path_factory):
    """The EMPS estimation file diagnosed once, without the forward view, its answer written
    (figures, report, models) as `diagnose --out FOLDER --no-forward` writes it:
    (log, diagnosis, folder)."""
    log = read_log(EMPS / "emps_estimation.csv")
    out = tmp_path_factory.mktemp("emps") / "d"
    return log, diagnose(log, out, forward=False), out


def test_emps_extended_model_of_every_candidate_runs(emps_diagnosis, tmp_path):
    """Each testable candidate of the EMPS estimation file, and all of them at once, in the
    prismatic rigid nominal: simulate and replay run; the simulated log says prismatic."""
    log, d, _ = emps_diagnosis
    tested = [c for c in d.inverse.candidates if c.testable]
    assert {c.effect for c in tested} == set(RIGID_TESTS)
    p = d.nominal_parameters
    runs = [[(c.effect, extended_parameters(c, d.inverse.nominal))] for c in tested]
    runs.append([(c.effect, extended_parameters(c, d.inverse.nominal)) for c in tested])
    for i, effects in enumerate(runs):
        spec = nominal_axes.rigid_axis(J=p["J"], FV=p["FV"], FS=p["FS"], timestep=log.ts,
                                       prismatic=True, tau_max=log.meta_float("tau_max"),
                                       gravity=log.gravity, name="axis1")
        write_effects(spec, "axis1", effects, 0.0)
        xml = tmp_path / f"extended{i}.xml"
        nominal_axes.write_xml(spec, xml)
        sim = tmp_path / f"sim{i}.csv"
        # all of them at once at the default 60 s, each alone at 20 s, whose chirp keeps the
        # 60 s one's amplitude (0.049 m) and acceleration (a shorter chirp's amplitude cap
        # kinks the reference: a velocity step)
        duration = [] if i == len(runs) - 1 else ["--duration", "20"]
        assert _run("--model", str(xml), *duration, "--out", str(sim)) == 0, effects
        assert read_log(sim).prismatic
        assert _run("--replay", str(log.path), "--model", str(xml),
                    "--out", str(tmp_path / f"replay{i}.csv")) == 0, effects


def test_emps_reports_metres(emps_diagnosis):
    log, d, _ = emps_diagnosis
    text = summary_text(d)
    assert "ripple_period_m" in text and "ripple_period_rad" not in text
    doc = json.loads(json.dumps(d.to_json()))
    ripple = [c for c in doc["candidates"] if c["effect"] == "torque_ripple"][0]
    assert "ripple_period_m" in ripple["parameters"]


def test_emps_diagnose_out_models_run(emps_diagnosis, tmp_path):
    _, d, out = emps_diagnosis
    assert {str(out / m) for m in ("nominal.xml", "extended.xml")} <= set(d.files)
    # the nominal at 20 s (the chirp of the 60 s default, test above), the extended at 60 s
    for name, duration in (("nominal.xml", ["--duration", "20"]), ("extended.xml", [])):
        assert _run("--model", str(out / name), *duration,
                    "--out", str(tmp_path / f"{name}.csv")) == 0
        assert _run("--replay", str(EMPS / "emps_estimation.csv"), "--model", str(out / name),
                    "--out", str(tmp_path / f"r_{name}.csv")) == 0
