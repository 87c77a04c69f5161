"""The names of the unmodelled effects (CONTRACT section 4): one source of truth.

Each entry gives the effect's strength parameter: its name in `extended_parameters` and its
unit on a revolute axis. The bench hides effects by these names; `diagnose` names them.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class EffectInfo:
    name: str
    parameter: str
    unit: str
    what: str


EFFECTS: dict[str, EffectInfo] = {e.name: e for e in (
    EffectInfo("gravity", "gravity_offset_rad", "rad",
               "gravity torque MX g cos q + MY g sin q acting away from the rest position"),
    EffectInfo("link_coulomb", "FS", "N m", "Coulomb friction FS sign(qd) on the link side"),
    EffectInfo("torque_ripple", "ripple_amplitude", "N m",
               "torque ripple periodic in the motor angle (cogging, drive ripple)"),
    EffectInfo("backlash", "backlash_rad", "rad",
               "dead zone of half-width b in the transmission deflection qm - q"),
    EffectInfo("spring_damping", "D", "N m s/rad",
               "viscous damping D (qmd - qd) in parallel with the joint spring"),
    EffectInfo("torque_lag", "lag_s", "s",
               "the applied torque lags the command (first-order current-loop lag)"),
    EffectInfo("hardening", "hardening_ratio", "",
               "stiffness that rises with deflection (piecewise linear)"),
    EffectInfo("offset", "offset", "N m", "a constant torque (sensor offset, constant load)"),
    EffectInfo("asymmetric_friction", "asymmetry", "",
               "viscous and Coulomb friction that differ with the direction of motion"),
)}
NONE = "none"
