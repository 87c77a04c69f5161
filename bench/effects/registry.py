"""The bench half of every effect, by name, in docs/effects.md's order (the order of
jointbench.identification.effects.EFFECTS; tests/test_effect_registry.py checks both)."""

from __future__ import annotations

from jointbench.bench.effects.asymmetric_friction import EFFECT as ASYMMETRIC_FRICTION
from jointbench.bench.effects.backlash import EFFECT as BACKLASH
from jointbench.bench.effects.gravity import EFFECT as GRAVITY
from jointbench.bench.effects.hardening import EFFECT as HARDENING
from jointbench.bench.effects.link_coulomb import EFFECT as LINK_COULOMB
from jointbench.bench.effects.offset import EFFECT as OFFSET
from jointbench.bench.effects.spring_damping import EFFECT as SPRING_DAMPING
from jointbench.bench.effects.torque_lag import EFFECT as TORQUE_LAG
from jointbench.bench.effects.torque_ripple import EFFECT as TORQUE_RIPPLE
from jointbench.bench.effects.base import BenchEffect

BENCH_EFFECTS: dict[str, BenchEffect] = {e.name: e for e in (
    GRAVITY, LINK_COULOMB, TORQUE_RIPPLE, BACKLASH, SPRING_DAMPING, TORQUE_LAG, HARDENING,
    OFFSET, ASYMMETRIC_FRICTION)}
