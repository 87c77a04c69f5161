"""Start-up (issue 18): a virtual experiment from the command line loads no scipy.

scipy.signal and scipy.optimize took 0.6 s of `jointbench simulate --duration 60`, whose
simulation takes about 0.3 s (README "Speed"); the wall-time ratio itself is measured by
benchmarks/run.py [5], never asserted here."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import jointbench

CODE = """
import sys
from jointbench.bench.cli import main
status = main(["simulate", "--duration", "4", "--quiet", "--out", sys.argv[1]])
print("status:", status)
print("scipy:", ",".join(sorted(m for m in sys.modules if m.split(".")[0] == "scipy")))
"""


def _env() -> dict[str, str]:
    env = dict(os.environ)
    root = str(Path(jointbench.__file__).parent.parent)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    return env


def test_simulate_imports_no_scipy(tmp_path):
    out = tmp_path / "s.csv"
    proc = subprocess.run([sys.executable, "-c", CODE, str(out)], env=_env(),
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "status: 0" in lines
    assert lines[-1] == "scipy: "
    assert out.read_text().startswith("# jointbench-log: 1")


def test_paper_constants_load_without_the_filter_modules():
    """identification.filter_choice holds the paper's constants for the bench; its filter
    chooser's modules (scipy) load only when a filter is chosen."""
    code = ("import sys\nfrom jointbench.identification.filter_choice import PAPER_RATE\n"
            "from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ\n"
            "assert SAMPLE_RATE_HZ == PAPER_RATE\n"
            "heavy = [m for m in ('scipy', 'jointbench.identification.filtering',\n"
            "         'jointbench.identification.first_mode') if m in sys.modules]\n"
            "from jointbench.identification.filter_choice import default_settings\n"
            "s = default_settings(PAPER_RATE)\n"
            "print('heavy:' + ','.join(heavy), s.wn, s.Nd)")
    proc = subprocess.run([sys.executable, "-c", code], env=_env(), capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["heavy:", "176.0", "26"]
