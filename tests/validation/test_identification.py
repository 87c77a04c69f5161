"""The paper's identification chain on the virtual prototype, against ground truth."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jointbench.bench.cli import main
from jointbench.identification import filter_choice as defaults, filtering
from jointbench.identification import regressors as models
from jointbench.identification.estimate import NotIdentifiable, least_squares
from jointbench.identification.identify import identify
from jointbench.identification.log import write_log


def err_pct(value: float, truth: float) -> float:
    return 100 * (value - truth) / abs(truth)


@pytest.fixture(scope="module")
def joint_motor(prototype_joint_motor):
    return prototype_joint_motor


def test_joint_motor_accuracy(joint_motor, prototype_log):
    """Issue targets: K, Jm, JL within 0.5 %; frictions within 5 %; MY within 2 %."""
    truth = prototype_log.truth()
    for name, tol in (("K", 0.5), ("Jm", 0.5), ("JL", 0.5), ("FVm", 5), ("FSm", 5), ("FV", 5),
                      ("FS", 5), ("MY", 2)):
        assert abs(err_pct(joint_motor.physical[name], truth[name])) < tol, name


def test_joint_motor_truth_within_3_sigma(joint_motor, prototype_log):
    truth = prototype_log.truth()
    for name in ("K", "Jm", "JL"):
        z = (joint_motor.physical[name] - truth[name]) / joint_motor.physical_sigma[name]
        assert abs(z) < 3, (name, z)


def test_motor_only_corrected_beats_printed(prototype_log):
    truth = prototype_log.truth()
    corrected = identify(prototype_log, "motor-only")
    printed = identify(prototype_log, "motor-only-printed")
    for name in ("K", "Jm", "JL"):
        assert abs(err_pct(corrected.physical[name], truth[name])) < 3, name
        assert abs(err_pct(printed.physical[name], truth[name])) > \
            2 * abs(err_pct(corrected.physical[name], truth[name])), name


def test_zoh_alignment_matters(prototype_log, joint_motor, monkeypatch):
    """Pairing tau[k] with positions at t_k, without the half-sample alignment, biases the
    estimate: the aligned K is at least three times closer to the truth."""
    truth = prototype_log.truth()
    aligned = joint_motor   # made before the patch below
    monkeypatch.setattr(models, "zoh_align", lambda tau, **_: np.asarray(tau, dtype=float))
    naive = identify(prototype_log, "joint-motor")
    for name in ("K", "FVm"):
        assert abs(err_pct(naive.physical[name], truth[name])) > \
            3 * abs(err_pct(aligned.physical[name], truth[name])), name


def test_rank_check_names_unexcited_parameters():
    rng = np.random.default_rng(0)
    W = np.column_stack([rng.normal(size=200), np.zeros(200), rng.normal(size=200)])
    W = np.column_stack([W, W[:, 0] + W[:, 2]])
    res = least_squares(W, W[:, 0] * 2.0, ("a", "b", "c", "d"))
    assert "b" in res.unidentifiable and np.isnan(res.X[1])
    # d = a + c: exactly one of the three is left out, with the others named
    dropped = [n for n in "acd" if n in res.unidentifiable]
    assert len(dropped) == 1 and "combination" in res.reasons[dropped[0]]
    assert len(res.unidentifiable) == 2
    with pytest.raises(NotIdentifiable):
        least_squares(np.zeros((50, 2)), np.ones(50), ("a", "b"))


def test_decimation_keeps_the_linear_relation():
    """y = W X holds exactly on synthetic data after the parallel filtering and decimation."""
    ts = 1 / 350.87
    t = np.arange(20000) * ts
    x1, x2 = np.sin(2 * np.pi * 1.3 * t), np.cos(2 * np.pi * 0.7 * t) ** 3
    s = filtering.FilterSettings(wn=176.0, m=4, Nd=26, ts=ts)
    y, W, _ = filtering.decimate_parallel(3 * x1 - 2 * x2, np.column_stack([x1, x2]), s)
    np.testing.assert_allclose(least_squares(W, y, ("a", "b")).X, [3, -2], rtol=1e-9)


def test_identify_json_contract(prototype_log, tmp_path, capsys):
    path = tmp_path / "p.csv"
    write_log(prototype_log, path)
    assert main(["identify", str(path), "--model", "joint-motor", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["model"] == "joint-motor"
    assert set(out["parameters"]) == {"Jm", "FVm", "FSm", "K", "JL", "MX", "MY", "FV", "FS"}
    k = out["parameters"]["K"]
    assert k["rel_sigma_pct"] == pytest.approx(100 * k["sigma"] / k["value"])
    assert {k: out["filter"][k] for k in ("wn_rad_s", "order", "decimate", "stencil")} == \
        {"wn_rad_s": 176.0, "order": 4, "decimate": 26, "stencil": 3}
    # issue 17: the design against the measured first mode, and why this stencil
    assert out["filter"]["decimated_cutoff_hz"] == pytest.approx(0.8 * 350.87 / 52, rel=1e-3)
    assert out["filter"]["cutoff_over_f1"] == pytest.approx(
        out["filter"]["decimated_cutoff_hz"] / out["first_mode"]["f1_hz"])
    assert out["filter"]["stencil_reason"].startswith("eq. (22)")
    assert out["first_mode"]["found"] and out["first_mode"]["source"] == "measured"
    assert out["warnings"] == [] and out["uncertainty"]["estimator"].startswith("instrumental")
    assert main(["identify", str(path), "--model", "joint-motor", "--stencil", "5",
                 "--json"]) == 0
    five = json.loads(capsys.readouterr().out)
    assert five["filter"]["stencil"] == 5
    truth = prototype_log.truth()
    for name in ("K", "Jm", "JL"):  # the 0.5 % holds with either stencil
        assert abs(five["physical"][name] / truth[name] - 1) < 0.005


def test_design_filter_json(capsys):
    assert main(["design-filter", "--f1", "3.9", "--nd", "4", "--m", "6", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["wn_rad_s"] == pytest.approx(168.91, abs=0.01)  # ERRATA.md
    assert out["fs_hz"] == pytest.approx(289.64, abs=0.01)


def test_demo_writes_figures_and_report(tmp_path, capsys):
    """The command end to end: its files and the report's sections, which the experiment's
    length does not change (20 s: a third of the default's simulations and the 16 closed-loop
    replicas' replays). The accuracy of the default 60 s experiment (seed 1) is the tests above,
    on the same log (the prototype_log fixture)."""
    assert main(["demo", "--duration", "20", "--out", str(tmp_path)]) == 0
    for name in ("figure1.png", "figure2.png", "frequency_response.png", "report.md",
                 "prototype.csv"):
        assert (tmp_path / name).stat().st_size > 0, name
    report = (tmp_path / "report.md").read_text()
    assert "Table 1" in report
    assert "## Bias correction of Table 1 (parametric bootstrap): 8 closed-loop" in report


def test_five_point_stencil_gain():
    """Analytic: eq. (22) differentiates sin(w t) with the gain sin(w ts) / (w ts); the
    5-point stencil with (8 sin(w ts) - sin(2 w ts)) / (6 w ts), short by (w ts)^4 / 30."""
    ts, w = 1e-3, 300.0
    t = np.arange(2000) * ts
    x = np.sin(w * t)
    exact = w * np.cos(w * t)
    k = slice(10, -10)
    g3 = filtering.central_difference(x, ts)[k] / exact[k]
    g5 = filtering.central_difference5(x, ts)[k] / exact[k]
    wt = w * ts
    ok = np.abs(np.cos(w * t[k])) > 0.1
    assert np.allclose(g3[ok], np.sin(wt) / wt, rtol=1e-9)
    assert np.allclose(g5[ok], (8 * np.sin(wt) - np.sin(2 * wt)) / (6 * wt), rtol=1e-9)
    assert abs(g5[ok].mean() - 1) < 1.1 * wt ** 4 / 30 < 0.02 * abs(g3[ok].mean() - 1)
    with pytest.raises(ValueError, match="stencil"):
        filtering.FilterSettings(wn=176.0, m=4, Nd=26, ts=ts, stencil=4)


def test_five_point_stencil_removes_the_differentiation_bias(tmp_path):
    """Without friction and with ideal sensors the only bias left on the prototype is eq. (22)'s
    sinc distortion: it pulls K down and Jm up by about 0.1 % (the 2nd derivative is short by
    (w1 ts)^2 / 3 = 0.16 % at 3.9 Hz). The 5-point stencil removes it (measured: K -0.093 ->
    -0.006 %, Jm +0.082 -> -0.016 %, seeds 1-2)."""
    import mujoco

    from jointbench.bench.sim.experiment import run_experiment
    from jointbench.bench.sim.sensors import Sensors
    from jointbench.models import model_path

    spec = mujoco.MjSpec.from_file(str(model_path("prototype")))
    for j in spec.joints:
        j.frictionloss = 0.0
    path = tmp_path / "prototype_no_friction.xml"
    path.write_text(spec.to_xml())
    res = run_experiment(path, seed=1, sensors=Sensors.ideal())
    truth = {k: float(res.log.meta[f"truth_{k}"]) for k in ("K", "Jm", "JL")}
    base = defaults.default_settings(defaults.PAPER_RATE)
    err = {}
    for stencil in (3, 5):
        s = filtering.FilterSettings(wn=base.wn, m=base.m, Nd=base.Nd, ts=res.log.ts,
                                     stencil=stencil)
        idn = identify(res.log, "joint-motor", settings=s)
        err[stencil] = {k: 100 * (idn.physical[k] / v - 1) for k, v in truth.items()}
    assert err[3]["K"] < -0.05 and err[3]["Jm"] > 0.05
    for k in ("K", "Jm", "JL"):
        assert abs(err[5][k]) < 0.03, (k, err)
