"""`backlash` on the bench: a dead band of half-width b in the joint spring tendon."""

from __future__ import annotations

import mujoco

from jointbench.bench.effects.base import BenchEffect, Uniform, nonnegative


def mjcf(spec: mujoco.MjSpec, axis: str, strength: float, options: dict, K: float) -> None:
    # Dead band: the spring acts only beyond +-b (MuJoCo's two-valued springlength).
    spec.tendon(f"{axis}_spring").springlength = [-strength, strength]


def extended(p: dict) -> tuple[float, dict]:
    return max(p["backlash_rad"], 0.0), {}


def draw(u: Uniform, sign: float, tau_max: float, f1_hz: float, K: float):
    return u(0.001, 0.003), {}


EFFECT = BenchEffect("backlash", draw, check=nonnegative, mjcf=mjcf, extended=extended)
