"""Edge cases of the command line, one test each: `--config` on the moving joint, the
`--amplitude` default, nan/inf rows and numpy warnings in campaign summaries beside a zero
truth, and `--joint` by index or name (the report rows on a real identification:
tests/sim/test_report_rows.py)."""

from __future__ import annotations

import re
import subprocess
import sys
import warnings

import numpy as np
import pytest

from jointbench.bench.cli import main
from jointbench.bench.cli.parser import build_parser
from jointbench.bench.sim import defaults as sim_defaults
from jointbench.bench.sim.reference import Chirp
from jointbench.identification.log import read_log
from jointbench.identification.summary import parameter_stats, stats_table
from jointbench.models import ModelStructureError, load_model, model_path, select_axis


def test_config_of_the_moving_joint_centres_the_experiment(tmp_path, capsys):
    # arm6 axis2 rests at -0.293 rad under gravity; --config axis2=0 must centre it at 0,
    # also for the model given as a file.
    out = tmp_path / "c.csv"
    assert main(["simulate", "--model", str(model_path("arm6")), "--joint", "axis2",
                 "--config", "axis2=0", "--duration", "5", "--out", str(out), "--quiet"]) == 0
    log = read_log(out)
    assert float(log.meta["truth_center"]) == 0.0
    assert float(log.meta["truth_q0"]) < -0.2
    # the motor starts at 0 less the spring's static deflection (0.7 mrad), the chirp around it
    assert abs(log.q_m[0]) < 1e-3 and np.max(np.abs(log.q_ref)) < sim_defaults.AMPLITUDE_RAD + 1e-3


def test_amplitude_help_is_the_default_used(tmp_path, capsys):
    sub = build_parser()._subparsers._group_actions[0].choices["simulate"]
    text = " ".join(sub.format_help().split())
    assert f"(default {sim_defaults.AMPLITUDE_RAD:g}," in text
    assert Chirp().amplitude == sim_defaults.AMPLITUDE_RAD
    out = tmp_path / "a.csv"
    assert main(["simulate", "--duration", "5", "--out", str(out), "--quiet"]) == 0
    chirp = read_log(out).meta["chirp"]
    assert f"amplitude {sim_defaults.AMPLITUDE_RAD:g} rad" in chirp


def test_zero_truth_campaign_rows_are_finite_and_silent():
    rng = np.random.default_rng(0)
    est = rng.normal(0.0, 0.01, 20)
    sig = np.full(20, 0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any numpy RuntimeWarning fails the test
        s = parameter_stats("MX", est, np.zeros(20), {"paper": sig})
        table = stats_table([s], ("paper",))
    assert s.bias == pytest.approx(np.mean(est)) and np.isnan(s.bias_pct)
    row = table.splitlines()[-1]
    assert "truth 0" in row and "nan" not in row and "inf" not in row
    assert f"bias {np.mean(est):+.4g}" in row
    assert s.coverage["paper"].coverage == pytest.approx(np.mean(np.abs(est) <= 0.02))
    empty = stats_table([parameter_stats("K", np.full(3, np.nan), np.ones(3))], ("paper",))
    assert "nan" not in empty and empty.splitlines()[-1].split()[:4] == ["K", "0", "-", "-"]


@pytest.mark.slow
def test_arm6_campaign_prints_no_nan_and_no_warning(tmp_path):
    out = tmp_path / "r.csv"
    proc = subprocess.run([sys.executable, "-W", "error::RuntimeWarning", "-m",
                           "jointbench.bench.cli", "campaign", "--model", "arm6", "--joint", "1",
                           "--runs", "2", "--duration", "10", "--workers", "1", "--out", str(out),
                           "--quiet"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "Warning" not in proc.stderr
    mx = [line for line in proc.stdout.splitlines() if line.startswith(("MX ", "MY "))]
    assert len(mx) == 4 and all("truth 0" in line for line in mx)
    assert not re.search(r"\b(nan|inf)\b", proc.stdout)


def test_joint_by_index_or_name(tmp_path):
    _, axes, path = load_model("arm6")
    assert select_axis(axes, "1").name == "axis1" and select_axis(axes, "axis3").name == "axis3"
    assert select_axis(axes, "6").name == "axis6" and select_axis(axes, None).name == "axis1"
    with pytest.raises(ModelStructureError, match="give a name or an index: 1 axis1, 2 axis2"):
        select_axis(axes, "7")
    with pytest.raises(ModelStructureError):
        select_axis(axes, "0")
    out = tmp_path / "j.csv"
    assert main(["simulate", "--model", "arm6", "--joint", "3", "--duration", "5",
                 "--out", str(out), "--quiet"]) == 0
    assert read_log(out).meta["joint"] == "axis3"
