"""Effects acting in the bench loop: an extra torque on the rotor from the state at the tick
(the effects' `loop` terms: offset, torque ripple, asymmetric friction), summed over the
hidden effects."""

from __future__ import annotations

import mujoco

from typing import Sequence

from jointbench.bench.effects.base import Term
from jointbench.bench.effects.hidden import HiddenEffect, as_effects
from jointbench.bench.effects.registry import BENCH_EFFECTS


class LoopEffects:
    """The bench-loop torque of the hidden effects (one, several or None; their registry
    `loop` terms, summed); FVm, FSm are the axis's motor friction, gear_ratio its gear (None
    for a direct drive)."""

    __slots__ = ("terms",)

    def __init__(self, effect: HiddenEffect | Sequence[HiddenEffect] | None, FVm: float,
                 FSm: float, gear_ratio: float | None, terms: tuple[Term, ...] = ()):
        self.terms = terms
        for e in as_effects(effect):
            loop = BENCH_EFFECTS[e.name].loop
            term = loop(e.strength, e.all_options, gear_ratio, FVm, FSm) if loop else None
            self.terms += (term,) if term is not None else ()

    @property
    def active(self) -> bool:
        return bool(self.terms)

    def torque(self, q_m: float, qd_m: float) -> float:
        tau = 0.0
        for term in self.terms:
            tau += term(q_m, qd_m)
        return tau


def _numeric(model: mujoco.MjModel, name: str) -> list[float] | None:
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, name)
    if i < 0:
        return None
    adr, size = model.numeric_adr[i], model.numeric_size[i]
    return [float(v) for v in model.numeric_data[adr:adr + size]]


def loop_effects_from_model(model: mujoco.MjModel, axis: str) -> LoopEffects | None:
    """Bench-loop effects an extended MJCF carries as custom numerics (written by
    `jointbench diagnose`): `{axis}_ripple` = (amplitude, period, phase) and
    `{axis}_asymmetry` = (a, FVm, FSm). None when the model has none. ValueError for a
    numeric of the wrong shape."""
    found = [(b, _numeric(model, f"{axis}_{b.numeric}"))
             for b in BENCH_EFFECTS.values() if b.numeric]
    found = [(b, values) for b, values in found if values is not None]
    if not found:
        return None
    terms = tuple(b.from_numeric(values, axis) for b, values in found)
    return LoopEffects(None, 0.0, 0.0, None, tuple(t for t in terms if t is not None))
