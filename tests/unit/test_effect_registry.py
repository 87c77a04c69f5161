"""The two halves of the effect registry (identification.effects, bench.effects) list the
same names, in docs/effects.md's order, and every entry is complete."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.effects import BENCH_EFFECTS, OPTIONS, HiddenEffect
from jointbench.bench.sim.axes import RIGID_AXIS_REFUSES
from jointbench.identification.discrepancy import RIGID_TESTS
from jointbench.identification.effects import EFFECTS, NONE
from jointbench.identification.parameters import PARAMETERS

# docs/effects.md, in its order.
CONTRACT = ("gravity", "link_coulomb", "torque_ripple", "backlash", "spring_damping",
            "torque_lag", "hardening", "offset", "asymmetric_friction")


def test_both_halves_list_the_contract_names_in_order():
    assert tuple(EFFECTS) == CONTRACT
    assert tuple(BENCH_EFFECTS) == CONTRACT
    assert tuple(OPTIONS) == CONTRACT
    assert NONE == "none" and NONE not in EFFECTS


@pytest.mark.parametrize("name", CONTRACT)
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


@pytest.mark.parametrize("name", CONTRACT)
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
