"""Hidden effects of docs/effects.md in the independent simulator
(jointbench.testing.simulator).

Written again from the effects' text (docs/effects.md 4.1-4.2), not from the bench's modules:
same names, strength units and options, so a log of either simulator says the same thing in
`truth_effect`. Every term is evaluated inside the RK4 stages (the bench evaluates its loop
terms once per tick); the Coulomb sign is the simulator's smoothed tanh(v / v_s).

    backlash             spring K dz(qm - q, b), dz the dead zone of half-width b       [rad]
    spring_damping       + D (qm' - q') in parallel with the spring                [N m s/rad]
    torque_lag           the rotor gets the command through 1 / (1 + T s), exact over a hold [s]
    hardening            + r K dz(qm - q, deflection)                                  [ratio]
    link_coulomb         + FS tanh(q' / v_s) on the link, on top of the family's FS      [N m]
    gravity              the experiment centred `strength` from the rest angle          [rad]
    offset               the rotor gets tau - c (the log records tau)                   [N m]
    torque_ripple        + A sin(2 pi qm / period + phase) on the rotor                  [N m]
    asymmetric_friction  the motor friction times (1 + a sign qm')                     [ratio]

torque_ripple's default period (0) is 2 pi / (6 N) with the family's gear ratio N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

from jointbench.bench.options import key_numbers
from jointbench.identification.effects import EFFECTS


@dataclass(frozen=True)
class Hidden:
    """One hidden effect: its name (a key of TERMS), strength and the options given."""

    name: str
    strength: float
    options: dict[str, float] = field(default_factory=dict)

    def __post_init__(self):
        if self.name not in EFFECTS or self.name not in TERMS:
            raise ValueError(f"unknown effect '{self.name}'")
        if not math.isfinite(self.strength):
            raise ValueError(f"effect '{self.name}': strength must be finite")
        why = TERMS[self.name].refuses(self.strength)
        if why:
            raise ValueError(f"effect '{self.name}': strength must {why}")
        unknown = set(self.options) - set(TERMS[self.name].options)
        if unknown:
            raise ValueError(f"effect '{self.name}' has no option {', '.join(sorted(unknown))}")

    def option(self, key: str) -> float:
        return self.options.get(key, TERMS[self.name].options[key])


def parse_hidden(text: str) -> tuple[Hidden, ...]:
    """`A=S1[:opt=v...],B=S2` (simulate --effect's syntax) -> the hidden effects."""
    out = []
    for item in text.split(","):
        head, *rest = item.strip().split(":")
        name, value = head.split("=", 1)
        options = key_numbers(rest, ValueError, lambda k, v: ValueError(f"{k}={v}"))
        out.append(Hidden(name.strip(), float(value), options))
    return as_hidden(out)


def as_hidden(effects: "Hidden | Sequence[Hidden] | str | None") -> tuple[Hidden, ...]:
    """One effect, several, a --effect string or None as a tuple; each name at most once."""
    if isinstance(effects, str):
        return parse_hidden(effects)
    out = () if effects is None else (effects,) if isinstance(effects, Hidden) else tuple(effects)
    names = [e.name for e in out]
    if len(set(names)) != len(names):
        raise ValueError(f"an effect is given twice: {', '.join(names)}")
    return out


def truth_meta(effects: tuple[Hidden, ...]) -> dict[str, str]:
    """`truth_effect` (names joined by commas, or none), `truth_<parameter>` and
    `truth_effect_<option>` (docs/log-format.md)."""
    meta = {"truth_effect": ",".join(e.name for e in effects) or "none"}
    for e in effects:
        meta[f"truth_{EFFECTS[e.name].parameter}"] = f"{e.strength:.10g}"
        meta.update({f"truth_effect_{k}": f"{v:.10g}" for k, v in e.options.items()})
    return meta


@dataclass(frozen=True)
class Plant:
    """The effects' parameters as the stepper reads them (joint side, SI; 0: absent)."""

    backlash: float = 0.0
    damping: float = 0.0
    lag: float = 0.0
    hardening: float = 0.0        # extra stiffness r K [N m/rad]
    deflection: float = 0.0
    link_coulomb: float = 0.0
    offset: float = 0.0
    ripple: float = 0.0
    ripple_wavenumber: float = 0.0   # 2 pi / period [1/rad]
    ripple_phase: float = 0.0
    asymmetry: float = 0.0
    center_shift: float = 0.0     # gravity: the centre's distance from the rest angle [rad]

    @property
    def spring_extras(self) -> bool:
        return bool(self.backlash or self.damping or self.hardening)


# (effect, joint stiffness K [N m/rad], gear ratio or None, whether the link has a mass) ->
# the Plant fields the effect sets
Fields = Callable[[Hidden, float, "float | None", bool], dict[str, float]]


def _any(strength: float) -> str:
    return ""


def _nonnegative(strength: float) -> str:
    return "" if strength >= 0 else "be >= 0"


def _field(name: str) -> Fields:
    return lambda e, K, gear_ratio, has_mass: {name: e.strength}


def _hardening(e: Hidden, K: float, gear_ratio: float | None, has_mass: bool) -> dict:
    return {"hardening": e.strength * K, "deflection": e.option("deflection")}


def _ripple(e: Hidden, K: float, gear_ratio: float | None, has_mass: bool) -> dict:
    period = e.option("period")
    if period <= 0:
        period = 2 * math.pi / (6 * gear_ratio) if gear_ratio else 0.02
    return {"ripple": e.strength, "ripple_wavenumber": 2 * math.pi / period,
            "ripple_phase": e.option("phase")}


def _gravity(e: Hidden, K: float, gear_ratio: float | None, has_mass: bool) -> dict:
    if not has_mass:
        raise ValueError("effect 'gravity' needs a family with a link mass (MX or MY)")
    return {"center_shift": e.strength}


@dataclass(frozen=True)
class Term:
    """How this simulator hides one effect: the Plant fields it sets, its options with their
    defaults and why a strength is refused ("" when allowed), docs/effects.md 4.2."""

    fields: Fields
    options: dict[str, float] = field(default_factory=dict)
    refuses: Callable[[float], str] = _any


# Every effect of docs/effects.md this simulator hides, by name.
TERMS: dict[str, Term] = {
    "gravity": Term(_gravity),
    "link_coulomb": Term(_field("link_coulomb"), refuses=_nonnegative),
    "torque_ripple": Term(_ripple, {"period": 0.0, "phase": 0.0}),
    "backlash": Term(_field("backlash"), refuses=_nonnegative),
    "spring_damping": Term(_field("damping"), refuses=_nonnegative),
    "torque_lag": Term(_field("lag"), refuses=_nonnegative),
    "hardening": Term(_hardening, {"deflection": 0.003}, _nonnegative),
    "offset": Term(_field("offset")),
    "asymmetric_friction": Term(_field("asymmetry"),
                                refuses=lambda a: "" if -1 < a < 1 else "lie in (-1, 1)"),
}


def plant(effects: tuple[Hidden, ...], K: float, gear_ratio: float | None,
          has_mass: bool) -> Plant:
    """The stepper's parameters of `effects` on an axis of stiffness K [N m/rad]; ValueError
    for gravity on an axis without a link mass."""
    p: dict[str, float] = {}
    for e in effects:
        p.update(TERMS[e.name].fields(e, K, gear_ratio, has_mass))
    return Plant(**p)


def deadzone(x: float, b: float) -> float:
    """x - b above b, x + b below -b, 0 between."""
    return x - b if x > b else x + b if x < -b else 0.0


def spring_deflection(K: float, e: Plant, torque: float) -> float:
    """The deflection qm - q at which the spring (with backlash and hardening) holds `torque`
    [N m] at rest: bisection on the monotone spring law."""
    if torque == 0.0:
        return 0.0
    spring = lambda x: K * deadzone(x, e.backlash) + e.hardening * deadzone(x, e.deflection)
    lo, hi = 0.0, abs(torque) / K + e.backlash
    s = math.copysign(1.0, torque)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if spring(s * mid) < abs(torque) else (lo, mid)
    return s * 0.5 * (lo + hi)


State = tuple[float, float, float, float]   # (qm, q, qm', q') [rad, rad, rad/s, rad/s]
Accel = Callable[[float, float, float, float, float], tuple[float, float]]


def rk4_step(accel: Accel, x: State, h: float, tau0: float, tau_half: float,
             tau_end: float) -> State:
    """One classical RK4 step of length h from x; the rotor torque at the step's start,
    middle and end (all equal under a zero-order hold without lag)."""
    qm, q, vm, v = x
    a1m, a1 = accel(qm, q, vm, v, tau0)
    vm2, v2 = vm + 0.5 * h * a1m, v + 0.5 * h * a1
    a2m, a2 = accel(qm + 0.5 * h * vm, q + 0.5 * h * v, vm2, v2, tau_half)
    vm3, v3 = vm + 0.5 * h * a2m, v + 0.5 * h * a2
    a3m, a3 = accel(qm + 0.5 * h * vm2, q + 0.5 * h * v2, vm3, v3, tau_half)
    vm4, v4 = vm + h * a3m, v + h * a3
    a4m, a4 = accel(qm + h * vm3, q + h * v3, vm4, v4, tau_end)
    return (qm + h / 6.0 * (vm + 2.0 * vm2 + 2.0 * vm3 + vm4),
            q + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4),
            vm + h / 6.0 * (a1m + 2.0 * a2m + 2.0 * a3m + a4m),
            v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4))


