"""Effects written into an MjSpec: a hidden effect of a virtual experiment, and the named
effect of `diagnose`'s extended model."""

from __future__ import annotations

from typing import Sequence

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


# Parameters of docs/effects.md that are positions (joint side): rad on a revolute axis, m on
# a prismatic one. Phases stay in rad, times in s.
POSITION_PARAMETERS = ("backlash_rad", "ripple_period_rad", "deflection_rad")


def axis_key(key: str, prismatic: bool) -> str:
    """The name a report gives parameter `key` on this axis: `backlash_rad` reads
    `backlash_m` on a prismatic axis (CONTRACT section 1: m and N in place of rad and N m)."""
    return key[:-len("_rad")] + "_m" if prismatic and key in POSITION_PARAMETERS else key


def axis_keys(p: dict[str, float], prismatic: bool) -> dict[str, float]:
    """`p` with every key named as on this axis (`axis_key`)."""
    return {axis_key(k, prismatic): v for k, v in p.items()}


def _registry_keys(p: dict[str, float]) -> dict[str, float]:
    """`p` with the prismatic names of `axis_key` read back as the registry's."""
    back = {k[:-len("_rad")] + "_m": k for k in POSITION_PARAMETERS}
    return {back.get(k, k): v for k, v in p.items()}


def write_effects(spec: mujoco.MjSpec, axis: str,
                  effects: Sequence[tuple[str, dict[str, float]]], K: float) -> list[str]:
    """Add several named effects to one axis `spec`, in order, each with its own identified
    parameters (`write_extended`; the prismatic names of `axis_key` are accepted). Returns
    the effects written; ValueError for an effect named twice or a parameter out of its
    range."""
    done: list[str] = []
    for name, p in effects:
        if name in done:
            raise ValueError(f"effect '{name}' is named twice")
        write_extended(spec, axis, name, _registry_keys(dict(p)), K)
        done.append(name)
    return done
