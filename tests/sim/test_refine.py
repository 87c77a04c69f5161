"""`jointbench identify --refine` (bench/analysis/refine.py): closed-loop output error (DIDIM-style)
from the least-squares estimate."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from jointbench.bench.cli import main
from jointbench.bench.sim.experiment import run_experiment
from jointbench.bench.analysis.refine import ALL_PARAMETERS, RefineError, refine
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.identify import identify
from jointbench.identification.log import write_log


def _err_pct(value: float, truth: float) -> float:
    return 100.0 * (value - truth) / abs(truth)


@pytest.fixture(scope="module")
def motor_only(prototype_log):
    """The demo's log (prototype, 60 s, default sensors, seed 1) without q, its motor-only LS
    identification and the refinement."""
    log = dataclasses.replace(prototype_log, q=None)
    ident = identify(log, "motor-only")
    return log, ident, refine(log, ident)


def test_motor_only_refinement_within_half_a_percent(motor_only):
    """The issue's target: K, Jm, JL within 0.5 % of truth on the prototype from motor-only
    data. Measured on seeds 1-6 (60 s): worst 0.31 % after refinement (this log 0.14 %). The
    motor-only start (the link reconstructed from q_m, identification/link_fit.py) is there
    already (this log: K +0.13, Jm +0.02, JL +0.14 %; eqs. 18-20 alone were up to 1.4 %).
    The optimiser must also lower the output error it minimises and the forward view's
    torque error, and not end on its evaluation limit."""
    log, ident, res = motor_only
    truth = log.truth()
    for n in ("K", "Jm", "JL"):
        ls, refined = _err_pct(ident.physical[n], truth[n]), _err_pct(res.parameters[n], truth[n])
        assert abs(refined) < 0.5, (n, refined)
        assert abs(ls) < 0.5, (n, ls)
    assert res.cost_after < res.cost_before == pytest.approx(1.0)
    assert res.forward_after["torque_rms"] < res.forward_before["torque_rms"]
    assert "maximum number" not in res.message
    assert set(res.free) == set(ALL_PARAMETERS) and res.outputs == ("tau_m",)
    # the motor-only model identifies FS through the reconstructed link (measured -8.2 %,
    # refined -4.5 %; FSm +3.0 -> +2.2 %, FV +1.8 -> +2.0 %): the refinement starts from it
    assert res.start["FS"] == pytest.approx(ident.physical["FS"])
    for n in ("FSm", "FV", "FS"):
        assert abs(_err_pct(res.parameters[n], truth[n])) < 10, n
    assert all(res.sigma[n] > 0 for n in res.free)


@pytest.fixture(scope="module")
def ideal_log():
    """10 s of the prototype with ideal sensors: the data the nominal axis can reproduce
    exactly (same MuJoCo model structure, friction constraint, integrator and physics steps a
    sample: the replay takes the log's). These tests are about the optimiser (its minimum is
    the truth, it is deterministic, it refuses) and not the plant's fidelity, which the
    motor-only bar above holds at the bench's default: one physics step a sample, a third
    of the replays' cost."""
    return run_experiment("prototype", duration=10.0, seed=1, sensors=Sensors.ideal(),
                          substeps=1).log


@pytest.mark.parametrize("model", ["motor-only", "joint-motor"])
def test_noise_free_refinement_recovers_all_nine(ideal_log, model):
    """Without noise the output-error minimum is the truth: all nine parameters, the ones the
    motor-only regressor does not give (FS) or barely sees (MX) included, to the optimiser's
    step tolerance (1e-5 relative; measured 5e-11). LS starts 0.1-15 % off (FS 100 %)."""
    log = ideal_log if model == "joint-motor" else dataclasses.replace(ideal_log, q=None)
    truth = log.truth()
    res = refine(log, identify(log, model))
    for n in ALL_PARAMETERS:
        assert abs(_err_pct(res.parameters[n], truth[n])) < 1e-3, (n, res.parameters[n])
    assert res.forward_after["torque_rel_pct"] < 1e-4