def stepper_with_effects(family, gravity: float, T: float, substeps: int, e: Plant,
                         tau_init: float) -> Callable[[State, float], State]:
    """simulator.make_stepper with the hidden effects' terms for an AxisFamily `family`
    (slower: every term is evaluated at every stage)."""
    Jm, JL, K, FVm, FSm, FV = family.Jm, family.JL, family.K, family.FVm, family.FSm, family.FV
    FS, inv_vs = family.FS + e.link_coulomb, 1.0 / family.v_s
    gx, gy = family.MX * gravity, family.MY * gravity
    b, D, H, d_h, a, c = e.backlash, e.damping, e.hardening, e.deflection, e.asymmetry, e.offset
    A, kw, phase = e.ripple, e.ripple_wavenumber, e.ripple_phase
    h = T / substeps
    # Exact first-order lag over a hold: tau_a(s) = u + (tau_a(0) - u) exp(-s / lag).
    decay_half, decay = (math.exp(-0.5 * h / e.lag), math.exp(-h / e.lag)) if e.lag > 0 \
        else (0.0, 0.0)
    lagged, lag = [tau_init], e.lag > 0
    tanh, cos, sin = math.tanh, math.cos, math.sin

    def accel(qm: float, q: float, vm: float, v: float, tau: float) -> tuple[float, float]:
        x = qm - q
        spring = K * deadzone(x, b) + D * (vm - v) + H * deadzone(x, d_h)
        sm = tanh(vm * inv_vs)
        friction = FVm * vm + FSm * sm + a * (FVm * abs(vm) + FSm * abs(sm))
        drive = tau - c + A * sin(kw * qm + phase)
        load = spring - FV * v - FS * tanh(v * inv_vs) - gx * cos(q) - gy * sin(q)
        return (drive - friction - spring) / Jm, load / JL

    def step(x: State, u: float) -> State:
        for _ in range(substeps):
            t0 = lagged[0] if lag else u
            t_half, t_end = u + (t0 - u) * decay_half, u + (t0 - u) * decay
            lagged[0] = t_end
            x = rk4_step(accel, x, h, t0, t_half, t_end)
        return x

    return step


