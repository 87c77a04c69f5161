"""`torque_lag` on the bench: the motor actuator through MuJoCo's exact first-order filter of
time constant T [s]."""

from __future__ import annotations

import math

import mujoco

from jointbench.bench.effects.base import BenchEffect, Uniform, nonnegative


def mjcf(spec: mujoco.MjSpec, axis: str, strength: float, options: dict, K: float) -> None:
    if not strength > 0:   # no lag: MuJoCo's filter with a zero time constant diverges
        return
    act = spec.actuator(f"{axis}_motor")
    act.dyntype = mujoco.mjtDyn.mjDYN_FILTEREXACT
    act.dynprm[0] = strength
    act.actlimited = 0


def extend(spec: mujoco.MjSpec, axis: str, p: dict, K: float) -> None:
    """diagnose's `lag_s` is a continuous current loop (docs/effects.md 4.3); MuJoCo's filter
    applies its state at the start of each step, about half a step later: it is written half a
    step shorter, so that the extended model lags as the log did."""
    mjcf(spec, axis, max(p["lag_s"] - 0.5 * spec.option.timestep, 0.0), {}, K)


def draw(u: Uniform, sign: float, tau_max: float, f1_hz: float, K: float):
    return u(0.15, 0.3) / (2 * math.pi * f1_hz), {}


EFFECT = BenchEffect("torque_lag", draw, check=nonnegative, mjcf=mjcf, extend=extend)
