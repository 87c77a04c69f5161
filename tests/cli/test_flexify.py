"""`jointbench flexify`: a rigid two-link arm in Menagerie's style (tests/data/two_link_arm)
flexified from a survey JSON keeps the user's bodies, meshes and contacts, passes the axis
convention, `survey --model` recovers the K and Jm written into it within 0.5 %, and
`diagnose --model` against a copy with K +25 % names K. Bad models: exit 2 naming the joint
or actuator."""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest

from jointbench.bench.cli import main
from jointbench.models import find_axes

ARM = Path(__file__).resolve().parent.parent / "data" / "two_link_arm" / "two_link.xml"
# A survey of the real arm (the `survey --json` layout): per joint K, Jm and the frictions.
SURVEYED = {"shoulder": {"K": 22000.0, "Jm": 4.0, "FVm": 3.0, "FSm": 8.0, "FV": 1.0, "FS": 1.0},
            "elbow": {"K": 4800.0, "Jm": 1.5, "FVm": 1.5, "FSm": 3.0, "FV": 0.4, "FS": 0.5}}
BAR_PCT = 0.5


@pytest.fixture(scope="module")
def flexified(tmp_path_factory):
    folder = tmp_path_factory.mktemp("flex")
    doc = {"model": "two_link_arm", "joints": [
        {"joint": j, "status": "ok", "parameters": {k: {"value": v, "sigma": 0.0}
                                                    for k, v in p.items()}}
        for j, p in SURVEYED.items()]}
    (folder / "survey.json").write_text(json.dumps(doc))
    out = folder / "models" / "flex.xml"
    out.parent.mkdir()
    assert main(["flexify", str(ARM), "--out", str(out), "--from",
                 str(folder / "survey.json")]) == 0
    return folder, out


def test_user_elements_untouched_and_convention(flexified):
    """Every body, geom, mesh, contact exclusion, site and sensor of the rigid arm is there
    with its values; the new axes follow the convention with the surveyed values, the torque
    limit is ctrlrange x gear and the rigid joint's armature moved to the rotor."""
    _, out = flexified
    rigid = mujoco.MjModel.from_xml_path(str(ARM))
    flex = mujoco.MjModel.from_xml_path(str(out))
    for b in range(rigid.nbody):
        f = flex.body(rigid.body(b).name)
        for attr in ("pos", "quat", "mass", "inertia", "ipos"):
            assert np.allclose(getattr(f, attr), getattr(rigid.body(b), attr), rtol=1e-5)
    for g in range(rigid.ngeom):
        name = rigid.geom(g).name
        f = flex.geom(name) if name else flex.geom(g)
        assert np.allclose(f.size, rigid.geom(g).size, rtol=1e-5)
        assert f.contype == rigid.geom(g).contype and f.dataid == rigid.geom(g).dataid
    assert flex.nmesh == rigid.nmesh == 1 and np.allclose(flex.mesh_vert, rigid.mesh_vert)
    assert flex.nexclude == rigid.nexclude and flex.nsensor == rigid.nsensor
    axes = {a.name: a for a in find_axes(flex, str(out))}
    assert set(axes) == {"shoulder", "elbow"}
    for name, limit, gear in (("shoulder", 300.0, 100.0), ("elbow", 120.0, 80.0)):
        a = axes[name]
        assert not a.rigid
        assert flex.tendon_stiffness[a.tendon] == pytest.approx(SURVEYED[name]["K"], rel=1e-5)
        assert flex.dof_armature[a.motor_dof] == pytest.approx(SURVEYED[name]["Jm"], rel=1e-5)
        assert flex.dof_armature[a.link_dof] == 0.0
        assert flex.actuator_ctrlrange[a.actuator][1] == pytest.approx(limit)
        nid = mujoco.mj_name2id(flex, mujoco.mjtObj.mjOBJ_NUMERIC, f"{name}_gear_ratio")
        assert flex.numeric_data[flex.numeric_adr[nid]] == gear


@pytest.mark.slow
def test_survey_recovers_k_and_jm_and_diagnose_names_k(flexified, tmp_path, capsys):
    folder, out = flexified
    sv = tmp_path / "sv"
    assert main(["survey", "--model", str(out), "--duration", "60", "--seed", "1", "--out",
                 str(sv), "--json", "--workers", "1"]) == 0
    doc = json.loads(capsys.readouterr().out)
    for j in doc["joints"]:
        for name in ("K", "Jm"):
            est = j["parameters"][name]["value"]
            truth = SURVEYED[j["joint"]][name]
            assert abs(100 * (est / truth - 1)) <= BAR_PCT, (j["joint"], name, est)
    wrong = folder / "models" / "k125.xml"
    assert main(["flexify", str(ARM), "--out", str(wrong), "--from", str(folder / "survey.json"),
                 "--set", f"elbow.K={1.25 * SURVEYED['elbow']['K']}"]) == 0
    capsys.readouterr()
    assert main(["diagnose", str(sv / "logs" / "elbow.csv"), "--model", str(wrong), "--joint",
                 "elbow", "--json", "--out", str(tmp_path / "d")]) == 0
    diag = json.loads((tmp_path / "d" / "diagnosis.json").read_text())
    assert "K" in diag["wrong_parameters"]
    assert diag["parameter_errors"]["K"]["error_pct"] == pytest.approx(25.0, abs=2.0)


BAD_ACTUATOR = """<mujoco><worldbody><body name="a"><inertial pos="0.1 0 0" mass="1"
 diaginertia="0.01 0.01 0.01"/><joint name="j1" axis="0 1 0"/><body name="b" pos="0.2 0 0">
 <inertial pos="0.1 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>{joint2}</body></body>
 </worldbody><actuator><motor name="m1" joint="j1" gear="{gear}" ctrlrange="-1 1"/>
 {act2}</actuator></mujoco>"""


