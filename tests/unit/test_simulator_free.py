"""identification/ runs on any robot's log: it reads none of the simulator's metadata (the
physics steps a sample, the integrator), so the bench's logs take the path everyone's take.
The log schema alone names those keys (it validates them)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SIMULATOR = re.compile(r"PLANT_STEPS_KEY|PLANT_INTEGRATOR_KEY|[\"']substeps[\"']|"
                       r"[\"']integrator[\"']|RK4|mjINT_")


def test_identification_reads_no_simulator_metadata():
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
             for path in sorted((ROOT / "identification").rglob("*.py"))
             if path.name != "log/schema.py"
             for n, line in enumerate(path.read_text().splitlines(), start=1)
             if SIMULATOR.search(line)]
    assert not found, "\n".join(found)


def test_the_schema_still_names_the_keys():
    # the check above is not vacuous: the keys exist and are spelled as it searches them
    text = (ROOT / "identification" / "log/schema.py").read_text()
    assert SIMULATOR.search(text)
