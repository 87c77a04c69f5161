"""`link_coulomb` on the bench: the link joint's frictionloss; diagnose's extended model
carries FS in the two-mass axis."""

from __future__ import annotations

import mujoco

from jointbench.bench.effects.base import BenchEffect, Uniform, nonnegative


def mjcf(spec: mujoco.MjSpec, axis: str, strength: float, options: dict, K: float) -> None:
    spec.joint(axis).frictionloss = strength


def draw(u: Uniform, sign: float, tau_max: float, f1_hz: float, K: float):
    return u(0.015, 0.03) * tau_max, {}


EFFECT = BenchEffect("link_coulomb", draw, check=nonnegative, mjcf=mjcf)
