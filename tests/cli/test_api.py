"""The public Python API (`import jointbench as jb`) and `jointbench --version`.

The snippet runs in a subprocess from a folder holding its own `models/` package, with that
folder as the working directory: the user's `models` must not shadow `jointbench.models`.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import jointbench

SNIPPET = textwrap.dedent("""
    import json, sys
    import jointbench as jb
    assert "numpy" not in sys.modules, "import jointbench must stay light"
    log = jb.simulate("prototype", seed=1, duration=20)
    assert isinstance(log, jb.Log)
    fit = jb.identify(log)
    table = fit.table()
    doc = fit.to_json()
    text = json.dumps(doc, allow_nan=False)
    import matplotlib
    matplotlib.use("Agg")
    fig = fit.plot()
    d = jb.diagnose(log, forward=False)
    d = d.write("out/")
    jb.write_log(log, "copy.csv")
    again = jb.read_log("copy.csv")
    print(json.dumps({"K": fit.parameters["K"].value, "K_truth": log.truth()["K"],
                      "json": json.loads(text), "table": table, "axes": len(fig.axes),
                      "named_cause": d.named_cause, "files": list(d.files),
                      "samples": [len(log), len(again)], "version": jb.__version__,
                      "duration": float(log.t[-1])}))
""")


def _env() -> dict[str, str]:
    """The environment of this test run, with `jointbench` importable from any folder."""
    env = dict(os.environ)
    root = str(Path(jointbench.__file__).parent.parent)  # the folder holding jointbench/
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    return env


@pytest.mark.slow
def test_api_snippet_from_a_folder_with_its_own_models_package(tmp_path):
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "__init__.py").write_text("")
    proc = subprocess.run([sys.executable, "-c", SNIPPET], cwd=tmp_path, env=_env(),
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert abs(out["K"] - out["K_truth"]) <= 0.01 * out["K_truth"]
    assert out["json"]["model"] == "joint-motor"
    assert set(out["json"]["physical"]) >= {"K", "Jm", "JL"}
    assert "Parameter" in out["table"] and "direct validation" in out["table"]
    assert out["axes"] == 2
    assert out["samples"][0] == out["samples"][1] > 0
    assert abs(out["duration"] - 20) < 0.01
    assert out["version"] == jointbench.__version__
    assert (tmp_path / "out" / "diagnosis.json").exists()
    assert str(Path("out") / "report.md") in out["files"]


def test_version_flag_prints_the_version():
    proc = subprocess.run([sys.executable, "-m", "jointbench.bench.cli", "--version"],
                          env=_env(), capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0
    assert proc.stdout == f"jointbench {jointbench.__version__}\n"


def test_help_loads_no_command_module():
    code = ("import sys\nfrom jointbench.bench.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "heavy = [m for m in ('numpy', 'scipy', 'mujoco', 'matplotlib') if m in sys.modules]\n"
            "print('heavy:' + ','.join(heavy))")
    proc = subprocess.run([sys.executable, "-c", code], env=_env(), capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[-1] == "heavy:"


def test_simulate_hides_several_effects():
    """Issue 15 item 2 in the API as on the command line: "A=S1,B=S2" hides both; a name
    given twice is a ValueError naming it."""
    import jointbench as jb
    log = jb.simulate(duration=6.0, seed=1, effect="offset=5,backlash=0.001")
    assert log.meta["truth_effect"] == "offset,backlash"
    assert float(log.meta["truth_offset"]) == 5
    assert float(log.meta["truth_backlash_rad"]) == 0.001
    with pytest.raises(ValueError, match="'offset' is given twice"):
        jb.simulate(duration=6.0, seed=1, effect="offset=5,offset=3")
