"""Adding an effect touches only its two modules (docs/effects.md, the identification half's
docstring): a toy effect written into a copy of the package, with nothing else changed, is
listed by both registries and the battery, accepted by `jointbench simulate --effect`,
written into the log's truth and tested by `jointbench diagnose`."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# A quadratic drag c qm' |qm'| on the rotor [N m s^2/rad^2]: a motor-side effect unlike the
# registered ones.
IDENTIFICATION_HALF = '''"""`toy`: a quadratic drag c qm' |qm'| on the rotor."""

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows, column_value

ORDER = 1000


def design(rows: Rows, fixed: dict) -> Design:
    qmd = np.nan_to_num(rows.sig.qmd)
    return rows.extend(("toy_drag", qmd * np.abs(qmd), None))


EFFECT = Effect("toy", "toy_drag", "N m s^2/rad^2", "N s^2/m^2", "a quadratic drag",
                needs_link=False, rigid_axis=True, block=0, k=1, design=design,
                params=column_value("toy_drag", "toy_drag"))
'''
BENCH_HALF = '''"""`toy` on the bench: the rotor gets -c qm' |qm'| in the bench loop."""

from jointbench.bench.effects.base import BenchEffect, nonnegative


def loop(strength, options, gear_ratio, FVm, FSm):
    return (lambda q_m, qd_m: -strength * qd_m * abs(qd_m)) if strength else None


def draw(u, sign, tau_max, f1_hz, K):
    return u(1.0, 2.0), {}


EFFECT = BenchEffect("toy", draw, check=nonnegative, loop=loop)
'''
REGISTRIES = '''
import json, sys
import jointbench
from jointbench.bench.campaign.battery import BATTERY_EFFECTS
from jointbench.bench.effects import BENCH_EFFECTS, OPTIONS
from jointbench.identification.discrepancy import RIGID_TESTS
from jointbench.identification.effects import EFFECTS
print(json.dumps({"package": jointbench.__file__, "identification": list(EFFECTS),
                  "bench": list(BENCH_EFFECTS), "options": list(OPTIONS),
                  "battery": list(BATTERY_EFFECTS), "rigid": list(RIGID_TESTS)}))
'''


def _copy_package(to: Path) -> Path:
    """The package's folders (every top-level folder with an __init__.py) and its
    __init__.py, as `jointbench` under `to`."""
    pkg = to / "jointbench"
    pkg.mkdir()
    shutil.copy(ROOT / "__init__.py", pkg / "__init__.py")
    for folder in ROOT.iterdir():
        if folder.is_dir() and (folder / "__init__.py").exists() and folder.name != "tests":
            shutil.copytree(folder, pkg / folder.name,
                            ignore=shutil.ignore_patterns("__pycache__"))
    return pkg


def _run(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    return subprocess.run([sys.executable, *args], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=300)


def test_a_toy_effect_needs_only_its_two_modules(tmp_path):
    pkg = _copy_package(tmp_path)
    (pkg / "identification" / "effects" / "toy.py").write_text(IDENTIFICATION_HALF)
    (pkg / "bench" / "effects" / "toy.py").write_text(BENCH_HALF)

    out = _run(tmp_path, "-c", REGISTRIES)
    assert out.returncode == 0, out.stderr
    found = json.loads(out.stdout)
    assert Path(found["package"]).resolve().parent == pkg.resolve()
    for registry in ("identification", "bench", "options", "battery", "rigid"):
        assert found[registry][-1] == "toy", registry   # ORDER 1000: last

    cli = ("-m", "jointbench.bench.cli")
    bad = _run(tmp_path, *cli, "simulate", "--quiet", "--duration", "4", "--effect", "nope=1")
    assert bad.returncode == 2 and "toy" in bad.stderr   # the known effects it lists

    log = tmp_path / "toy.csv"
    sim = _run(tmp_path, *cli, "simulate", "--quiet", "--duration", "12", "--seed", "2",
               "--effect", "toy=4000", "--out", str(log))
    assert sim.returncode == 0, sim.stderr
    text = log.read_text()
    assert "truth_effect: toy" in text and "truth_toy_drag: 4000" in text

    diag = _run(tmp_path, *cli, "diagnose", str(log), "--json", "--no-forward", "--quiet",
                "--out", str(tmp_path / "diagnosis"))
    assert diag.returncode == 0, diag.stderr
    answer = json.loads(diag.stdout)
    toy = next(c for c in answer["candidates"] if c["effect"] == "toy")
    assert toy["testable"]
    # named, its strength within test_diagnose's 20 % of the hidden one
    assert answer["named_cause"] == "toy"
    assert abs(toy["parameters"]["toy_drag"] / 4000 - 1) < 0.2