def test_refinement_is_deterministic(ideal_log):
    log = dataclasses.replace(ideal_log, q=None)
    ident = identify(log, "motor-only")
    a = refine(log, ident, max_nfev=2)
    b = refine(log, ident, max_nfev=2)
    assert a.parameters == b.parameters and a.sigma == b.sigma and a.replays == b.replays


def test_refine_refuses_what_it_cannot_refine(ideal_log):
    rigid = identify(ideal_log, "rigid")
    with pytest.raises(RefineError, match="two-mass models"):
        refine(ideal_log, rigid)
    ident = identify(ideal_log, "joint-motor")
    with pytest.raises(RefineError, match="each must be one of"):
        refine(ideal_log, ident, params=("K", "Q"))
    with pytest.raises(ValueError, match="outputs"):
        refine(dataclasses.replace(ideal_log, q=None), ident, outputs=("q",))


@pytest.fixture(scope="module")
def short_file(tmp_path_factory):
    """A 10 s prototype log with default sensors, written to a file; for the command's output,
    not the plant's fidelity: one physics step a sample (the replays take the log's)."""
    path = tmp_path_factory.mktemp("refine") / "proto10.csv"
    write_log(run_experiment("prototype", duration=10.0, seed=2, substeps=1).log, path)
    return path


def test_cli_refine_json(short_file, capsys):
    assert main(["identify", str(short_file), "--refine", "--refine-max-nfev", "3",
                 "--json"]) == 0
    out, _ = capsys.readouterr()
    doc = json.loads(out)
    for key in ("model", "parameters", "physical", "filter", "residual_rms"):  # CONTRACT keys
        assert key in doc
    ref = doc["refined"]
    assert set(ref["parameters"]) == set(ALL_PARAMETERS)
    for entry in ref["parameters"].values():
        assert {"value", "sigma", "start"} <= set(entry)
        assert entry["sigma"] > 0
    assert ref["parameters"]["K"]["start"] == doc["physical"]["K"]
    assert ref["cost"]["after"] <= ref["cost"]["before"]
    assert {"before", "after"} == set(ref["forward"])
    # the cost weighs the torque and both positions: three evaluations from the least-squares
    # start may trade a little torque for position (this log: torque +0.04 %, link -3.7 %)
    assert ref["forward"]["after"]["torque_rms"] <= 1.001 * ref["forward"]["before"]["torque_rms"]
    assert ref["replays"] >= 1 + 9  # the start and at least one Jacobian
    assert set(ref["error_pct"]["refined"]) == set(ALL_PARAMETERS)


def test_cli_refine_text(short_file, capsys):
    assert main(["identify", str(short_file), "--model", "motor-only", "--refine",
                 "--refine-max-nfev", "2"]) == 0
    out, err = capsys.readouterr()
    assert "## Refinement (closed-loop output error" in out
    assert out.index("direct validation") < out.index("## Refinement")
    rows = [line.split()[0] for line in out.split("## Refinement")[1].splitlines()[3:12]]
    assert rows == list(ALL_PARAMETERS)
    assert "forward view: torque" in out and "refine: iteration 1" in err


