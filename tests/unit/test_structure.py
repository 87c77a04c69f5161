"""The house rules of the package, checked on the source: module-level imports form no cycle
and point one way, identification/ stays free of MuJoCo and bench. (A module's size is not
capped: a module holds one concept, whole.)"""

from __future__ import annotations

import ast
from pathlib import Path


ROOT = Path(__file__).resolve().parents[2]
# Folders of the package and their import names (pyproject.toml's package-dir).
PACKAGES = {"bench": "jointbench.bench", "identification": "jointbench.identification",
            "models": "jointbench.models", "tests/indep": "jointbench.testing"}
# Layers, lowest first: a module may import its own layer or a lower one.
LAYERS = (("jointbench.identification", "jointbench.models"),
          ("jointbench.bench.effects", "jointbench.bench.options", "jointbench.bench.output_files",
           "jointbench.bench.memory"),
          ("jointbench.bench.sim",),
          ("jointbench.bench.analysis", "jointbench.bench.campaign", "jointbench.bench.present",
           "jointbench.bench.demo", "jointbench.bench.results", "jointbench.bench.api_log",
           "jointbench.bench.api_identify", "jointbench.bench.api_diagnose",
           "jointbench.bench.api_campaign", "jointbench.bench.api_import_many",
           "jointbench.bench.api", "jointbench.bench.api_args"),
          ("jointbench.bench.cli",),
          ("jointbench.testing",))


def _modules() -> dict[str, Path]:
    out = {}
    for folder, package in PACKAGES.items():
        for path in (ROOT / folder).rglob("*.py"):
            parts = path.relative_to(ROOT / folder).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join((package,) + parts)] = path
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

