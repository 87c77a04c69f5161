"""Plug-in methods are contained (bench/campaign/host.py, methods.py): a method's process group
dies with its deadline and with the campaign, SIGKILL included, children it forked too; its
module is imported, and its answer read, in its host under the deadline; its memory is capped;
its prints never reach `campaign --json`; a method that ends its process is a failed run. The
blind log a method receives holds no seed, source, chirp or locked configuration. `--junit`
and `--method-timeout` are checked before any run; survey and campaign count their workers'
memory.

Every plug-in is a small file written to tmp_path; campaigns are one or two runs of 5 s."""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import jointbench as jb
from jointbench.bench.campaign.methods import BLIND_META, blind
from jointbench.bench.campaign.settings import CampaignError
from jointbench.bench.cli import main

# Most tests start processes and wait on deadlines: the file is left out of `make check`.
pytestmark = pytest.mark.slow

GRACE_S = 20.0   # how long a killed process group may take to be gone on a loaded machine
TINY = ["--runs", "1", "--duration", "5", "--id-models", "joint-motor", "--quiet"]


def _alive(pid: int) -> bool:
    """True while `pid` runs (a zombie, killed and not yet reaped, counts as gone)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state not in ("Z", "X")


def _gone(pid: int) -> bool:
    """True when `pid` is gone within GRACE_S."""
    end = time.monotonic() + GRACE_S
    while time.monotonic() < end:
        if not _alive(pid):
            return True
        time.sleep(0.1)
    return False


def _wait_for(path: Path, timeout_s: float = 120.0) -> int:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if path.exists() and path.read_text().strip():
            return int(path.read_text())
        time.sleep(0.1)
    raise AssertionError(f"{path} never written")


def _plugin(tmp_path: Path, body: str, name: str = "plug.py") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(body))
    return path


def _campaign(args: list[str], cwd: Path, env: dict | None = None, timeout: float = 300):
    return subprocess.run([sys.executable, "-m", "jointbench.bench.cli", "campaign", *args],
                          cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, **(env or {})})


def _rows(table: Path) -> list[dict[str, str]]:
    from jointbench.bench.campaign.table import read_table
    return read_table(table)[1]


# ---------------------------------------------------------------------------------------------
# Processes


FORKS = """
    import os, time
    from pathlib import Path

    def forks(log):
        pid = os.fork()
        if pid == 0:                      # the child: outlive the call, then write a file
            Path("child.pid").write_text(str(os.getpid()))
            time.sleep(30)
            Path("child_survived").write_text("yes")
            os._exit(0)
        # the child runs before the call returns (the campaign then contains it), whatever the
        # machine's load: otherwise it can be killed before it wrote its pid
        while not (Path("child.pid").exists() and Path("child.pid").read_text().strip()):
            time.sleep(0.01)
        return {"K": 2.0e4}

    def sleeps(log):
        Path("host.pid").write_text(str(os.getpid()))
        if os.fork() == 0:
            Path("child.pid").write_text(str(os.getpid()))
            time.sleep(60)
            os._exit(0)
        time.sleep(60)
        return {"K": 2.0e4}
