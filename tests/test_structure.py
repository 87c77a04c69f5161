"""The house rules of the package (issue 13), checked on the source: module-level imports form
no cycle and point one way, identification/ stays free of MuJoCo and bench, no module is
longer than about 400 lines."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("bench", "identification", "models")
MAX_LINES = 400
# Layers, lowest first: a module may import its own layer or a lower one.
LAYERS = (("jointbench.identification", "jointbench.models"),
          ("jointbench.bench.effects", "jointbench.bench.options", "jointbench.bench.output"),
          ("jointbench.bench.sim",),
          ("jointbench.bench.analysis", "jointbench.bench.campaign", "jointbench.bench.present",
           "jointbench.bench.demo", "jointbench.bench.results", "jointbench.bench.api_log",
           "jointbench.bench.api_identify", "jointbench.bench.api_diagnose",
           "jointbench.bench.api_campaign", "jointbench.bench.api_import_many",
           "jointbench.bench.api"),
          ("jointbench.bench.cli",))


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(("jointbench",) + parts)] = path
    return out


def _top_imports(path: Path) -> set[str]:
    """Modules imported at module level (not inside functions)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names = set()
    for node in tree.body:
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names |= {f"{node.module}.{a.name}" for a in node.names}
    return names


def _layer(module: str) -> int:
    for i, prefixes in enumerate(LAYERS):
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return i
    raise AssertionError(f"{module} belongs to no layer of test_structure.LAYERS")


MODULES = _modules()
GRAPH = {m: {n for n in _top_imports(p) if n in MODULES and n != m} for m, p in MODULES.items()}


def test_every_module_is_in_a_layer_and_imports_point_down():
    wrong = [f"{m} -> {n}" for m, deps in GRAPH.items() for n in deps
             if m != "jointbench" and _layer(n) > _layer(m)]
    assert not wrong, "imports that point up a layer: " + ", ".join(sorted(wrong))


def test_no_import_cycle():
    state: dict[str, int] = {}

    def visit(m: str, stack: list[str]) -> None:
        state[m] = 1
        for n in GRAPH[m]:
            # a package's __init__ re-exporting its submodules is not a cycle with them
            if n.startswith(m + "."):
                continue
            if state.get(n) == 1:
                raise AssertionError("import cycle: " + " -> ".join(stack[stack.index(n):] + [n]))
            if n not in state:
                visit(n, stack + [n])
        state[m] = 2

    for m in GRAPH:
        if m not in state:
            visit(m, [m])


def test_identification_imports_no_mujoco_and_no_bench():
    for m, path in MODULES.items():
        if m.startswith("jointbench.identification"):
            bad = {n for n in _top_imports(path)
                   if n.split(".")[0] == "mujoco" or n.startswith("jointbench.bench")}
            assert not bad, f"{path}: {bad}"


@pytest.mark.parametrize("module", sorted(MODULES))
def test_module_length(module):
    n = len(MODULES[module].read_text(encoding="utf-8").splitlines())
    assert n <= MAX_LINES, f"{MODULES[module]} has {n} lines (at most {MAX_LINES})"
