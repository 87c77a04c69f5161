"""`torque_ripple` on the bench: A sin(2 pi q_m / period + phase) added to the rotor torque in
the bench loop (no MuJoCo actuator bias depends on the motor angle that way); an extended
MJCF carries it as the custom numeric `{axis}_ripple` = (amplitude, period, phase)."""

from __future__ import annotations

import math

import mujoco

from jointbench.bench.effects.base import BenchEffect, Term, Uniform

NUMERIC = "ripple"
# period 0: one period per sixth of a motor turn, 2 pi / (6 N), or 0.02 rad without a gear.
OPTIONS = {"period": 0.0, "phase": 0.0}


def _term(amplitude: float, period: float, phase: float) -> Term:
    return lambda q_m, qd_m: amplitude * math.sin(2 * math.pi * q_m / period + phase)


def loop(strength: float, options: dict, gear_ratio: float | None, FVm: float,
         FSm: float) -> Term | None:
    if not strength:
        return None
    period = options["period"]
    if period <= 0:
        period = 2 * math.pi / (6 * gear_ratio) if gear_ratio else 0.02
    return _term(strength, period, options["phase"])


def from_numeric(values: list[float], axis: str) -> Term | None:
    if len(values) != 3 or not values[1] > 0:
        raise ValueError(f"numeric {axis}_{NUMERIC} must hold amplitude, period > 0, phase")
    return _term(*values) if values[0] else None


def extend(spec: mujoco.MjSpec, axis: str, p: dict, K: float) -> None:
    spec.add_numeric(name=f"{axis}_{NUMERIC}", data=[p["ripple_amplitude"],
                                                      p["ripple_period_rad"],
                                                      p["ripple_phase_rad"]])


def draw(u: Uniform, sign: float, tau_max: float, f1_hz: float, K: float):
    return u(0.015, 0.03) * tau_max, {}


EFFECT = BenchEffect("torque_ripple", draw, options=OPTIONS, extend=extend, loop=loop,
                     numeric=NUMERIC, from_numeric=from_numeric)
