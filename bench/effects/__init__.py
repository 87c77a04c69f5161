"""Hidden effects for virtual experiments (docs/effects.md), bench half: one registry.

`BENCH_EFFECTS` maps each name of jointbench.identification.effects.EFFECTS to its
`BenchEffect` (one module per effect). `HiddenEffect` is what a user asks for
(`--effect backlash=0.002`, several: `parse_effects`); effects MuJoCo expresses are written into the MJCF
(`apply_to_spec`), the others act in the bench loop (`LoopEffects`).
"""

from __future__ import annotations

from jointbench.bench.effects.base import BenchEffect
from jointbench.bench.effects.hidden import (OPTIONS, HiddenEffect, as_effects, effects_meta,
                                             parse_effect, parse_effects, strength_of)
from jointbench.bench.effects.loop import LoopEffects, loop_effects_from_model
from jointbench.bench.effects.mjcf import (apply_to_spec, axis_key, axis_keys, write_effects,
                                           write_extended)
from jointbench.bench.effects.registry import BENCH_EFFECTS

__all__ = ["BENCH_EFFECTS", "OPTIONS", "BenchEffect", "HiddenEffect", "LoopEffects",
           "apply_to_spec", "as_effects", "axis_key", "axis_keys", "effects_meta",
           "loop_effects_from_model", "parse_effect", "parse_effects", "strength_of",
           "write_effects", "write_extended"]
