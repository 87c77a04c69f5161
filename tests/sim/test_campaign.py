"""Campaigns (bench/campaign/), their engines (bench/campaign/executors.py), the Monte Carlo
statistics (identification/summary.py) and the filter search (bench/campaign/tuning.py).

Short experiments (10 s) keep the file fast; the 200-run coverage measurement is in
benchmarks/campaign.py."""

from __future__ import annotations

import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from jointbench.bench.campaign.run import run_campaign
from jointbench.bench.campaign.scatter import scattered_factors, scattered_mjcf
from jointbench.bench.campaign.settings import CampaignError, RunSettings
from jointbench.bench.campaign.spec import CampaignSpec
from jointbench.bench.campaign.table import CampaignTable, read_table
from jointbench.bench.campaign.executors import LocalExecutor, SerialExecutor
from jointbench.identification.summary import coverage, parameter_stats, wilson_interval

REPO = Path(__file__).resolve().parents[2]
SHORT = RunSettings(duration=10.0)


def small_spec(runs: int = 4, **kw) -> CampaignSpec:
    return CampaignSpec(base=RunSettings(**{"duration": 10.0, **kw}), runs=runs, seed=7)


def data_rows(path: Path) -> list[str]:
    return path.read_text().splitlines()[3:]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The 4-run campaign done serially in this process: the table every engine must match."""
    path = tmp_path_factory.mktemp("ref") / "ref.csv"
    result = run_campaign(small_spec(), path, SerialExecutor())
    return path, result


# ---------------------------------------------------------------------------------------------
# Monte Carlo statistics (pure numerics)


def test_wilson_interval_known_values():
    # 0 of n: upper bound z^2 / (n + z^2) (Wilson 1927); symmetric about 1/2 for n/2.
    z = 1.959964
    lo, hi = wilson_interval(0, 10)
    assert lo == 0.0 and hi == pytest.approx(z * z / (10 + z * z), rel=1e-12)
    lo, hi = wilson_interval(50, 100)
    assert lo + hi == pytest.approx(1.0, abs=1e-12)
    assert math.isnan(wilson_interval(0, 0)[0])


def test_coverage_of_gaussian_errors():
    rng = np.random.default_rng(0)
    e = rng.standard_normal(40000)
    ones = np.ones_like(e)
    # sigma calibrated: P(|z| <= 2) = 0.9545; sigma halved: P(|z| <= 1) = 0.6827.
    # Binomial std at n = 40000 is about 0.001 and 0.0023: 4.5 of them as tolerance.
    assert coverage(e, ones).coverage == pytest.approx(0.9545, abs=0.005)
    assert coverage(e, 0.5 * ones).coverage == pytest.approx(0.6827, abs=0.011)
    assert coverage(e, ones).std_over_sigma == pytest.approx(1.0, abs=0.02)
    # NaN sigma: those runs do not count
    s = ones.copy()
    s[:100] = np.nan
    assert coverage(e, s).n == 40000 - 100


def test_parameter_stats_matches_numpy():
    rng = np.random.default_rng(1)
    truth = 100.0 * (1 + 0.1 * rng.standard_normal(50))
    est = truth + 2.0 + rng.standard_normal(50)
    est[3] = np.nan
    st = parameter_stats("K", est, truth, {"paper": np.full(50, 1.0)})
    ok = np.isfinite(est)
    e = est[ok] - truth[ok]
    assert st.n == 49
    assert st.bias == pytest.approx(e.mean(), rel=1e-12)
    assert st.std == pytest.approx(e.std(ddof=1), rel=1e-12)
    assert st.bias_pct == pytest.approx(np.mean(100 * e / truth[ok]), rel=1e-12)
    inside = np.mean(np.abs(e) <= 2.0)
    assert st.coverage["paper"].coverage == pytest.approx(inside, rel=1e-12)


# ---------------------------------------------------------------------------------------------
# Specification and seeds


def test_run_seed_depends_on_campaign_seed_and_repeat_only():
    a = CampaignSpec(base=SHORT, runs=5, seed=3)
    b = CampaignSpec(base=SHORT, runs=50, seed=3)
    assert [a.task(i).seed for i in range(5)] == [b.task(i).seed for i in range(5)]
    assert a.task(0).seed != CampaignSpec(base=SHORT, runs=5, seed=4).task(0).seed
    assert len({b.task(i).seed for i in range(50)}) == 50
    # a sweep: repeat j of every point shares its noise seed (paired comparison)
    sw = CampaignSpec(base=SHORT, runs=5, seed=3, sweep="amplitude", values=(0.05, 0.1))
    assert sw.total == 10
    assert sw.task(7).repeat == 2 and sw.task(7).seed == a.task(2).seed
    assert sw.task(7).settings.amplitude == 0.1 and sw.task(2).settings.amplitude == 0.05


def test_bad_specs_are_refused():
    with pytest.raises(CampaignError, match="cannot sweep"):
        CampaignSpec(base=SHORT, sweep="gains", values=(1.0,))
    with pytest.raises(CampaignError, match="runs"):
        CampaignSpec(base=SHORT, runs=0)
    with pytest.raises(CampaignError, match="identification model"):
        RunSettings(id_models=("rigid",))


# ---------------------------------------------------------------------------------------------
# Runs, failures, determinism across engines


def test_serial_campaign_rows_against_truth(reference):
    path, result = reference
    assert result.summary["ok"] == 4 and result.summary["failed"] == 0
    spec, rows = read_table(path)
    assert spec == small_spec()
    assert [int(r["run"]) for r in rows] == [0, 1, 2, 3]
    for r in rows:
        truth_K = float(r["truth.K"])
        assert truth_K == pytest.approx(20341.0458)
        # 10 s chirps: K within 2 % on the joint-motor model, 5 % on motor-only (README
        # accuracy on 60 s: 0.2 % and 0.7 %); the paper's sigma is present and positive.
        assert float(r["jm.K"]) == pytest.approx(truth_K, rel=0.02)
        assert float(r["mo.K"]) == pytest.approx(truth_K, rel=0.05)
        assert float(r["jm.K.sigma"]) > 0
    # the summary's statistics come from exactly these rows
    K = [s for s in result.summary["groups"][0]["models"]["joint-motor"] if s["name"] == "K"][0]
    errs = np.array([float(r["jm.K"]) - float(r["truth.K"]) for r in rows])
    assert K["bias"] == pytest.approx(errs.mean(), rel=1e-12)
    assert K["n"] == 4


def test_process_pool_gives_the_same_table(reference, tmp_path):
    ref_path, _ = reference
    out = tmp_path / "pool.csv"
    with LocalExecutor(2) as ex:
        result = run_campaign(small_spec(), out, ex)
    assert result.new == 4
    assert out.read_bytes() == ref_path.read_bytes()


def test_dask_cluster_on_loopback_gives_the_same_table(reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    from jointbench.bench.cli import main

    ref_path, _ = reference
    out = tmp_path / "dask.csv"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  host="127.0.0.1", protocol="tcp",
                                  dashboard_address=None) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        rc = main(["campaign", "--runs", "4", "--seed", "7", "--duration", "10", "--quiet",
                   "--scheduler", cluster.scheduler_address, "--out", str(out)])
    assert rc == 0
    assert out.read_bytes() == ref_path.read_bytes()
    assert (tmp_path / "dask.summary.json").exists() and (tmp_path / "dask.summary.md").exists()


def test_failed_run_is_recorded_and_the_rest_go_on(tmp_path):
    # Nd = 219 passes the options' check (16 decimated rows of a 10 s run) but the motor-only
    # model's fourth derivatives need 3513 samples of the 3510 (options out of range are
    # refused before any run: tests/test_faults2.py)
    spec = CampaignSpec(base=SHORT, runs=2, seed=7, sweep="Nd", values=(26, 219))
    result = run_campaign(spec, tmp_path / "f.csv", SerialExecutor())
    status = {int(r["run"]): (r["status"], r["reason"]) for r in result.rows}
    assert [status[i][0] for i in range(4)] == ["ok", "ok", "failed", "failed"]
    assert "too few" in status[2][1] and "motor-only" in status[2][1]
    assert result.summary["ok"] == 2 and result.summary["failed"] == 2
    assert result.summary["groups"][0]["ok"] == 2 and result.summary["groups"][1]["ok"] == 0
    # the failed runs' truth is still recorded (the simulation worked)
    assert all(r["truth.K"] not in ("", "nan") for r in result.rows)


def test_worker_death_is_retried_then_recorded():
    with LocalExecutor(2) as ex:
        done = {d.item: d for d in ex.map_unordered(_die_on_three, range(6))}
    assert sorted(done) == list(range(6))
    assert done[3].error is not None and "died" in done[3].error
    assert all(done[i].value == i * i for i in range(6) if i != 3)


def _die_on_three(x: int) -> int:
    if x == 3:
        os._exit(1)
    return x * x


# ---------------------------------------------------------------------------------------------
# Resuming


def test_resume_drops_a_partial_line_and_duplicates_nothing(reference, tmp_path):
    ref_path, _ = reference
    out = tmp_path / "resume.csv"
    lines = ref_path.read_text().splitlines(keepends=True)
    # header (3 lines) + runs 0 and 2 (completion order is free) + half of run 3's line
    out.write_text("".join(lines[:3] + [lines[3], lines[5], lines[6][:40]]))
    result = run_campaign(small_spec(), out, SerialExecutor())
    assert result.resumed == 2 and result.new == 2
    assert out.read_bytes() == ref_path.read_bytes()


def test_resume_after_sigkill(tmp_path):
    """A real kill: the CLI in a subprocess, SIGKILL once two rows are on disk, resume."""
    args = ["campaign", "--runs", "16", "--seed", "7", "--duration", "10", "--workers", "1",
            "--quiet", "--id-models", "joint-motor"]
    killed = tmp_path / "killed.csv"
    proc = subprocess.Popen([sys.executable, "-m", "jointbench.bench.cli", *args, "--out", str(killed)],
                            cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        while proc.poll() is None:
            if killed.exists() and len(data_rows(killed)) >= 2:
                proc.send_signal(signal.SIGKILL)
                break
            time.sleep(0.005)
    finally:
        proc.wait()
    was_killed = proc.returncode == -signal.SIGKILL
    before = len(data_rows(killed))
    from jointbench.bench.cli import main

    assert main([*args, "--out", str(killed)]) == 0
    ref = tmp_path / "ref16.csv"
    assert main([*args, "--out", str(ref)]) == 0
    assert killed.read_bytes() == ref.read_bytes()
    runs = [int(line.split(",")[0]) for line in data_rows(killed)]
    assert runs == list(range(16))
    if was_killed:
        assert before < 16


def test_resume_with_another_spec_is_refused(reference, tmp_path, capsys):
    from jointbench.bench.cli import main

    out = tmp_path / "other.csv"
    shutil.copy(reference[0], out)
    before = out.read_bytes()
    with pytest.raises(CampaignError, match=r"other.csv:2: .*different campaign"):
        CampaignTable(out, small_spec(runs=5))
    rc = main(["campaign", "--runs", "5", "--seed", "7", "--duration", "10", "--quiet",
               "--workers", "1", "--out", str(out)])
    assert rc == 2
    assert "different campaign" in capsys.readouterr().err
    assert out.read_bytes() == before  # never touched


@pytest.mark.parametrize("argv, message", [
    (["--sweep", "gains=1,2"], "cannot sweep"),
    (["--sweep", "Nd=2.5"], "not an integer"),
    (["--runs", "0"], "runs"),
    (["--id-models", "rigid"], "identification model"),
    (["--noise", "-1"], "noise"),
    (["--model", "no_such.xml"], "no_such.xml"),
])
def test_cli_bad_input_exit_2(argv, message, tmp_path, capsys):
    from jointbench.bench.cli import main

    rc = main(["campaign", "--quiet", "--workers", "1", "--out", str(tmp_path / "x.csv"), *argv])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and "Traceback" not in err


# ---------------------------------------------------------------------------------------------
# Parameter scatter


def test_scattered_model_round_trip_and_truth_follows(tmp_path):
    from jointbench.models import load_model
    from jointbench.models.truth import axis_truth

    def truth_of(path):
        model, axes, _ = load_model(path)
        return axis_truth(model, axes[0], model.qpos0)

    xml, joint = scattered_mjcf("prototype", None, scattered_factors(0.0, 1))
    same = tmp_path / "same.xml"
    same.write_text(xml)
    t0, t1 = truth_of("prototype"), truth_of(same)
    for p in ("K", "Jm", "JL", "FVm", "FSm", "FV", "FS", "MX", "MY"):
        assert getattr(t1, p) == pytest.approx(getattr(t0, p), rel=1e-12), p
    f = scattered_factors(0.1, 5)
    xml, _ = scattered_mjcf("prototype", None, f)
    moved = tmp_path / "moved.xml"
    moved.write_text(xml)
    t2 = truth_of(moved)
    for p in ("K", "Jm", "JL", "FVm", "FSm", "FV", "FS"):
        assert getattr(t2, p) == pytest.approx(f[p] * getattr(t0, p), rel=1e-9), p
    assert t2.MY == pytest.approx(f["JL"] * t0.MY, rel=1e-9)  # the payload scales as a whole


def test_scatter_campaign_identifies_each_runs_truth(tmp_path):
    spec = CampaignSpec(base=RunSettings(duration=10.0, scatter=0.1,
                                         id_models=("joint-motor",)), runs=3, seed=2)
    result = run_campaign(spec, tmp_path / "s.csv", SerialExecutor())
    Ks = [float(r["truth.K"]) for r in result.rows]
    assert len(set(Ks)) == 3 and all(abs(k / 20341.0458 - 1) > 1e-6 for k in Ks)
    for r in result.rows:
        assert r["status"] == "ok"
        for p in ("K", "Jm", "JL"):
            assert float(r[f"jm.{p}"]) == pytest.approx(float(r[f"truth.{p}"]), rel=0.03), p


# ---------------------------------------------------------------------------------------------
# Filter tuning


def test_tune_filter_small_grid():
    from jointbench.bench.campaign.tuning import tune_filter

    r = tune_filter("prototype", None, (120.0, 176.0), (13, 26), seeds=1,
                    executor=SerialExecutor(), duration=20.0, seed=3)
    assert r.objective.shape == (2, 2) and np.isfinite(r.objective).all()
    best = r.candidates[0]
    assert best.label.startswith("optimum")
    assert best.search_rms_pct == pytest.approx(np.min(r.objective), rel=1e-12)
    paper = [c for c in r.candidates if c.label == "paper section 4"][0]
    assert (paper.wn, paper.Nd) == (176.0, 26)
    # the paper's pair is also on the grid: computed twice on the same logs, same value
    assert paper.search_rms_pct == pytest.approx(r.objective[1, 1], rel=1e-12)
    eq28 = [c for c in r.candidates if c.label.startswith("eq. (28), paper's")][0]
    assert eq28.wn == pytest.approx(181.04, abs=0.01)  # ERRATA table
    assert all(math.isfinite(c.validation_rms_pct) for c in r.candidates)


def test_cli_json_is_one_strict_json_object(tmp_path, capsys):
    import json

    from jointbench.bench.cli import main

    rc = main(["campaign", "--runs", "1", "--duration", "10", "--workers", "1", "--json",
               "--id-models", "joint-motor", "--out", str(tmp_path / "j.csv")])
    out = capsys.readouterr().out
    assert rc == 0
    summary = json.loads(out, parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))
    assert summary["runs"] == 1 and summary["ok"] == 1
    K = summary["groups"][0]["models"]["joint-motor"][0]
    assert K["name"] == "K" and K["std"] is None  # one run: no spread (null, not NaN)
    assert json.loads((tmp_path / "j.summary.json").read_text())["runs"] == 1


def test_cli_rate_runs_the_experiment_at_that_rate(tmp_path, capsys):
    """Issue 17: `campaign --rate` (the arm at 1 kHz here); a rate outside 10 Hz-100 kHz is
    bad input before any run."""
    import json

    from jointbench.bench.cli import main

    out = tmp_path / "r.csv"
    rc = main(["campaign", "--model", "arm6", "--joint", "axis6", "--runs", "1", "--duration",
               "10", "--workers", "1", "--json", "--rate", "1000", "--id-models", "joint-motor",
               "--out", str(out)])
    summary = json.loads(capsys.readouterr().out)
    assert rc == 0 and summary["ok"] == 1
    assert summary["spec"]["base"]["rate"] == 1000.0
    K = summary["groups"][0]["models"]["joint-motor"][0]
    assert K["name"] == "K" and abs(K["bias_pct"]) < 1.0   # 10 s at 1 kHz: measured -0.17 %
    rc = main(["campaign", "--runs", "1", "--rate", "5", "--out", str(tmp_path / "b.csv")])
    assert rc == 2 and "--rate" in capsys.readouterr().err
    assert not (tmp_path / "b.csv").exists()


def test_filter_overrides_keep_the_chooser_for_what_is_not_given():
    """A campaign's --wn alone keeps the stencil identify chooses from f1 / Fs (it used to
    force 3 points); an explicit --stencil 3 is kept; nothing given: identify's own choice."""
    from jointbench.bench.campaign.run import _filter
    from jointbench.bench.sim.experiment import run_experiment
    from jointbench.identification.filter_choice import choose_filter

    log = run_experiment("arm6", "axis1", duration=10.0, seed=0).log
    base = choose_filter(log).settings
    assert base.stencil == 5      # arm6's ~15 Hz mode at the bench's rate needs 5 points
    assert _filter(RunSettings(model="arm6"), log) == (None, None)
    s, mode = _filter(RunSettings(model="arm6", wn=200.0), log)
    assert (s.wn, s.Nd, s.stencil) == (200.0, base.Nd, base.stencil)
    own = choose_filter(log).first_mode    # the log's own measurement goes to identify
    assert (mode.found, mode.method, mode.note) == (own.found, own.method, own.note)
    assert _filter(RunSettings(model="arm6", wn=200.0, stencil=3), log)[0].stencil == 3
