"""`gravity` on the bench: the experiment is centred the strength [rad] away from the link's
rest (bench.sim.axes), so gravity acts; diagnose's extended model carries MX, MY."""

from __future__ import annotations

from jointbench.bench.effects.base import BenchEffect, Uniform


def draw(u: Uniform, sign: float, tau_max: float, f1_hz: float, K: float):
    return sign * u(0.15, 0.45), {}


EFFECT = BenchEffect("gravity", draw)
