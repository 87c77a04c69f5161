"""Hidden effects for virtual experiments (CONTRACT section 4).

`HiddenEffect` is what a user asks for (`--effect backlash=0.002`, options after colons:
`--effect hardening=1.0:deflection=0.004`). Effects MuJoCo expresses are written into the
MJCF (`apply_to_spec`); the others act in the bench loop (`LoopEffects`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco

from jointbench.identification.effects import EFFECTS

# Options each effect accepts, with defaults (joint-side units).
OPTIONS: dict[str, dict[str, float]] = {
    "torque_ripple": {"period": 0.0, "phase": 0.0},  # period 0: 2 pi / (6 N) or 0.02 rad
    "hardening": {"deflection": 0.003},  # |qm - q| beyond which stiffness rises by ratio K
    "torque_lag": {},
    "gravity": {}, "link_coulomb": {}, "backlash": {}, "spring_damping": {}, "offset": {},
    "asymmetric_friction": {},
}


@dataclass(frozen=True)
class HiddenEffect:
    """An effect of CONTRACT section 4 with its strength (the unit of EFFECTS[name])."""

    name: str
    strength: float
    options: dict[str, float] = field(default_factory=dict)

    def __post_init__(self):
        if self.name not in EFFECTS:
            raise ValueError(f"unknown effect '{self.name}' (known: {', '.join(EFFECTS)})")
        if not math.isfinite(self.strength):
            raise ValueError(f"effect '{self.name}': strength must be finite")
        if self.name in ("backlash", "spring_damping", "torque_lag", "hardening",
                         "link_coulomb") and self.strength < 0:
            raise ValueError(f"effect '{self.name}': strength must be >= 0, got {self.strength}")
        if self.name == "asymmetric_friction" and not -1 < self.strength < 1:
            raise ValueError("effect 'asymmetric_friction': strength must lie in (-1, 1)")
        unknown = set(self.options) - set(OPTIONS[self.name])
        if unknown:
            raise ValueError(f"effect '{self.name}' has no option {', '.join(sorted(unknown))} "
                             f"(options: {', '.join(OPTIONS[self.name]) or 'none'})")

    def option(self, key: str) -> float:
        return self.options.get(key, OPTIONS[self.name][key])

    def to_meta(self) -> dict[str, str]:
        meta = {"truth_effect": self.name,
                f"truth_{EFFECTS[self.name].parameter}": f"{self.strength:.10g}"}
        for key, value in self.options.items():
            meta[f"truth_effect_{key}"] = f"{value:.10g}"
        return meta


def parse_effect(text: str) -> HiddenEffect:
    """`name=strength[:option=value...]` -> HiddenEffect; ValueError says what is wrong."""
    head, *rest = text.split(":")
    if "=" not in head:
        raise ValueError(f"effect '{text}': expected NAME=STRENGTH, e.g. backlash=0.002")
    name, value = head.split("=", 1)
    try:
        strength = float(value)
    except ValueError:
        raise ValueError(f"effect '{text}': strength '{value}' is not a number") from None
    options = {}
    for item in rest:
        if "=" not in item:
            raise ValueError(f"effect '{text}': option '{item}' must read KEY=VALUE")
        key, val = item.split("=", 1)
        try:
            options[key.strip()] = float(val)
        except ValueError:
            raise ValueError(f"effect '{text}': option value '{val}' is not a number") from None
    return HiddenEffect(name.strip(), strength, options)


def apply_to_spec(spec: mujoco.MjSpec, axis: str, effect: HiddenEffect, K: float) -> None:
    """Write the effects MuJoCo expresses into the spec of the experiment model."""
    tendon = spec.tendon(f"{axis}_spring")
    if effect.name == "backlash":
        # Dead band: the spring acts only beyond +-b (MuJoCo's two-valued springlength).
        tendon.springlength = [-effect.strength, effect.strength]
    elif effect.name == "spring_damping":
        tendon.damping[0] = effect.strength
    elif effect.name == "hardening":
        # A second spring stacked in parallel that engages beyond +-deflection.
        d = effect.option("deflection")
        extra = spec.add_tendon(name=f"{axis}_hardening")
        extra.stiffness[0] = effect.strength * K
        extra.springlength = [-d, d]
        extra.wrap_joint(f"{axis}_motor", 1.0)
        extra.wrap_joint(axis, -1.0)
    elif effect.name == "link_coulomb":
        spec.joint(axis).frictionloss = effect.strength
    elif effect.name == "torque_lag":
        act = spec.actuator(f"{axis}_motor")
        act.dyntype = mujoco.mjtDyn.mjDYN_FILTEREXACT
        act.dynprm[0] = effect.strength
        act.actlimited = 0


class LoopEffects:
    """Effects acting in the bench loop: extra torque on the rotor from the state at the tick.

    offset: the rotor receives tau - c while the log records tau (sensor offset / constant load).
    torque_ripple: A sin(2 pi q_m / period + phase).
    asymmetric_friction: the motor friction (FVm qmd + FSm sign qmd) is scaled by (1 + a)
    for qmd > 0 and (1 - a) for qmd < 0.
    """

    __slots__ = ("offset", "ripple", "period", "phase", "asym", "FVm", "FSm")

    def __init__(self, effect: HiddenEffect | None, FVm: float, FSm: float,
                 gear_ratio: float | None):
        self.offset = self.ripple = self.asym = 0.0
        self.period, self.phase, self.FVm, self.FSm = 1.0, 0.0, FVm, FSm
        if effect is None:
            return
        if effect.name == "offset":
            self.offset = effect.strength
        elif effect.name == "torque_ripple":
            self.ripple = effect.strength
            period = effect.option("period")
            if period <= 0:
                period = 2 * math.pi / (6 * gear_ratio) if gear_ratio else 0.02
            self.period, self.phase = period, effect.option("phase")
        elif effect.name == "asymmetric_friction":
            self.asym = effect.strength

    @property
    def active(self) -> bool:
        return bool(self.offset or self.ripple or self.asym)

    def torque(self, q_m: float, qd_m: float) -> float:
        tau = -self.offset
        if self.ripple:
            tau += self.ripple * math.sin(2 * math.pi * q_m / self.period + self.phase)
        if self.asym and qd_m != 0.0:
            # Friction force opposing motion is (1 + a s)(FVm |qmd| + FSm), s = sign(qmd):
            # the extra part acts against the positive direction whatever the sign of qmd.
            tau -= self.asym * (self.FVm * abs(qd_m) + self.FSm)
        return tau


def loop_effects_from_model(model: mujoco.MjModel, axis: str) -> LoopEffects | None:
    """Bench-loop effects an extended MJCF carries as custom numerics (written by
    `jointbench diagnose`): `{axis}_ripple` = (amplitude, period, phase) and
    `{axis}_asymmetry` = (a, FVm, FSm). None when the model has neither."""
    def numeric(name: str) -> list[float] | None:
        i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, name)
        if i < 0:
            return None
        adr, size = model.numeric_adr[i], model.numeric_size[i]
        return [float(v) for v in model.numeric_data[adr:adr + size]]
    ripple, asym = numeric(f"{axis}_ripple"), numeric(f"{axis}_asymmetry")
    if ripple is None and asym is None:
        return None
    loop = LoopEffects(None, 0.0, 0.0, None)
    if ripple is not None:
        if len(ripple) != 3 or not ripple[1] > 0:
            raise ValueError(f"numeric {axis}_ripple must hold amplitude, period > 0, phase")
        loop.ripple, loop.period, loop.phase = ripple
    if asym is not None:
        if len(asym) != 3:
            raise ValueError(f"numeric {axis}_asymmetry must hold a, FVm, FSm")
        loop.asym, loop.FVm, loop.FSm = asym
    return loop