"""


@pytest.mark.parametrize("workers", ["1", "2"])
def test_a_forked_child_does_not_outlive_the_campaign(tmp_path, workers):
    _plugin(tmp_path, FORKS)
    done = _campaign([*TINY, "--workers", workers, "--method", "plug.py:forks", "--out",
                      "c.csv"], tmp_path)
    assert done.returncode == 0, done.stderr
    assert _rows(tmp_path / "c.csv")[0]["forks.status"] == "ok"
    child = _wait_for(tmp_path / "child.pid", 10)
    assert _gone(child)
    assert not (tmp_path / "child_survived").exists()


@pytest.mark.parametrize("workers", ["1", "2"])
def test_kill_9_of_the_campaign_leaves_no_host_alive(tmp_path, workers):
    _plugin(tmp_path, FORKS)
    proc = subprocess.Popen([sys.executable, "-m", "jointbench.bench.cli", "campaign", *TINY,
                             "--workers", workers, "--method", "plug.py:sleeps",
                             "--method-timeout", "300", "--out", "c.csv"], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        host = _wait_for(tmp_path / "host.pid")
        child = _wait_for(tmp_path / "child.pid")
        assert _alive(host) and _alive(child)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert _gone(host) and _gone(child)


def test_deadline_kills_the_method_and_what_it_forked(tmp_path):
    _plugin(tmp_path, FORKS)
    done = _campaign([*TINY, "--workers", "1", "--method", "plug.py:sleeps",
                      "--method-timeout", "3", "--out", "c.csv"], tmp_path)
    assert done.returncode == 0, done.stderr
    row = _rows(tmp_path / "c.csv")[0]
    assert row["sleeps.status"] == "failed"
    assert row["sleeps.reason"] == "timeout: no answer within 3 s (call stopped)"
    assert _gone(int((tmp_path / "host.pid").read_text()))
    assert _gone(int((tmp_path / "child.pid").read_text()))


# ---------------------------------------------------------------------------------------------
# Import and answer in the host, under the deadline


def test_a_module_that_sleeps_at_import_hits_the_deadline(tmp_path):
    _plugin(tmp_path, """
        import os, time
        from pathlib import Path
        Path("import.pid").write_text(str(os.getpid()))
        time.sleep(60)

        def f(log):
            return {"K": 1.0}
    """)
    done = _campaign([*TINY, "--workers", "1", "--method", "plug.py:f", "--method-timeout",
                      "2", "--out", "c.csv"], tmp_path)
    assert done.returncode == 2
    assert "--method plug.py:f: cannot import it: timeout: no answer within 2 s during the " \
           "import of plug.py:f (stopped)" in done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "c.csv").exists()
    assert _gone(int((tmp_path / "import.pid").read_text()))


@pytest.mark.parametrize("where", ["import", "call"])
def test_a_method_that_ends_its_process_is_a_failure_with_its_reason(tmp_path, where):
    _plugin(tmp_path, f"""
        import os
        if {where == "import"}:
            os._exit(0)

        def f(log):
            os._exit(0)
    """)
    done = _campaign([*TINY, "--workers", "1", "--method", "plug.py:f", "--out", "c.csv"],
                     tmp_path)
    if where == "import":   # found before any run: bad input
        assert done.returncode == 2 and not (tmp_path / "c.csv").exists()
        assert "its process died (exit code 0) during the import of plug.py:f" in done.stderr
    else:                   # a failed run, the built-in model's row intact
        assert done.returncode == 0, done.stderr
        (row,) = _rows(tmp_path / "c.csv")
        assert row["status"] == "ok" and row["f.status"] == "failed"
        assert row["f.reason"] == "its process died (exit code 0)"


def test_an_answer_is_never_unpickled_by_the_campaign(tmp_path):
    """A value whose unpickling would sleep or end the process: the host reads the numbers
    and sends them as JSON, so the campaign neither blocks nor exits."""
    _plugin(tmp_path, """
        import os, time

        class Sleepy(float):
            def __reduce__(self):
                return (time.sleep, (60,))

        class Exits(dict):
            def __reduce__(self):
                return (os._exit, (0,))

        def sleepy(log):
            return {"K": Sleepy(2.0e4)}

        def exits(log):
            return Exits(K=(2.0e4, 10.0))
    """)
    done = _campaign([*TINY, "--workers", "1", "--method", "plug.py:sleepy", "--method",
                      "plug.py:exits", "--method-timeout", "5", "--out", "c.csv", "--json"],
                     tmp_path)
    assert done.returncode == 0, done.stderr
    (row,) = _rows(tmp_path / "c.csv")
    assert row["sleepy.status"] == row["exits.status"] == "ok"
    assert row["sleepy.K"] == row["exits.K"] == "20000.0" and row["exits.K.sigma"] == "10.0"
    assert json.loads(done.stdout)["runs"] == 1


def test_prints_of_a_method_do_not_reach_campaign_json(tmp_path):
    _plugin(tmp_path, """
        print("hello from the import")

        def f(log):
            print("hello from the call")
            return {"K": 2.0e4}
    """)
    done = _campaign([*TINY, "--workers", "1", "--method", "plug.py:f", "--json",
                      "--out", "c.csv"], tmp_path)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)          # one JSON object, nothing else
    assert summary["runs"] == 1 and "hello" not in done.stdout
    assert "hello from the call" in done.stderr


def test_a_method_allocation_is_capped_by_the_memory_limit(tmp_path):
    _plugin(tmp_path, """
        def greedy(log):
            block = bytearray(8 * 2**30)       # 8 GiB
            return {"K": float(len(block))}
    """)
    done = _campaign([*TINY, "--workers", "1", "--method", "plug.py:greedy", "--out", "c.csv"],
                     tmp_path, env={"JOINTBENCH_MAX_MEMORY_MB": "500"})
    assert done.returncode == 0, done.stderr
    (row,) = _rows(tmp_path / "c.csv")
    assert row["greedy.status"] == "failed"
    assert row["greedy.reason"].startswith(
        "MemoryError: the method needed more than the 500 MB memory limit "
        "(JOINTBENCH_MAX_MEMORY_MB)")


# ---------------------------------------------------------------------------------------------
# The blind log


def test_blind_log_holds_what_a_measured_file_holds():
    log = jb.simulate("prototype", duration=5.0, seed=3, effect="backlash=0.002")
    seen = blind(log)
    assert set(seen.meta) <= BLIND_META
    for key in ("sample_rate_hz", "kp", "kv", "ki", "tau_max", "gravity", "joint",
                "motor_encoder_resolution_rad", "torque_noise_std"):
        assert seen.meta[key] == log.meta[key]
    for key in ("seed", "source", "chirp", "locked_config", "lock", "truth_K", "truth_effect"):
        assert key in log.meta and key not in seen.meta
    assert not seen.truth() and (seen.tau_m == log.tau_m).all()


def test_a_method_cannot_find_a_seed_to_simulate_again(tmp_path):
    _plugin(tmp_path, """
        import jointbench as jb

        def replays(log):
            seed = log.meta.get("seed")
            if seed is None:
                raise LookupError("no seed in " + ",".join(sorted(log.meta)))
            again = jb.simulate("prototype", duration=5.0, seed=int(seed))
            return {"K": float(again.meta["truth_K"])}
    """)
    done = _campaign([*TINY, "--workers", "1", "--method", "plug.py:replays", "--out",
                      "c.csv"], tmp_path)
    assert done.returncode == 0, done.stderr
    (row,) = _rows(tmp_path / "c.csv")
    assert row["replays.status"] == "failed"
    assert row["replays.reason"].startswith("LookupError: no seed in ")
    shown = row["replays.reason"].split("no seed in ")[1].split(",")
    assert set(shown) <= BLIND_META and {"sample_rate_hz", "joint"} <= set(shown)


# ---------------------------------------------------------------------------------------------
# Checked before any run


@pytest.mark.parametrize("value, message", [
    ("1e10", "1e10 s is over the longest deadline, 1e6 s"),
    ("0", "0 must be positive"),
    ("inf", "inf"),
])
def test_method_timeout_out_of_range_is_exit_2(tmp_path, value, message):
    done = _campaign([*TINY, "--workers", "1", "--method-timeout", value, "--out", "c.csv"],
                     tmp_path)
    assert done.returncode == 2 and message in done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "c.csv").exists()


def test_method_timeout_out_of_range_in_the_api(tmp_path):
    with pytest.raises(ValueError, match=r"method_timeout: .*\(0, 1e\+06\]"):
        jb.campaign(runs=1, duration=5, workers=1, id_models=["joint-motor"],
                    method_timeout=1e10, out=tmp_path / "c.csv")
    assert not (tmp_path / "c.csv").exists()


@pytest.mark.parametrize("target, message", [
    ("fifo", "is a FIFO (named pipe), not a regular file"),
    ("/dev/stdout", "is a symbolic link, not a regular file"),
    ("readonly.xml", "is read-only"),
    ("no_folder/gates.xml", "folder no_folder does not exist"),
])
def test_junit_target_refused_before_any_run(tmp_path, target, message, monkeypatch, capsys):
    # in this process (the command's own dispatcher, `main`): no run, so no process to
    # contain, and no interpreter to start for each target
    monkeypatch.chdir(tmp_path)
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "readonly.xml").write_text("")
    os.chmod(tmp_path / "readonly.xml", stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH)
    code = main(["campaign", *TINY, "--workers", "1", "--require", "failed==0", "--junit",
                 target, "--out", "c.csv"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"--junit {target}: {message}" in err and "Traceback" not in err
    assert not (tmp_path / "c.csv").exists()        # no run happened
    assert stat.S_ISFIFO(os.lstat(tmp_path / "fifo").st_mode)
    assert (tmp_path / "readonly.xml").read_text() == ""


# ---------------------------------------------------------------------------------------------
# Memory estimates count the workers


# The estimates are checked before any worker starts: in this process, through `main`.


def test_survey_multiplies_its_memory_estimate_by_the_workers(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("JOINTBENCH_MAX_MEMORY_MB", "1000")
    code = main(["survey", "--workers", "6", "--duration", "10", "--out", "sv"])
    # 6 axes of 10 s at the paper's rate: 200 MB + 6 x 3.4 MB here, 6 x (200 + 3.4) MB in the
    # workers (bench.cli.resources' figures), 1441 MB in all.
    assert code == 2
    assert ("--duration 10 s on 6 axes with 6 workers: about 1,441 MB of memory "
            "(221 MB here and 203 MB per worker), over the 1,000 MB limit"
            ) in capsys.readouterr().err
    assert not (tmp_path / "sv").exists()


def test_campaign_multiplies_its_memory_estimate_by_the_workers(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("JOINTBENCH_MAX_MEMORY_MB", "500")
    code = main(["campaign", *TINY, "--workers", "4", "--out", "c.csv"])
    assert code == 2 and "(4 workers), over the 500 MB limit" in capsys.readouterr().err
    assert not (tmp_path / "c.csv").exists()


def test_api_campaign_checks_its_memory_per_worker(tmp_path, monkeypatch):
    monkeypatch.setenv("JOINTBENCH_MAX_MEMORY_MB", "500")
    with pytest.raises(CampaignError, match=r"duration 5 s at 350.87 Hz: .* MB of memory "
                                            r"\(4 workers\), over the 500 MB limit"):
        jb.campaign(runs=4, duration=5, workers=4, out=tmp_path / "c.csv")
    with pytest.raises(CampaignError, match=r"duration 100000 s at 100000 Hz: 1e\+10 samples "
                                            r"need about .* MB of memory, over the 500 MB"):
        jb.campaign(runs=1, duration=1e5, rate=1e5, workers=1, out=tmp_path / "c.csv")
    assert not (tmp_path / "c.csv").exists()
