"""identification/ runs on any robot's log: it reads none of the simulator's metadata (the
physics steps a sample, the integrator), so the bench's logs take the path everyone's take.
No file of the package, code or text, names them: the bench's `plant_keys` does."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "identification"
# the keys as the log carries them (`grep -rnE "substeps|integrator" identification/`), their
# constants and MuJoCo's integrator names
SIMULATOR = re.compile(r"substeps|integrator|PLANT_STEPS_KEY|PLANT_INTEGRATOR_KEY|RK4|mjINT_")


def _lines(path: Path) -> list[str]:
    try:
        return path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError:   # a binary file holds no code that could branch on a key
        return []


def test_identification_reads_no_simulator_metadata():
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
             for path in sorted(PACKAGE.rglob("*"))
             if path.is_file() and "__pycache__" not in path.parts
             for n, line in enumerate(_lines(path), start=1)
             if SIMULATOR.search(line)]
    assert not found, "\n".join(found)


def test_the_bench_names_the_keys():
    # the check above is not vacuous: the keys exist and are spelled as it searches them
    from jointbench.bench.sim import plant_keys
    from jointbench.bench.sim.plant_keys import PLANT_INTEGRATOR_KEY, PLANT_STEPS_KEY

    assert SIMULATOR.search(Path(plant_keys.__file__).read_text())
    assert SIMULATOR.fullmatch(PLANT_STEPS_KEY) and SIMULATOR.fullmatch(PLANT_INTEGRATOR_KEY)
