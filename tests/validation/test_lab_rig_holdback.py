"""The hold-back scenario on the lab-rig family: four runs of one lab rotary flexible joint with
its arm (open loop 20 s; the lab's P loop, 1 V/rad, multisine 0.025-10 Hz, 20, 40 and 80 s),
stored as the lab stores them (MATLAB .mat files with the servo angle theta, the spring
deflection alpha, the voltage u and the reference r), imported with the expression map
q = theta - alpha and the drive's constants (--drive), then identified and diagnosed with the
defaults (no --f1). The rig has light link damping in the springs themselves (spring_damping,
D (qm' - q'), beside the link's FV): the two encoders alone give a damping ratio near 0.02.

What the real runs must show (the same checks): every run identifies; K agrees across the runs
within 3 %, Jm and JL within 5 %; K / JL lies within 3 % of what the two encoders alone give
(the link mode of q / q_m); no units warning; every run's K lies within 3 of its own sigma of
the runs' median, or the report names it with its sigma as a lower bound; diagnose names the
same causes on the open-loop and the closed-loop runs, each with a passing test of its own;
with the lab's P loop described in the metadata the forward view runs and the report's files,
nominal.xml and extended.xml among them, exist."""

from __future__ import annotations

import contextlib
import io
import json
import re
from pathlib import Path
from statistics import median

import pytest
from scipy import io as sio

import jointbench as jb
from jointbench.bench.cli import main
from jointbench.bench.results.diagnose_runs import RunsDiagnosis
from jointbench.identification.link_mode import link_mode
from jointbench.identification.log import read_log
from jointbench.testing.simulator import LAB_RIG, simulate_lab_rig

D_SPRING = 0.0025       # N m s/rad: with FV, a link damping ratio near 0.02
RUNS = (("open20", 20.0, False), ("closed20", 20.0, True), ("closed40", 40.0, True),
        ("closed80", 80.0, True))
G = LAB_RIG.volt_to_torque
DRIVE = (f"Kt={LAB_RIG.Kt!r},R={LAB_RIG.R!r},Ke={LAB_RIG.Ke!r},"
         f"eta={LAB_RIG.eta_gear * LAB_RIG.eta_motor!r}")
COMMON = ["--units", "tau_m=V", "--drive", DRIVE, "--gear-ratio", repr(LAB_RIG.N),
          "--motor-side", "tau_m", "--gravity", "0", "--json"]
MAP = "t=time,q_m=theta,q=theta-alpha,tau_m=u"
# the lab's loop u = 1 V/rad (r - theta), within +-u_max, as docs/controller.md section 3.2 writes it
P_LOOP = ["--meta", "controller=P", "--meta", f"pid_kp={G!r}", "--tau-max", repr(G * LAB_RIG.u_max)]


def _import(*argv: str) -> list[dict]:
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main(["import", *argv]) == 0
    doc = json.loads(printed.getvalue())
    return doc if isinstance(doc, list) else [doc]


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """The four runs written as .mat files and imported: (paths, import answers)."""
    folder = tmp_path_factory.mktemp("lab")
    for i, (name, duration, closed) in enumerate(RUNS):
        log = simulate_lab_rig(seed=320 + i, duration=duration, closed_loop=closed,
                               effects=f"spring_damping={D_SPRING}")
        data = {"time": log.t[:, None], "theta": log.extra["theta"][:, None],   # n x 1
                "alpha": log.extra["alpha"][:, None], "u": log.extra["u"][:, None]}
        if closed:
            data["r"] = log.q_ref[:, None]
        sio.savemat(folder / f"{name}.mat", data)
    logs = folder / "logs"
    logs.mkdir()
    answers = _import(str(folder / "open20.mat"), "--out", str(logs / "open20.csv"),
                      "--map", MAP, *COMMON)
    answers += _import(*(str(folder / f"{name}.mat") for name, _, closed in RUNS if closed),
                       "--out", str(logs), "--map", MAP + ",q_ref=r", *COMMON, *P_LOOP)
    return [str(logs / f"{name}.csv") for name, _, _ in RUNS], answers


@pytest.fixture(scope="module")
def runs(lab):
    return jb.identify(lab[0])


