"""`offset` on the bench: the rotor receives tau - c while the log records tau (a current
sensor offset, or a constant load). diagnose's extended model holds it as a passive
constant-bias actuator."""

from __future__ import annotations

import mujoco

from jointbench.bench.effects.base import BenchEffect, Term, Uniform


def add_offset_load(spec: mujoco.MjSpec, name: str, joint: str, offset: float) -> None:
    """A passive actuator `{name}_offset` on `joint` with constant force -offset (gain 0,
    affine bias): a constant load the motor holds with tau_m = offset."""
    load = spec.add_actuator()
    load.name = f"{name}_offset"
    load.target = joint
    load.trntype = mujoco.mjtTrn.mjTRN_JOINT
    load.gaintype = mujoco.mjtGain.mjGAIN_FIXED
    load.gainprm[0] = 0.0
    load.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    load.biasprm[:3] = [-offset, 0.0, 0.0]


def loop(strength: float, options: dict, gear_ratio: float | None, FVm: float,
         FSm: float) -> Term | None:
    return (lambda q_m, qd_m: -strength) if strength else None


def extend(spec: mujoco.MjSpec, axis: str, p: dict, K: float) -> None:
    # On the motor of a two-mass axis; on the joint itself of a rigid one (K = 0).
    add_offset_load(spec, axis, f"{axis}_motor" if K else axis, p["offset"])


def draw(u: Uniform, sign: float, tau_max: float, f1_hz: float, K: float):
    return sign * u(0.01, 0.025) * tau_max, {}


EFFECT = BenchEffect("offset", draw, extend=extend, loop=loop)
