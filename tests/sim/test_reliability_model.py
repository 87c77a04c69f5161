"""A user's MJCF: every value the bench reads is checked (finite, of its sign, the actuator's
gear, the gear ratio) with a message naming the file, the element and the attribute, in
`simulate` as in `diagnose --model`; `diagnose --model` checks the log's axis and its type
against the model; `corrected.xml` keeps the model's asset paths valid."""

from __future__ import annotations

import re
from pathlib import Path

import mujoco
import pytest

import jointbench as jb
from jointbench.bench.cli import main
from jointbench.models import ModelStructureError, model_path

PROTOTYPE = model_path("prototype").read_text()

EDITS = {   # name -> (substitution on the prototype's MJCF, what the message names)
    "stiffness_inf": (('stiffness="20341.0458"', 'stiffness="inf"'),
                      "tendon 'axis1_spring': stiffness=\"inf\""),
    "link_damping_inf": (('damping="83.1508"', 'damping="inf"'),
                         "joint 'axis1': damping=\"inf\""),
    "negative_armature": (('armature="174.7996"', 'armature="-174.7996"'),
                          "joint 'axis1_motor': armature=\"-174.8\""),
    "actuator_gear": (('gear="1"', 'gear="50"'), "actuator 'axis1_motor': gear=\"50\""),
    "negative_gear_ratio": (("</mujoco>", '<custom><numeric name="axis1_gear_ratio" '
                                          'data="-100"/></custom></mujoco>'),
                            "numeric 'axis1_gear_ratio': data=\"-100\""),
    "huge_gear_ratio": (("</mujoco>", '<custom><numeric name="axis1_gear_ratio" '
                                      'data="1e300"/></custom></mujoco>'),
                        "numeric 'axis1_gear_ratio': data=\"1e+300\""),
}


def edited(tmp_path: Path, name: str, old: str, new: str) -> Path:
    assert old in PROTOTYPE
    path = tmp_path / f"{name}.xml"
    path.write_text(PROTOTYPE.replace(old, new))
    return path


@pytest.fixture(scope="module")
def log_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("model") / "log.csv"
    jb.write_log(jb.simulate("prototype", duration=20.0, seed=1), path)
    return path


@pytest.mark.parametrize("case", sorted(EDITS))
@pytest.mark.parametrize("surface", ["simulate", "diagnose", "api"])
def test_unphysical_model_values_are_refused_naming_the_element(case, surface, tmp_path,
                                                               log_file, capsys):
    (old, new), named = EDITS[case]
    model = edited(tmp_path, case, old, new)
    if surface == "api":
        with pytest.raises(ModelStructureError) as err:
            jb.simulate(model, duration=10.0)
        message = str(err.value)
    else:
        args = (["simulate", "--model", str(model), "--duration", "10", "--out",
                 str(tmp_path / "o.csv")] if surface == "simulate" else
                ["diagnose", str(log_file), "--model", str(model), "--no-forward"])
        assert main(args) == 2
        message = capsys.readouterr().err
    assert f"{case}.xml" in message and named in message
    for misleading in ("NaN to integer", "math domain", "velocity loop", "wrong parameters"):
        assert misleading not in message
    assert not (tmp_path / "o.csv").exists()


def test_diagnose_refuses_a_model_without_the_logs_axis(tmp_path, log_file, capsys):
    """The model's axes are named otherwise: refused naming both, never another axis
    diagnosed quietly; --joint chooses one explicitly."""
    model = tmp_path / "renamed.xml"
    model.write_text(PROTOTYPE.replace("axis1", "axisA"))
    assert main(["diagnose", str(log_file), "--model", str(model), "--no-forward"]) == 2
    err = capsys.readouterr().err
    assert "renamed.xml" in err and "'axis1'" in err and "axisA" in err and "--joint" in err
    assert main(["diagnose", str(log_file), "--model", str(model), "--no-forward",
                 "--joint", "axisA", "--json"]) == 0