@pytest.mark.parametrize("joint2, act2, gear, text", [
    ('<joint name="j2" type="slide"/>', '<motor joint="j2" gear="1"/>', 50,
     "joint 'j2' is a slide joint, not a hinge"),
    ('<joint name="j2" axis="0 1 0"/>', "", 50, "joint 'j2' has no actuator"),
    ('<joint name="j2" axis="0 1 0"/>', '<motor joint="j2" gear="1"/>', 0,
     "actuator 'm1' has gear 0"),
])
def test_bad_models_exit_2(tmp_path, capsys, joint2, act2, gear, text):
    xml = tmp_path / "bad.xml"
    xml.write_text(BAD_ACTUATOR.format(joint2=joint2, act2=act2, gear=gear))
    assert main(["flexify", str(xml), "--out", str(tmp_path / "out.xml")]) == 2
    assert text in capsys.readouterr().err
    assert not (tmp_path / "out.xml").exists()


def test_bad_options_exit_2(tmp_path, capsys):
    for argv, text in ((["--set", "elbow.Q=1"], "'Q' is not a parameter"),
                       (["--set", "elbow.K=x"], "'x' is not a number"),
                       (["--set", "nope.K=1"], "no joint 'nope'"),
                       (["--set", "elbow.K=-5"], "K = -5"),
                       (["--from", str(tmp_path / "missing.json")], "missing.json")):
        assert main(["flexify", str(ARM), "--out", str(tmp_path / "o.xml"), *argv]) == 2
        assert text in capsys.readouterr().err
        assert not (tmp_path / "o.xml").exists()


def test_one_joint_from_an_identify_answer(tmp_path, capsys):
    """--joints elbow with an `identify --json` answer: the elbow becomes an axis with its K
    and Jm; the shoulder, its actuator and its armature stay the user's; an unknown
    parameter name in the answer is ignored, a missing one takes its stated default."""
    answer = {"model": "joint-motor", "parameters": {
        "K": {"value": 5000.0, "sigma": 10.0}, "Jm": {"value": 1.4, "sigma": 0.01},
        "MX": {"value": 0.1, "sigma": 0.01}}}
    (tmp_path / "id.json").write_text(json.dumps(answer))
    out = tmp_path / "one.xml"
    assert main(["flexify", str(ARM), "--out", str(out), "--from", str(tmp_path / "id.json"),
                 "--joints", "elbow", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    (elbow,) = doc["joints"]
    assert elbow["sources"]["K"] == "--from id.json" and elbow["sources"]["FVm"] == "default 0"
    flex = mujoco.MjModel.from_xml_path(str(out))
    (axis,) = find_axes(flex, str(out))
    assert axis.name == "elbow" and flex.tendon_stiffness[axis.tendon] == 5000.0
    assert flex.actuator("shoulder_drive").gear[0] == 100.0
    assert flex.dof_armature[flex.joint("shoulder").dofadr[0]] == 2.0
    assert main(["flexify", str(ARM), "--out", str(tmp_path / "two.xml"), "--from",
                 str(tmp_path / "id.json")]) == 2
    assert "an identify answer is one joint's: give --joints JOINT" in capsys.readouterr().err
    assert main(["flexify", str(ARM), "--out", str(tmp_path / "three.xml"), "--joints",
                 "elbow", "--set", "shoulder.K=1e4"]) == 2
    assert "not among the joints to flexify (elbow)" in capsys.readouterr().err


def test_default_k_places_the_first_mode_and_the_users_file_is_kept(tmp_path, capsys):
    """Without values: Jm is the joint's armature, K puts f1 at 15 Hz; an --out that is the
    user's own file is refused and left as it was."""
    out = tmp_path / "d.xml"
    assert main(["flexify", str(ARM), "--out", str(out), "--json"]) == 0
    for j in json.loads(capsys.readouterr().out)["joints"]:
        v = j["values"]
        assert v["Jm"] == {"shoulder": 2.0, "elbow": 1.2}[j["joint"]]
        f1 = (v["K"] * (1 / v["Jm"] + 1 / j["JL"])) ** 0.5 / (2 * np.pi)
        assert f1 == pytest.approx(15.0, rel=1e-12)
    mine = tmp_path / "mine.xml"
    mine.write_text("<mujoco/>\n")
    assert main(["flexify", str(ARM), "--out", str(mine)]) == 2
    assert "did not write" in capsys.readouterr().err and mine.read_text() == "<mujoco/>\n"


def test_a_servo_gives_its_force_range_times_the_gear(tmp_path, capsys):
    """A position servo (Menagerie's `<position>`/`<general>` with a bias): its ctrlrange is
    an angle, so the torque limit is its forcerange times the gear."""
    xml = tmp_path / "servo.xml"
    xml.write_text(BAD_ACTUATOR.format(
        joint2='<joint name="j2" axis="0 1 0"/>', gear=50,
        act2='<position joint="j2" kp="100" gear="20" forcerange="-4 4" ctrlrange="-1 1"/>'))
    assert main(["flexify", str(xml), "--out", str(tmp_path / "s.xml"), "--json"]) == 0
    drives = {j["joint"]: j for j in json.loads(capsys.readouterr().out)["joints"]}
    assert drives["j1"]["values"]["tau_max"] == 50.0      # motor: ctrlrange 1 x gear 50
    assert drives["j2"]["values"]["tau_max"] == 80.0      # servo: forcerange 4 x gear 20
    assert drives["j2"]["sources"]["tau_max"] == "forcerange x gear"
    assert drives["j2"]["values"]["N"] == 20.0
