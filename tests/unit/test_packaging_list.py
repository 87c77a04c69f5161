"""`pip install .` (not editable) installs only the packages pyproject.toml lists: every
folder of the package that holds an `__init__.py` must be among them, or the installed
command fails to import it."""

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_every_subpackage_is_listed_for_a_wheel():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {"jointbench"}
    for top in ("bench", "identification", "models"):
        for init in (ROOT / top).rglob("__init__.py"):
            if ".venv" in init.parts:
                continue
            found.add(".".join(("jointbench", *init.parent.relative_to(ROOT).parts)))
    assert found - listed == set(), f"missing from pyproject's packages: {sorted(found - listed)}"
