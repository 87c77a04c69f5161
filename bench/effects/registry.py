"""The bench half of every effect, by name, in CONTRACT section 4's order (the order of
jointbench.identification.effects.EFFECTS; tests/test_effect_registry.py checks both)."""

from __future__ import annotations

from jointbench.bench.effects import (asymmetric_friction, backlash, gravity, hardening,
                                      link_coulomb, offset, spring_damping, torque_lag,
                                      torque_ripple)
from jointbench.bench.effects.base import BenchEffect

BENCH_EFFECTS: dict[str, BenchEffect] = {m.EFFECT.name: m.EFFECT for m in (
    gravity, link_coulomb, torque_ripple, backlash, spring_damping, torque_lag, hardening,
    offset, asymmetric_friction)}
