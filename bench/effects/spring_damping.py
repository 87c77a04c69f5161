"""`spring_damping` on the bench: damping D on the joint spring tendon."""

from __future__ import annotations

import math

import mujoco

from jointbench.bench.effects.base import BenchEffect, Uniform, nonnegative


def mjcf(spec: mujoco.MjSpec, axis: str, strength: float, options: dict, K: float) -> None:
    spec.tendon(f"{axis}_spring").damping[0] = strength


def extended(p: dict) -> tuple[float, dict]:
    return max(p["D"], 0.0), {}


def draw(u: Uniform, sign: float, tau_max: float, f1_hz: float, K: float):
    return u(0.2, 0.5) * K / (2 * math.pi * f1_hz), {}


EFFECT = BenchEffect("spring_damping", draw, check=nonnegative, mjcf=mjcf, extended=extended)
