"""The bench half of an effect (docs/effects.md): how a virtual experiment hides it (MJCF
on an MjSpec, or a torque in the bench loop), how `diagnose`'s extended model carries it, and
how the battery draws its strength. The names and units are the identification half's
(jointbench.identification.effects).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import mujoco

Term = Callable[[float, float], float]          # (q_m, qd_m) -> extra torque on the rotor
Uniform = Callable[[float, float], float]       # rng.uniform(low, high)
# (strength, options with defaults, gear ratio, motor FVm, motor FSm) -> loop term or None
LoopTerm = Callable[[float, dict, "float | None", float, float], "Term | None"]


def any_strength(strength: float) -> str:
    return ""


def nonnegative(strength: float) -> str:
    return "" if not strength < 0 else f"strength must be >= 0, got {strength}"


def positive_part(p: dict, key: str) -> float:
    """p[key] when positive and finite, else 0 (missing keys are 0)."""
    v = float(p.get(key, 0.0))
    return v if v > 0 and math.isfinite(v) else 0.0


@dataclass(frozen=True)
class BenchEffect:
    """How the bench simulates one effect. Every callable is optional but `draw`.

    - `check(strength)`: why a strength is refused ("" when accepted);
    - `mjcf(spec, axis, strength, options, K)`: writes the effect into the experiment's MjSpec;
    - `extended(parameters)`: the (strength, options) `diagnose`'s extended model hides with
      `mjcf`, from the identified parameters;
    - `extend(spec, axis, parameters, K)`: writes the extended model another way (a load,
      custom numerics the bench loop reads); K = 0 for a rigid axis;
    - `loop(...)`: the torque it adds in the bench loop (LoopTerm);
    - `numeric`, `from_numeric(values, axis)`: the custom numeric `{axis}_{numeric}` an
      extended MJCF carries it in, read back as a loop term;
    - `draw(uniform, sign, tau_max, f1_hz, K)`: a battery strength and options for an axis
      with this torque limit, first mode and stiffness; `largest`: the largest strength
      magnitude the battery's search for a visibility tries (an effect bounded by its
      definition stays inside its bounds).
    """

    name: str
    draw: Callable[[Uniform, float, float, float, float], tuple[float, dict[str, float]]]
    options: dict[str, float] = field(default_factory=dict)   # accepted options, defaults
    check: Callable[[float], str] = any_strength
    mjcf: Callable[[mujoco.MjSpec, str, float, dict, float], None] | None = None
    extended: Callable[[dict], tuple[float, dict[str, float]]] | None = None
    extend: Callable[[mujoco.MjSpec, str, dict, float], None] | None = None
    loop: LoopTerm | None = None
    numeric: str = ""
    from_numeric: Callable[[list[float], str], "Term | None"] | None = None
    largest: float = math.inf
