"""The bench half of every effect, by name, in the order of
jointbench.identification.effects.EFFECTS: the module `bench/effects/NAME.py` of each effect
the identification half discovers (tests/unit/test_effect_registry.py checks that no bench module
is left without one)."""

from __future__ import annotations

import importlib

from jointbench.bench.effects.base import BenchEffect
from jointbench.identification.effects import EFFECTS


def bench_half(name: str) -> BenchEffect:
    """The `EFFECT` of `bench/effects/{name}.py`; ImportError when the effect has none."""
    try:
        module = importlib.import_module(f"{__package__}.{name}")
    except ModuleNotFoundError as e:
        if e.name != f"{__package__}.{name}":
            raise
        raise ImportError(f"effect '{name}' has no bench half: bench/effects/{name}.py "
                          "(docs/effects.md)") from None
    effect = getattr(module, "EFFECT", None)
    if not isinstance(effect, BenchEffect) or effect.name != name:
        raise ImportError(f"{module.__file__}: EFFECT must be a BenchEffect named '{name}'")
    return effect


BENCH_EFFECTS: dict[str, BenchEffect] = {name: bench_half(name) for name in EFFECTS}
