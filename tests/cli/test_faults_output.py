"""Issue 16, outputs and closed loops: no file that is not ours touched (device nodes, FIFOs,
folders, users' files), folders written all or nothing, the umask respected, nothing left in
the working directory, the target checked before any computation; and every closed-loop
replay (simulate --replay, diagnose's forward view, identify --refine and --debias) stopped
with a reason when it diverges."""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import signal
import stat
from pathlib import Path

import pytest

import jointbench.bench.campaign.run  # noqa: F401 - bound to run_experiment before any patch
from jointbench.bench.cli import main
from jointbench.bench.cli.common import Terminated
from jointbench.bench.output_files import MANIFEST, OutputError, OutputFolder, is_ours
from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.log import format_log, write_log


def run(args: list[str]) -> tuple[int, str, str]:
    """main(args) in-process: (status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in args])
        except SystemExit as stop:
            rc = stop.code
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def logs(tmp_path_factory, bench_log) -> dict[str, Path]:
    """A 10 s prototype log, the same with the velocity gain's sign flipped (an unstable
    loop), one with kv = 1e12 (MuJoCo warns), and a 20 s log with backlash hidden."""
    folder = tmp_path_factory.mktemp("logs")
    log = run_experiment("prototype", duration=10.0, seed=3).log
    paths = {"ok": folder / "ok.csv", "neg": folder / "neg.csv", "huge": folder / "huge.csv"}
    write_log(log, paths["ok"])
    text = format_log(log)
    paths["neg"].write_text(text.replace(f"# kv: {log.meta['kv']}", f"# kv: -{log.meta['kv']}"))
    paths["huge"].write_text(text.replace(f"# kv: {log.meta['kv']}", "# kv: 1e12")
                             .replace(f"# tau_max: {log.meta['tau_max']}", "# tau_max: 1e15"))
    from jointbench.bench.effects import HiddenEffect
    paths["backlash"] = folder / "backlash.csv"
    write_log(bench_log("prototype", duration=20.0, seed=1, effect=HiddenEffect("backlash", 0.002)),
              paths["backlash"])
    return paths


def _digest(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


# --- 1. Targets that are not regular files, and files that are not ours --------------------

def _make(kind: str, path: Path) -> None:
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "folder":
        path.mkdir()
    elif kind == "symlink":
        (path.parent / "elsewhere.txt").write_text("the user's")
        path.symlink_to(path.parent / "elsewhere.txt")
    else:  # a user's own file
        path.write_text("the user's own notes\n")


COMMANDS = {  # command line writing to TARGET (a file); LOG is the 10 s log
    "simulate --out": ["simulate", "--duration", "5", "--out", "TARGET"],
    "replay --out": ["simulate", "--replay", "LOG", "--out", "TARGET"],
    "replay --plot": ["simulate", "--replay", "LOG", "--plot", "TARGET"],
    "replay --save-model": ["simulate", "--replay", "LOG", "--save-model", "TARGET"],
    "campaign --out": ["campaign", "--runs", "1", "--workers", "1", "--duration", "5",
                       "--out", "TARGET"],
}
SUFFIX = {"replay --plot": ".png", "replay --save-model": ".xml"}


@pytest.mark.parametrize("kind", ["fifo", "folder", "symlink", "user file"])
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_targets_not_ours_are_refused_before_computing(tmp_path, logs, monkeypatch, kind,
                                                      command):
    """Every command refuses a FIFO, a folder, a symbolic link or a user's file as its output
    (status 2, the target untouched), before the experiment or the replay runs."""
    if command == "campaign --out" and kind == "folder":
        pytest.skip("a folder --out of campaign is a table path: covered by the FIFO case")
    target = tmp_path / ("target" + SUFFIX.get(command, ".csv"))
    _make(kind, target)
    before = os.lstat(target)
    import jointbench.bench.present.replay as replay_mod
    import jointbench.bench.sim.experiment as experiment
    for module, name in ((experiment, "run_experiment"), (replay_mod, "replay_log_file")):
        monkeypatch.setattr(module, name, lambda *a, **k: pytest.fail("computed first"))
    args = [logs["ok"] if a == "LOG" else target if a == "TARGET" else a
            for a in COMMANDS[command]]
    rc, out, err = run(args)
    assert rc == 2, err
    assert "error:" in err and str(target.name) in err
    after = os.lstat(target)
    assert (after.st_mode, after.st_ino, after.st_size) == \
        (before.st_mode, before.st_ino, before.st_size)


@pytest.mark.parametrize("where", ["missing folder", "device node"])
def test_unwritable_targets_exit_2(tmp_path, where):
    """A missing folder, and a character device like /dev/null (made here: mknod c 1 3, as
    root), are refused; the device stays a device."""
    target = tmp_path / "no" / "x.csv"
    if where == "device node":
        target = tmp_path / "fake"
        try:
            os.mknod(target, stat.S_IFCHR | 0o600, os.makedev(1, 3))
        except PermissionError:
            pytest.skip("mknod needs root")
    rc, out, err = run(["simulate", "--duration", "5", "--out", target])
    assert rc == 2 and ("does not exist" in err or "character device" in err), err
    assert where != "device node" or target.is_char_device()


def test_files_written_are_ours_and_ours_only_while_unchanged(tmp_path):
    path = tmp_path / "fig.png"
    from jointbench.bench.output_files import check_file, record
    path.write_bytes(b"\x89PNG not really")
    with pytest.raises(OutputError, match="did not write"):
        check_file(path)
    record(path)
    assert is_ours(path)
    check_file(path)  # ours now: may be replaced
    path.write_bytes(b"\x89PNG edited by the user")
    assert not is_ours(path)


# --- 1. Folders: all or nothing, our stale files removed, users' files kept ----------------

@pytest.mark.slow
def test_diagnose_folder_guard_stale_files_and_interruption(tmp_path, logs, monkeypatch):
    out = tmp_path / "report"
    out.mkdir()
    (out / "report.md").write_text("my own report\n")
    (out / "notes.txt").write_text("mine too\n")
    rc, _, err = run(["diagnose", logs["backlash"], "--out", out, "--quiet", "--no-forward"])
    assert rc == 2 and "report.md" in err and "did not write" in err
    (out / "report.md").unlink()
    rc, _, err = run(["diagnose", logs["backlash"], "--out", out, "--quiet", "--no-forward"])
    assert rc == 0, err
    assert (out / "extended.xml").exists() and (out / MANIFEST).exists()
    # A log without a named cause: our extended.xml of the first run goes, the user's stays.
    rc, stdout, err = run(["diagnose", logs["ok"], "--out", out, "--quiet", "--no-forward"])
    assert rc == 0 and "named cause: none" in stdout, err
    assert not (out / "extended.xml").exists() and (out / "notes.txt").read_text() == "mine too\n"
    snapshot = _digest(out)
    # Interrupted while writing (SIGTERM turned into Terminated): the folder stays as it was.
    import jointbench.bench.analysis.diagnose.report as report

    def interrupted(*a, **k):
        raise Terminated(signal.SIGTERM)
    monkeypatch.setattr(report, "plot_inverse", interrupted)
    rc, _, err = run(["diagnose", logs["backlash"], "--out", out, "--quiet", "--no-forward"])
    assert rc == 128 + signal.SIGTERM, err
    assert _digest(out) == snapshot
    fresh = tmp_path / "fresh"
    rc, _, _ = run(["diagnose", logs["backlash"], "--out", fresh, "--quiet", "--no-forward"])
    assert rc == 128 + signal.SIGTERM and not fresh.exists()


def test_output_folder_refuses_what_is_not_a_folder(tmp_path):
    os.mkfifo(tmp_path / "pipe")
    for name in ("pipe",):
        with pytest.raises(OutputError, match="not a folder"):
            OutputFolder(tmp_path / name, ["a.txt"])
    with pytest.raises(OutputError, match="does not exist"):
        OutputFolder(tmp_path / "a" / "b", ["a.txt"])


# --- 1. Permissions and the working directory -----------------------------------------------

@pytest.mark.parametrize("mask", [0o022, 0o027, 0o077])
def test_files_get_the_mode_the_umask_allows(tmp_path, mask):
    old = os.umask(mask)
    try:
        rc, _, err = run(["simulate", "--duration", "5", "--out", tmp_path / "a.csv"])
    finally:
        os.umask(old)
    assert rc == 0, err
    assert stat.S_IMODE(os.stat(tmp_path / "a.csv").st_mode) == 0o666 & ~mask


# --- 2. Every closed loop guarded -----------------------------------------------------------

@pytest.mark.parametrize("args, status, says", [
    (["simulate", "--replay", "NEG"], 2, "diverged"),
    (["simulate", "--replay", "OK", "--tau0", "1e300"], 2, "tau0"),
    (["simulate", "--replay", "HUGE"], 2, "diverged"),
    (["identify", "NEG", "--refine"], 2, "diverged"),
    (["identify", "NEG", "--debias", "2"], 2, "diverged"),
    (["diagnose", "NEG", "--quiet"], 0, "forward view: not replayed: replay of"),
])
def test_diverging_replays_are_stopped_with_the_reason(tmp_path, logs, monkeypatch, args,
                                                       status, says):
    """No replay runs to 87 rad RMS and exits 0: the command fails naming the divergence,
    or (diagnose) says the forward view was not replayed and why; MuJoCo's warnings never
    reach MUJOCO_LOG.TXT in the working directory."""
    monkeypatch.chdir(tmp_path)
    names = {"NEG": logs["neg"], "OK": logs["ok"], "HUGE": logs["huge"]}
    rc, out, err = run([names.get(a, a) for a in args])
    assert rc == status, err
    assert says in (out + err)
    assert "Traceback" not in err and "internal error" not in err
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
    assert sorted(os.listdir(tmp_path)) == []


def test_mujoco_warnings_never_reach_the_working_directory(tmp_path, monkeypatch):
    """MuJoCo's default handler appends every warning to MUJOCO_LOG.TXT in the working
    directory; bench.sim.loop keeps the texts instead."""
    import math

    import mujoco

    from jointbench.bench.sim import loop
    from jointbench.models import load_model
    monkeypatch.chdir(tmp_path)
    # The handler of this process may be a run's own collector left by threads (Dask) that
    # swapped it concurrently (bench.sim.experiment); any handler keeps MuJoCo's default off.
    import subprocess
    import sys
    fresh = subprocess.run([sys.executable, "-c", "import mujoco; from jointbench.bench.sim "
                            "import loop; print(mujoco.get_mju_user_warning() is "
                            "loop._keep_warning)"], capture_output=True, text=True)
    assert fresh.stdout.strip() == "True", fresh.stderr  # installed on import
    monkeypatch.setattr(loop, "MUJOCO_WARNING_TEXTS", [])
    mujoco.set_mju_user_warning(loop._keep_warning)
    model, axes, _ = load_model("prototype")
    data = mujoco.MjData(model)
    data.ctrl[axes[0].actuator] = math.nan
    mujoco.mj_step(model, data)
    assert loop.first_warning(data)[0] == "mjWARN_BADCTRL"
    assert "CTRL" in loop.MUJOCO_WARNING_TEXTS[-1]
    assert os.listdir(tmp_path) == []


def test_output_folder_touches_only_its_own_files(tmp_path):
    """A user's empty folder and files stay; an empty file of a name we write is replaced;
    an interrupted write puts our previous files back; a later run removes the ones it does
    not write again."""
    out = tmp_path / "out"
    (out / "mine").mkdir(parents=True)
    (out / "notes.txt").write_text("user")
    (out / "a.txt").write_text("")
    folder = OutputFolder(out, ["a.txt", "b.txt", "sub/*"])
    with folder.writing() as p:
        (p / "a.txt").write_text("A1")
        (p / "sub").mkdir()
        (p / "sub" / "c.txt").write_text("C1")
    from jointbench.bench.output_files import read_manifest
    assert is_ours(out / "a.txt") and is_ours(out / "sub" / "c.txt", read_manifest(out),
                                              "sub/c.txt")
    snapshot = _digest(out)
    with pytest.raises(KeyboardInterrupt):
        with OutputFolder(out, ["a.txt", "b.txt", "sub/*"]).writing() as p:
            (p / "a.txt").write_text("A2")
            (p / "b.txt").write_text("B2")
            raise KeyboardInterrupt
    assert _digest(out) == snapshot
    with OutputFolder(out, ["a.txt", "b.txt", "sub/*"]).writing() as p:
        (p / "b.txt").write_text("B3")
    assert sorted(os.listdir(out)) == [MANIFEST, "b.txt", "mine", "notes.txt"]
    assert (out / "mine").is_dir() and (out / "notes.txt").read_text() == "user"