def test_cli_refine_bad_input(prototype_log, tmp_path, capsys):
    """A log that cannot be replayed (no q_ref, no gains, docs/log-format.md and docs/controller.md), a rigid
    identification and a stray option: exit 2, one line, nothing on stdout."""
    short = dataclasses.replace(prototype_log, t=prototype_log.t[:3000],
                                q_m=prototype_log.q_m[:3000], q=prototype_log.q[:3000],
                                tau_m=prototype_log.tau_m[:3000],
                                q_ref=prototype_log.q_ref[:3000])
    no_ref = tmp_path / "no_ref.csv"
    write_log(dataclasses.replace(short, q_ref=None), no_ref)
    no_gains = tmp_path / "no_gains.csv"
    write_log(dataclasses.replace(short, meta={
        k: v for k, v in short.meta.items() if k not in ("kp", "kv", "ki")}), no_gains)
    good = tmp_path / "good.csv"
    write_log(short, good)
    cases = [([str(no_ref), "--refine"], "no column 'q_ref'"),
             ([str(no_gains), "--refine", "--json"], "controller gains kp, kv, ki"),
             ([str(good), "--model", "rigid", "--refine"], "two-mass models"),
             ([str(good), "--refine-max-nfev", "3"], "applies to --refine"),
             ([str(good), "--refine", "--refine-max-nfev", "0"], "must be >= 1")]
    for args, message in cases:
        assert main(["identify", *args]) == 2, args
        out, err = capsys.readouterr()
        assert out == "" and message in err and "Traceback" not in err, (args, err)
        assert len(err.strip().splitlines()) == 1, err


def test_sigma_widened_where_refined_and_least_squares_disagree():
    """Issue 17: arm6 axis3 at 350.87 Hz (seed 1), refined Jm 14.591 at 2 white sigma 0.0216
    (truth 14.7: -10 sigma), least squares 14.756 (corrected sigma 0.034). The two differ by 3.3
    of their combined corrected sigma: a model error neither holds, so the refined sigma is
    widened to include the difference and the truth lies inside; K, which agrees, is kept."""
    from jointbench.bench.analysis.refine import widen_on_disagreement

    theta, start = {"Jm": 14.591, "K": 89769.1}, {"Jm": 14.7564, "K": 89790.2}
    sigma, sigma_c = {"Jm": 0.0108, "K": 54.1}, {"Jm": 0.0364, "K": 192.6}
    s, sc, notes = widen_on_disagreement(theta, start, sigma, sigma_c,
                                         {"Jm": 0.0340, "K": 183.5})
    d = 14.7564 - 14.591
    assert s["Jm"] == pytest.approx(math.hypot(0.0108, d))
    assert sc["Jm"] == pytest.approx(math.hypot(0.0364, d))
    assert abs(14.591 - 14.7) / sc["Jm"] < 1 < abs(14.591 - 14.7) / sigma_c["Jm"]
    assert (s["K"], sc["K"]) == (54.1, 192.6)
    assert len(notes) == 1 and notes[0].startswith("Jm: refined and least squares differ")


def test_sigma_withdrawn_when_the_refinement_stays_at_its_start():
    """Issue 17: arm6 axis2 at 350.87 Hz (seed 1), the refinement ended at Jm 40.9568 from the
    least squares' 40.9566 (corrected sigma 0.125), with a white sigma of 3.3e-5 that put the
    truth 40.96 about 50 sigma away. Nothing moved by a least-squares sigma, so the sigma
    printed is the least squares' corrected one (truth then within 0.1 of it); one parameter
    that moves keeps the refinement's own sigma."""
    from jointbench.bench.analysis.refine import withdraw_when_unmoved
    start, theta = {"Jm": 40.9566, "K": 200056.0}, {"Jm": 40.9568, "K": 200057.0}
    ls_c = {"Jm": 0.1254, "K": 431.0}
    sigma, sigma_c = {"Jm": 3.25e-5, "K": 0.049}, {"Jm": 9e-5, "K": 0.2}
    s, sc, notes = withdraw_when_unmoved(theta, start, sigma, sigma_c, ls_c)
    assert s == sc == ls_c and len(notes) == 1 and "withdrawn" in notes[0]
    assert abs(theta["Jm"] - 40.96) / s["Jm"] < 0.1 < 3 < abs(theta["Jm"] - 40.96) / sigma["Jm"]
    moved = {**theta, "K": 200056.0 + 2 * 431.0}
    assert withdraw_when_unmoved(moved, start, sigma, sigma_c, ls_c) == (sigma, sigma_c, [])
