"""`pip install .`: the wheel carries the MJCF models; installed into a fresh virtual
environment it runs `jointbench --version` and a short `simulate`. Offline and fast: the
fresh environment sees this interpreter's installed dependencies through a .pth file, and
the wheel is installed with --no-deps, so jointbench itself comes from the wheel."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import venv
import zipfile
from pathlib import Path

import pytest

import jointbench

ROOT = Path(__file__).resolve().parents[2]


def _run(args, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(args, capture_output=True, text=True, check=False, **kw)


@pytest.mark.slow
def test_wheel_installs_and_runs(tmp_path):
    # a copy of the sources: setuptools' build/ folder stays out of the checkout; the caches
    # stay out of the copy (another test process may be writing into .hypothesis meanwhile)
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".git", ".venv", "build", "*.egg-info", ".pytest_cache", ".hypothesis", "__pycache__",
        "*_out"))
    wheels = tmp_path / "wheels"
    built = _run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps",
                  "-w", str(wheels), "-q"])
    assert built.returncode == 0, built.stderr
    wheel = next(wheels.glob("jointbench-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    for model in ("arm6.xml", "prototype_axis.xml"):
        assert f"jointbench/models/{model}" in names
    assert not any(n.startswith("jointbench/tests/") for n in names)

    env = tmp_path / "env"
    venv.create(env, with_pip=False)
    py = env / "bin" / "python"
    site = Path(_run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"]
                     ).stdout.strip())
    # the dependencies of this interpreter, after the fresh environment's own packages
    (site / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    clean = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    installed = _run([sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps",
                      "-q", str(wheel)], env=clean)
    if installed.returncode != 0:   # pip older than 22.3: no --python
        installed = _run([sys.executable, "-m", "pip", "install", "--no-deps", "-q",
                          "--target", str(site), str(wheel)], env=clean)
    assert installed.returncode == 0, installed.stderr
    where = _run([str(py), "-c", "import jointbench; print(jointbench.__file__)"], env=clean,
                 cwd=tmp_path)
    assert Path(where.stdout.strip()).resolve().is_relative_to(env.resolve()), where
    exe = env / "bin" / "jointbench"
    if not exe.exists():
        exe = None
    cmd = [str(exe)] if exe else [str(py), "-m", "jointbench.bench.cli"]
    version = _run([*cmd, "--version"], env=clean, cwd=tmp_path)
    assert version.stdout.strip() == f"jointbench {jointbench.__version__}", version
    sim = _run([*cmd, "simulate", "--duration", "5", "--quiet", "--out", "log.csv"],
               env=clean, cwd=tmp_path)
    assert sim.returncode == 0, sim.stderr
    assert "# source: jointbench virtual experiment" in (tmp_path / "log.csv").read_text()
