"""The effects are found by discovery (jointbench.identification.effects.discover): every name
has its two modules, its rows in docs/effects.md and its term in the independent simulator,
and the two halves of the registry list the same names in the one order."""

from __future__ import annotations

import importlib
import pkgutil
import re
from pathlib import Path

import numpy as np
import pytest

from jointbench.testing import hidden_effects as indep_effects
import jointbench.bench.effects as bench_effects
import jointbench.identification.effects as identification_effects
from jointbench.bench.effects import BENCH_EFFECTS, OPTIONS, HiddenEffect
from jointbench.bench.sim.axes import RIGID_AXIS_REFUSES
from jointbench.identification.discrepancy import RIGID_TESTS
from jointbench.identification.effects import EFFECTS, NONE
from jointbench.identification.parameters import PARAMETERS

NAMES = tuple(EFFECTS)     # the discovery's names, in its order
DOCS = Path(__file__).resolve().parents[2] / "docs" / "effects.md"


def _modules_with_effect(package) -> set[str]:
    return {m.name for m in pkgutil.iter_modules(package.__path__)
            if hasattr(importlib.import_module(f"{package.__name__}.{m.name}"), "EFFECT")}


def _docs_tables() -> list[list[str]]:
    """The first column of every table of docs/effects.md whose rows name effects."""
    tables: list[list[str]] = []
    previous = False
    for line in DOCS.read_text().splitlines():
        row = re.match(r"\| `([a-z_0-9]+)` \|", line)
        if row and not previous:
            tables.append([])
        if row:
            tables[-1].append(row.group(1))
        previous = bool(row)
    return tables


def test_the_registry_is_the_discovery():
    assert NAMES and NONE == "none" and NONE not in EFFECTS
    assert EFFECTS == identification_effects.discover()
    assert tuple(BENCH_EFFECTS) == NAMES
    assert tuple(OPTIONS) == NAMES
    orders = [importlib.import_module(f"jointbench.identification.effects.{n}").ORDER
              for n in NAMES]
    assert orders == sorted(orders) and len(set(orders)) == len(orders)


def test_every_effect_module_has_its_other_half():
    assert _modules_with_effect(identification_effects) == set(NAMES)
    assert _modules_with_effect(bench_effects) == set(NAMES)


def test_every_effect_has_its_rows_in_docs_in_the_registry_order():
    """docs/effects.md's tables of names (4.1 the names, 4.2 hiding them) list every effect,
    in the discovery's order (4.1 ends with `none`)."""
    tables = _docs_tables()
    assert len(tables) >= 2
    for names in tables:
        assert tuple(n for n in names if n != NONE) == NAMES


def test_every_effect_has_its_independent_simulator_term():
    assert set(indep_effects.TERMS) == set(NAMES)
    for name in NAMES:
        # the same options and defaults as the bench's, written again there
        assert indep_effects.TERMS[name].options == OPTIONS[name], name


@pytest.mark.parametrize("name", NAMES)
def test_identification_entry_is_complete(name):
    e = EFFECTS[name]
    assert e.name == name
    assert e.parameter and e.what
    assert isinstance(e.unit, str) and isinstance(e.unit_prismatic, str)
    assert e.block in (0, 1) and e.k >= 1
    assert callable(e.design) and callable(e.params)
    assert e.check is None or callable(e.check)
    # A searched parameter comes with its grid, and only then.
    assert bool(e.search) == (e.grid is not None)
    assert e.reference is None or callable(e.reference)
    # An effect whose size is measured on the link equation needs the link position.
    assert e.block == 0 or e.needs_link
    # A strength named like a physical parameter has that parameter's units.
    if e.parameter in PARAMETERS:
        p = PARAMETERS[e.parameter]
        assert (e.unit, e.unit_prismatic) == (p.unit, p.unit_prismatic)


@pytest.mark.parametrize("name", NAMES)
def test_bench_entry_is_complete(name):
    b = BENCH_EFFECTS[name]
    assert b.name == name
    assert callable(b.draw) and callable(b.check)
    # At most one way into diagnose's extended model; the numerics a loop effect is carried
    # in are read back by the bench loop.
    assert b.extended is None or b.extend is None
    assert b.extended is None or b.mjcf is not None
    assert bool(b.numeric) == (b.from_numeric is not None)
    assert not b.numeric or b.loop is not None
    # Every effect the bench hides acts somewhere: in the MJCF, in the loop, or (gravity) in
    # the experiment's set-up.
    assert b.mjcf is not None or b.loop is not None or name == "gravity"
    # The battery's draw is a valid hidden effect.
    rng = np.random.default_rng(1)
    strength, options = b.draw(rng.uniform, 1.0, 100.0, 5.0, 1e4)
    HiddenEffect(name, strength, options)


def test_rigid_fields_encode_both_former_lists():
    assert set(RIGID_TESTS) == {"offset", "asymmetric_friction", "torque_ripple", "torque_lag"}
    assert set(RIGID_AXIS_REFUSES) == {"backlash", "spring_damping", "hardening",
                                       "link_coulomb", "asymmetric_friction"}


def test_hidden_effect_validation_goes_through_the_registry():
    with pytest.raises(ValueError, match="must be >= 0"):
        HiddenEffect("backlash", -0.001)
    with pytest.raises(ValueError, match=r"must lie in \(-1, 1\)"):
        HiddenEffect("asymmetric_friction", 1.5)
    with pytest.raises(ValueError, match="has no option"):
        HiddenEffect("offset", 1.0, {"period": 1.0})
    assert HiddenEffect("hardening", 1.0).all_options == {"deflection": 0.003}
