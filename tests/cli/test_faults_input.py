"""Issue 16, inputs: sampling (the rate comes from t), user MJCF values that cannot be
physical, the memory a command needs, campaign options and resume, messages that name the
option, line or column, strict JSON and strictly numeric fields, clipped torque. One
parametrised test per class of attack; Hypothesis fuzzes the campaign options, diagnose and
design-filter (the loader and identify: tests/cli/test_faults.py)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointbench.bench.campaign.settings import CampaignError, RunSettings
from jointbench.bench.campaign.spec import CampaignSpec
from jointbench.identification.log import read_log, write_log
from jointbench.models import model_path
from test_faults_output import run


@pytest.fixture(scope="module")
def sim(tmp_path_factory, bench_log):
    """A 20 s prototype log (seed 1): the file, its Log and its text."""
    path = tmp_path_factory.mktemp("sim") / "native.csv"
    log = bench_log("prototype", duration=20.0, seed=1)
    write_log(log, path)
    return path, read_log(path), path.read_text()


def _rows(text: str, fn) -> str:
    """`text` with fn(cells) applied to every data row."""
    out, header = [], False
    for line in text.splitlines():
        if line.startswith("#") or not header:
            header = header or not line.startswith("#")
            out.append(line)
            continue
        out.append(",".join(fn(line.split(","))))
    return "\n".join(out) + "\n"


def _meta(text: str, key: str, value: str | None) -> str:
    lines = [ln for ln in text.splitlines() if not ln.startswith(f"# {key}:")]
    if value is not None:
        lines.insert(1, f"# {key}: {value}")
    return "\n".join(lines) + "\n"


def _t_scaled(scale: float):
    return lambda text: _rows(_meta(text, "sample_rate_hz", None),
                              lambda c: [repr(float(c[0]) * scale)] + c[1:])


# --- 3. Sampling: the rate comes from t -----------------------------------------------------

@pytest.mark.parametrize("edit, status, says", [
    (lambda s: _meta(s, "sample_rate_hz", "353"), 0, "the rate of t is used"),
    (lambda s: _meta(s, "sample_rate_hz", "351.2"), 0, "differs from the rate of t"),
    (lambda s: _meta(s, "sample_rate_hz", "360"), 2, "contradicts t"),
    (_t_scaled(1000.0), 2, "from milliseconds: divide by 1000"),
    (_t_scaled(1e-6), 2, "must be in seconds"),
])
def test_sampling_rate_comes_from_t(tmp_path, sim, edit, status, says):
    """A metadata rate off by 0.05-1 % is a warning and changes nothing (t wins: the same
    estimates as without the key); over 1 % and implausible rates (t in ms, in us) exit 2."""
    path = tmp_path / "r.csv"
    path.write_text(edit(sim[2]))
    rc, out, err = run(["identify", path, "--json"])
    assert rc == status and says in err, err
    if status == 0:
        bare = tmp_path / "bare.csv"
        bare.write_text(_meta(sim[2], "sample_rate_hz", None))
        rc0, out0, _ = run(["identify", bare, "--json"])
        assert rc0 == 0
        assert json.loads(out)["physical"] == pytest.approx(json.loads(out0)["physical"],
                                                             rel=1e-9)


def test_metadata_rate_that_agrees_is_used_exactly(sim):
    log = sim[1]
    assert log.sample_rate_hz == 350.87  # the written value: results bit for bit as before
    assert abs(log.rate_from_t / 350.87 - 1) < 1e-9


# --- 4. User MJCF: values that cannot be physical, missing parts ----------------------------

def _arm_without_spring(text: str) -> str:
    import re
    return re.sub(r'<fixed name="axis3_spring".*?</fixed>', "", text, flags=re.S)


@pytest.mark.parametrize("model, edit, says", [
    ("prototype", ('stiffness="20341.0458"', 'stiffness="0"'), "tendon 'axis1_spring': stiffness"),
    ("prototype", ('stiffness="20341.0458"', 'stiffness="-5"'), "tendon 'axis1_spring': stiffness"),
    ("prototype", ('armature="174.7996"', 'armature="0"'), "joint 'axis1_motor': armature"),
    ("prototype", ('damping="235.9100"', 'damping="-1"'), "joint 'axis1_motor': damping"),
    ("prototype", ('frictionloss="8.4612"', 'frictionloss="-3"'), "joint 'axis1': frictionloss"),
    ("prototype", ('joint="axis1" coef="-1"', 'joint="axis1" coef="-2"'), "{'axis1_motor': 1.0"),
    ("arm6", _arm_without_spring, "no fixed tendon 'axis3_spring'"),
])
def test_unphysical_or_incomplete_mjcf_is_named(tmp_path, model, edit, says):
    text = model_path(model).read_text()
    text = edit(text) if callable(edit) else text.replace(*edit)
    path = tmp_path / "user.xml"
    path.write_text(text)
    rc, out, err = run(["simulate", "--model", path, "--joint", "axis2" if model == "arm6"
                        else "axis1", "--duration", "5", "--out", tmp_path / "o.csv"])
    assert rc == 2 and says in err, err
    assert "np.float64" not in err and not (tmp_path / "o.csv").exists()


# --- 5. Resources ---------------------------------------------------------------------------

@pytest.mark.parametrize("args, env, says", [
    (["simulate", "--duration", "1e6"], None, "342,846 MB"),
    (["simulate", "--duration", "1e9"], None, "samples need about"),
    (["simulate", "--rate", "1e6", "--duration", "1e4"], None, "samples need about"),
    (["campaign", "--duration", "1e6", "--runs", "1"], None, "samples need about"),
    (["simulate", "--duration", "60"], "50", "over the 50 MB limit"),
    (["simulate", "--duration", "60"], "lots", "give a positive number of MB"),
])
def test_memory_is_estimated_and_refused_up_front(tmp_path, monkeypatch, args, env, says):
    """3.5e8 samples (--duration 1e6) need about 1 KiB each: refused with the number before
    anything runs (it once reached 17 GB RSS in 30 s); JOINTBENCH_MAX_MEMORY_MB sets the
    limit."""
    if env is not None:
        monkeypatch.setenv("JOINTBENCH_MAX_MEMORY_MB", env)
    else:
        monkeypatch.setenv("JOINTBENCH_MAX_MEMORY_MB", "12053")  # the figure in the README
    monkeypatch.chdir(tmp_path)
    rc, out, err = run(args + ["--workers", "1"] if args[0] == "campaign" else args)
    assert rc == 2 and says in err, err
    assert os.listdir(tmp_path) == []


# --- 6. Campaigns ---------------------------------------------------------------------------

@pytest.mark.parametrize("option, says", [
    (["--duration", "1"], "--duration 1: must be at least 4 s"),
    (["--wn", "-5"], "--wn -5: must be in"),
    (["--decimate", "0"], "--decimate 0: must be between 1 and"),
    (["--amplitude", "-1"], "--amplitude -1: must be positive"),
    (["--motor-bits", "5000"], "--motor-bits 5000: must be between 1 and 52"),
    (["--sweep", "Nd=26,0"], "--sweep Nd=0: --decimate must be"),
    (["--noise", "nan"], "--noise: nan is not finite"),
    (["--seed", "-1"], "--seed must be >= 0"),
])
def test_campaign_options_are_checked_before_any_run(tmp_path, monkeypatch, option, says):
    import jointbench.bench.campaign.run as campaign_run
    monkeypatch.setattr(campaign_run, "run_campaign", lambda *a, **k: pytest.fail("ran"))
    rc, out, err = run(["campaign", "--runs", "2", "--workers", "1", "--out",
                        tmp_path / "c.csv", *option])
    assert rc == 2 and says in err, err
    assert os.listdir(tmp_path) == []


def test_campaign_resume_retries_failed_rows_and_refuses_an_edited_model(tmp_path):
    model = tmp_path / "my.xml"
    model.write_text(model_path("prototype").read_text())
    table = tmp_path / "c.csv"
    args = ["campaign", "--model", model, "--runs", "2", "--workers", "1", "--duration", "5",
            "--out", table, "--quiet", "--json"]
    assert run(args)[0] == 0
    text = table.read_text()
    first = text.splitlines()[3]
    cells = first.split(",")
    cells[3], cells[4] = "failed", "simulation: killed"
    table.write_text(text.replace(first, ",".join(cells)))
    rc, out, err = run(args)
    assert rc == 0, err
    summary = json.loads(out)
    assert summary["ok"] == 2 and summary["timing"]["runs_this_invocation"] == 1
    assert table.read_text() == text  # the retried row is the same run, bit for bit
    model.write_text(model.read_text().replace('damping="83.1508"', 'damping="90"'))
    rc, out, err = run(args)
    assert rc == 2 and "my.xml changed since this table was started" in err, err


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG: Linux")
def test_campaign_workers_die_with_their_parent(tmp_path):
    """SIGKILL of the campaign process: its pool workers go too (they lived on for minutes)."""
    script = tmp_path / "pool.py"
    script.write_text(
        "import os, time\n"
        "from jointbench.bench.campaign.executors import LocalExecutor\n"
        "if __name__ == '__main__':\n"
        "    ex = LocalExecutor(2)\n"
        "    list(ex.map_unordered(time.sleep, [0.01, 0.01]))\n"
        "    print(' '.join(str(p) for p in ex._pool._processes), flush=True)\n"
        "    list(ex.map_unordered(time.sleep, [600, 600]))\n")
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True,
                              stderr=subprocess.DEVNULL, env=dict(os.environ))
    workers = [int(p) for p in parent.stdout.readline().split()]
    assert len(workers) == 2
    parent.send_signal(signal.SIGKILL)
    parent.wait()

    def alive(pid: int) -> bool:  # a zombie waiting for init counts as dead
        try:
            return Path(f"/proc/{pid}/stat").read_text().split(")")[1].split()[0] != "Z"
        except FileNotFoundError:
            return False
    for _ in range(100):  # the kernel's SIGKILL is immediate; the watchdog polls each second
        if not any(alive(p) for p in workers):
            break
        time.sleep(0.1)
    assert not any(alive(p) for p in workers)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(duration=st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.just(60.0)),
       wn=st.one_of(st.none(), st.floats(allow_nan=True, allow_infinity=True)),
       Nd=st.one_of(st.none(), st.integers(-10, 10**6)),
       bits=st.one_of(st.none(), st.integers(-5, 10**4)),
       amplitude=st.one_of(st.none(), st.floats(allow_nan=True, allow_infinity=True)),
       noise=st.floats(allow_nan=True, allow_infinity=True))
def test_fuzz_campaign_options(duration, wn, Nd, bits, amplitude, noise):
    """Any option values: either a CampaignError naming an option, or settings every run
    can start with (finite, in range)."""
    try:
        spec = CampaignSpec(base=RunSettings(duration=duration, wn=wn, Nd=Nd, motor_bits=bits,
                                             amplitude=amplitude, noise=noise), runs=1)
    except CampaignError as err:
        assert str(err).startswith("--")
        return
    s = spec.base
    assert np.isfinite(s.duration) and s.duration >= 4 and np.isfinite(s.noise) and s.noise >= 0
    assert wn is None or 0 < wn < np.pi * 350.87
    assert Nd is None or 1 <= Nd <= s.duration * 350.87 / 16
    assert bits is None or 1 <= bits <= 52
    assert amplitude is None or (np.isfinite(amplitude) and amplitude > 0)
