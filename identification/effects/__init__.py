"""The unmodelled effects (docs/effects.md), identification half: one registry, by discovery.

Every module of this package that defines `EFFECT` (an `Effect` named as the module) is an
effect; its module constant `ORDER` places it in `EFFECTS`, the one order of the effects:
docs/effects.md's tables, the candidates `diagnose` tests and reports, and the battery's
labels follow it. The bench half (jointbench.bench.effects) finds each effect's MuJoCo half
by the same name. Adding an effect is its module here, `bench/effects/NAME.py`, its term in
the independent simulator and its rows in docs/effects.md (tests/unit/test_effect_registry.py
checks the four).
"""

from __future__ import annotations

import importlib
import pkgutil

from jointbench.identification.effects.base import Effect, Rows, deadzone, sign0


def discover() -> dict[str, Effect]:
    """Every effect module of this package, by name, sorted by its `ORDER`. ImportError for
    an `EFFECT` named unlike its module, or without an `ORDER` shared with no other."""
    found: list[tuple[float, str, Effect]] = []
    for info in pkgutil.iter_modules(__path__):
        module = importlib.import_module(f"{__name__}.{info.name}")
        effect = getattr(module, "EFFECT", None)
        if effect is None:
            continue
        if not isinstance(effect, Effect) or effect.name != info.name:
            raise ImportError(f"{module.__file__}: EFFECT must be an Effect named "
                              f"'{info.name}'")
        order = getattr(module, "ORDER", None)
        if not isinstance(order, (int, float)):
            raise ImportError(f"{module.__file__}: the effect needs a number ORDER, its "
                              "place in the list of effects")
        found.append((order, info.name, effect))
    orders = [o for o, _, _ in found]
    twice = sorted({n for o, n, _ in found if orders.count(o) > 1})
    if twice:
        raise ImportError(f"effects {', '.join(twice)} share an ORDER")
    return {name: effect for _, name, effect in sorted(found)}


EFFECTS: dict[str, Effect] = discover()
NONE = "none"

__all__ = ["EFFECTS", "NONE", "Effect", "Rows", "deadzone", "discover", "sign0"]
