"""The unmodelled effects (docs/effects.md), identification half: one registry.

`EFFECTS` maps each name, in docs/effects.md order, to its `Effect` (one module per effect): the
strength parameter's name in `extended_parameters` and its unit, and the extended regression
`diagnose`'s inverse view tests (identification.discrepancy). The bench half
(jointbench.bench.effects) hides the same names in a simulation. To add an effect: one module
here, one in bench/effects, and one entry in each registry.
"""

from __future__ import annotations

from jointbench.identification.effects import (asymmetric_friction, backlash, gravity,
                                               hardening, link_coulomb, offset, spring_damping,
                                               torque_lag, torque_ripple)
from jointbench.identification.effects.base import Effect, Rows, deadzone, sign0

EFFECTS: dict[str, Effect] = {m.EFFECT.name: m.EFFECT for m in (
    gravity, link_coulomb, torque_ripple, backlash, spring_damping, torque_lag, hardening,
    offset, asymmetric_friction)}
NONE = "none"

__all__ = ["EFFECTS", "NONE", "Effect", "Rows", "deadzone", "sign0"]
