"""The README stays a newcomer's entry in step with the code: at most 300 lines, the install
and `make` lines, eq. (13) in its method section, every function it (and docs/method.md)
points to importable by that name, every relative link resolving, and no history markers."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
METHOD = ROOT / "docs" / "method.md"
MAX_LINES = 300
# The history markers the project keeps out of its prose (docs/design-notes.md and
# docs/validation.md excepted): dates, issue and session numbers, seed-and-case labels,
# before -> after figures.
HISTORY = re.compile(r"\b20[0-9]{2}-[01][0-9]-[0-3][0-9]\b|\b[Ii]ssue [0-9]+|\bsession [0-9]+"
                     r"|seed-[0-9]+ #[0-9]|[0-9.]+ ?%? ?-> ?[-+]?[0-9]")
NAME = re.compile(r"`(identification(?:\.[A-Za-z_][A-Za-z0-9_]*)+)`")
# The filter chain the method section must point to, step by step (eqs. 13, 18-22, 25).
CHAIN = ("identification.filtering.lowpass", "identification.filtering.central_difference",
         "identification.regressors.joint_motor", "identification.regressors.motor_only",
         "identification.filtering.decimate_parallel", "identification.estimate.block_weighted")


def text(path: Path) -> str:
    return path.read_text(encoding="utf-8")


def resolve(dotted: str) -> object:
    """`identification.a.b.c` -> the object, importing the longest module prefix of
    jointbench.identification and taking the rest as attributes."""
    parts = ("jointbench." + dotted).split(".")
    for cut in range(len(parts), 1, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for attr in parts[cut:]:
            obj = getattr(obj, attr)
        return obj
    raise ModuleNotFoundError(dotted)


def test_readme_is_short():
    n = len(text(README).splitlines())
    assert n <= MAX_LINES, f"README.md has {n} lines; at most {MAX_LINES}: move the rest to docs/"


def test_readme_shows_install_and_make():
    t = text(README)
    for line in ("pip install .", 'pip install ".[test]"', "make demo", "make test", "make check"):
        assert line in t, f"README.md does not show `{line}`"


def test_readme_sections_in_order():
    heads = [h for h in re.findall(r"^## (.+)$", text(README), flags=re.M)]
    order = ["Install", "Quick start", "The method", "Your own data", "Accuracy", "Speed",
             "Documentation"]
    assert [h for h in heads if h in order] == order, heads


def test_method_section_states_eq13_and_the_chain():
    t = text(README)
    method = t[t.index("## The method"):t.index("## Your own data")]
    assert "eq. (13)" in method
    # the stacked model itself, not only its name
    assert "( Jm  FVm  FSm  K  JL  MX  MY  FV  FS )" in method
    named = set(NAME.findall(method))
    missing = [c for c in CHAIN if c not in named]
    assert not missing, f"the method section does not point to {missing}"


@pytest.mark.parametrize("path", [README, METHOD], ids=lambda p: p.name)
def test_named_functions_exist(path):
    names = sorted(set(NAME.findall(text(path))))
    assert len(names) >= 8, f"{path.name} names only {names}"
    for dotted in names:
        try:
            resolve(dotted)
        except (ModuleNotFoundError, AttributeError) as e:
            pytest.fail(f"{path.name} names `{dotted}`, which does not exist ({e})")
    for dotted in CHAIN:
        assert callable(resolve(dotted))


def test_readme_links_resolve():
    for target in re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text(README)):
        if "://" in target:
            continue
        assert (ROOT / target).exists(), f"README.md links to {target}, which does not exist"


@pytest.mark.parametrize("path", [README, METHOD], ids=lambda p: p.name)
def test_no_history_markers(path):
    hits = [(i + 1, m.group(0)) for i, line in enumerate(text(path).splitlines())
            for m in [HISTORY.search(line)] if m and not line.lstrip().startswith("def ")]
    assert not hits, f"{path.name}: history markers (dates, issues, before -> after): {hits}"
