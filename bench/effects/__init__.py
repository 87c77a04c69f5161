"""Hidden effects for virtual experiments (docs/effects.md), bench half: one registry.

`BENCH_EFFECTS` maps each name of jointbench.identification.effects.EFFECTS to its
`BenchEffect` (one module per effect). `HiddenEffect` is what a user asks for
(`--effect backlash=0.002`); effects MuJoCo expresses are written into the MJCF
(`apply_to_spec`), the others act in the bench loop (`LoopEffects`).
"""

from __future__ import annotations

from jointbench.bench.effects.base import BenchEffect
from jointbench.bench.effects.hidden import OPTIONS, HiddenEffect, parse_effect
from jointbench.bench.effects.loop import LoopEffects, loop_effects_from_model
from jointbench.bench.effects.mjcf import (apply_to_spec, axis_key, axis_keys, write_effects,
                                           write_extended)
from jointbench.bench.effects.registry import BENCH_EFFECTS

__all__ = ["BENCH_EFFECTS", "OPTIONS", "BenchEffect", "HiddenEffect", "LoopEffects",
           "apply_to_spec", "axis_key", "axis_keys", "loop_effects_from_model", "parse_effect",
           "write_effects", "write_extended"]
