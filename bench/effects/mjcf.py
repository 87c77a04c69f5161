"""Effects written into an MjSpec: a hidden effect of a virtual experiment, and the named
effect of `diagnose`'s extended model."""

from __future__ import annotations

import mujoco

from jointbench.bench.effects.hidden import HiddenEffect
from jointbench.bench.effects.registry import BENCH_EFFECTS


def apply_to_spec(spec: mujoco.MjSpec, axis: str, effect: HiddenEffect, K: float) -> None:
    """Write the effects MuJoCo expresses into the spec of the experiment model (the others
    act in the bench loop or the experiment's set-up). K: the joint stiffness."""
    write = BENCH_EFFECTS[effect.name].mjcf
    if write is not None:
        write(spec, axis, effect.strength, effect.all_options, K)


def write_extended(spec: mujoco.MjSpec, axis: str, effect: str, p: dict[str, float],
                   K: float) -> None:
    """Add `effect` to the nominal axis `spec` with diagnose's identified parameters `p`
    (K = 0 for a rigid axis). Effects whose parameters the axis builder takes (gravity's MX,
    MY; link_coulomb's FS) write nothing. ValueError for parameters out of the effect's range."""
    b = BENCH_EFFECTS[effect]
    if b.extended is not None:
        apply_to_spec(spec, axis, HiddenEffect(effect, *b.extended(p)), K)
    elif b.extend is not None:
        b.extend(spec, axis, p, K)