@pytest.fixture(scope="module")
def diagnoses(lab, tmp_path_factory):
    """Each run diagnosed with the forward view and cross-validated on the next (the last on
    the first), as `diagnose A B C D` does; the 20 s closed-loop run written out."""
    paths = lab[0]
    out = tmp_path_factory.mktemp("diag") / "closed20"
    return [jb.diagnose(p, validate=paths[(i + 1) % len(paths)],
                        out=out if Path(p).stem == "closed20" else None)
            for i, p in enumerate(paths)]


def _no_units_warning(texts) -> None:
    assert not [w for w in texts if "degrees" in w or "radians" in w], texts


def test_import_as_the_lab_stores_it(lab):
    paths, answers = lab
    for path, doc in zip(paths, answers):
        assert doc["out"] == path
        _no_units_warning(doc["warnings"])
        log = read_log(path)
        assert log.meta["gravity"] == "0" and "back_emf_damping" in log.meta
        assert "alpha" in log.extra      # only used in an expression: kept as it is
        assert (log.q_ref is not None) == ("controller" in log.meta)


def test_every_run_identifies_and_the_runs_agree(lab, runs):
    fits = runs.fits
    assert len(fits) == len(RUNS)
    for fit in fits:
        assert fit.model == "joint-motor"
        _no_units_warning(fit.warnings)
        assert all(fit.parameters[k].value > 0 for k in ("K", "Jm", "JL"))
    for key, tol in (("K", 0.03), ("Jm", 0.05), ("JL", 0.05)):
        values = [f.parameters[key].value for f in fits]
        assert max(values) / min(values) - 1 < tol, (key, values)


def test_stiffness_over_link_inertia_is_the_encoders(lab, runs):
    """K / JL of each fit against the link mode of q / q_m alone (identification.link_mode)."""
    for path, fit in zip(lab[0], runs.fits):
        wa2, _ = link_mode(read_log(path))
        ratio = fit.parameters["K"].value / fit.parameters["JL"].value
        assert abs(ratio / wa2 - 1) < 0.03, (path, ratio, wa2)


def test_each_run_within_three_of_its_sigma_or_named_a_lower_bound(lab, runs):
    doc = runs.to_json()
    ks = [f.parameters["K"] for f in runs.fits]
    mid = median(k.value for k in ks)
    outliers = doc["pooled"]["K"]["outliers"]
    for name, k in zip(lab[0], ks):
        if abs(k.value - mid) > 3 * k.sigma_hac:
            assert name in outliers and any("lower bound" in n for n in doc["notes"])


def test_diagnose_names_the_same_causes_on_every_run(lab, diagnoses):
    for path, d in zip(lab[0], diagnoses):
        doc = d.to_json()
        _no_units_warning(doc["warnings"])
        assert doc["named_causes"] == ["spring_damping"], (path, doc["named_causes"],
                                                           doc.get("reason"))
        cands = {c["effect"]: c for c in doc["candidates"]}
        for cause in doc["causes"]:       # each named cause passes its own held-out test
            assert cands[cause["effect"]]["significant"]
            assert cause["t"] > 0 and cause["p_heldout"] < cands[cause["effect"]]["alpha"]
    every = RunsDiagnosis(tuple(diagnoses), tuple(lab[0]))
    assert every.supported == ("spring_damping",) and every.unsupported == {}
    # each run's extended model predicts the run it did not fit better than its nominal
    assert every.confirms() == (True,) * len(RUNS)
    doc = every.to_json()
    assert [r["named"] for r in doc["evidence"]["spring_damping"]] == [True] * len(RUNS)
    jsonschema = pytest.importorskip("jsonschema")
    schema = Path(__file__).resolve().parents[2] / "docs" / "schemas" / "diagnose_runs.schema.json"
    jsonschema.Draft202012Validator(json.loads(schema.read_text())).validate(
        json.loads(json.dumps(doc, allow_nan=False)))


def test_the_p_loop_replays_and_the_models_are_written(lab, diagnoses):
    for path, d in zip(lab[0], diagnoses):
        if Path(path).stem.startswith("closed"):
            assert d.diagnosis.forward_nominal is not None, d.diagnosis.forward_note
            assert d.diagnosis.forward_extended is not None, d.diagnosis.forward_note
    written = diagnoses[1].to_json()
    folder = Path(written["files"][0]).parent
    assert (folder / "nominal.xml").is_file() and (folder / "extended.xml").is_file()
    for f in written["files"]:
        assert Path(f).is_file(), f
    report = (folder / "report.md").read_text()
    for name in set(re.findall(r"`?([\w.-]+\.(?:xml|png|json))`?", report)):
        assert (folder / name).is_file(), name