def test_diagnose_refuses_a_slide_model_for_a_revolute_log(tmp_path, log_file, capsys):
    model = tmp_path / "slide.xml"
    model.write_text(PROTOTYPE.replace('type="hinge"', 'type="slide"'))
    assert main(["diagnose", str(log_file), "--model", str(model), "--no-forward"]) == 2
    err = capsys.readouterr().err
    assert "slide.xml" in err and "slide (prismatic)" in err and "revolute" in err


def test_diagnose_names_a_folder_given_as_model(tmp_path, log_file, capsys):
    assert main(["diagnose", str(log_file), "--model", str(tmp_path), "--no-forward"]) == 2
    assert f"{tmp_path}: is a directory, not an MJCF file" in capsys.readouterr().err


@pytest.mark.parametrize("text", ['<mujoco><worldbody><body><joint name="x" type="bogus"/>'
                                  '</body></worldbody></mujoco>', "<mujoco><worldbody>"])
def test_diagnose_names_the_mjcf_file_mujoco_cannot_read(text, tmp_path, log_file, capsys):
    model = tmp_path / "broken.xml"
    model.write_text(text)
    assert main(["diagnose", str(log_file), "--model", str(model), "--no-forward"]) == 2
    assert f"{model}: MuJoCo cannot load it" in capsys.readouterr().err


def test_diagnose_warns_of_a_gear_ratio_other_than_the_logs(tmp_path, log_file):
    """The prototype's log carries no gear ratio; a log that says 100 against a model that
    says 50: the diagnosis notes both."""
    log = jb.read_log(log_file)
    log = type(log)(**{**log.__dict__, "meta": {**log.meta, "gear_ratio": "100"}})
    model = edited(tmp_path, "geared", "</mujoco>", '<custom><numeric '
                   'name="axis1_gear_ratio" data="50"/></custom></mujoco>')
    from jointbench.bench.analysis.diagnose.against_model import diagnose_against_model
    d = diagnose_against_model(log, model, forward=False)
    note = [n for n in d.notes if n.startswith("gear ratio")]
    assert note and "50" in note[0] and "100" in note[0]


CUBE_OBJ = "\n".join([*(f"v {x} {y} {z}" for x in (-0.05, 0.05) for y in (-0.05, 0.05)
                        for z in (-0.05, 0.05)),
                      "f 1 2 4 3", "f 5 7 8 6", "f 1 5 6 2", "f 3 4 8 7", "f 1 3 7 5",
                      "f 2 6 8 4"]) + "\n"


@pytest.mark.parametrize("meshdir", [None, "meshes"])
def test_corrected_xml_loads_with_a_relative_mesh_path(meshdir, tmp_path, log_file):
    """A model whose mesh lies beside it (a relative path, with or without a compiler
    meshdir): corrected.xml, written into another folder, still loads in MuJoCo."""
    folder = tmp_path / "robot"
    (folder / "meshes").mkdir(parents=True)
    (folder / "meshes" / "cube.obj").write_text(CUBE_OBJ)
    mesh = "cube.obj" if meshdir else "meshes/cube.obj"
    text = PROTOTYPE.replace("<worldbody>", f'<asset><mesh name="cube" file="{mesh}"/></asset>'
                             "<worldbody>", 1)
    if meshdir:
        text = text.replace('<compiler angle="radian"',
                            f'<compiler angle="radian" meshdir="{meshdir}"')
    text = re.sub(r'<geom type="capsule"[^>]*/>', '<geom type="mesh" mesh="cube" mass="0" '
                  'contype="0" conaffinity="0"/>', text)
    text = text.replace('armature="174.7996"', 'armature="120"')   # Jm wrong: corrected
    model = folder / "robot.xml"
    model.write_text(text)
    out = tmp_path / "out"
    assert main(["diagnose", str(log_file), "--model", str(model), "--no-forward", "--quiet",
                 "--out", str(out)]) == 0
    corrected = out / "corrected.xml"
    assert corrected.exists()
    loaded = mujoco.MjModel.from_xml_path(str(corrected))
    assert loaded.nmesh == 1
