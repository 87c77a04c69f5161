"""What a user asks a virtual experiment to hide: `--effect backlash=0.002`, options after
colons: `--effect hardening=1.0:deflection=0.004`, several effects separated by commas:
`--effect backlash=0.002,offset=20` (each name at most once)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

from jointbench.bench.options import key_numbers
from jointbench.bench.effects.registry import BENCH_EFFECTS
from jointbench.identification.effects import EFFECTS

# Options each effect accepts, with defaults (joint-side units).
OPTIONS: dict[str, dict[str, float]] = {n: b.options for n, b in BENCH_EFFECTS.items()}


@dataclass(frozen=True)
class HiddenEffect:
    """An effect of docs/effects.md with its strength (the unit of EFFECTS[name])."""

    name: str
    strength: float
    options: dict[str, float] = field(default_factory=dict)

    def __post_init__(self):
        if self.name not in EFFECTS:
            raise ValueError(f"unknown effect '{self.name}' (known: {', '.join(EFFECTS)})")
        if not math.isfinite(self.strength):
            raise ValueError(f"effect '{self.name}': strength must be finite")
        why = BENCH_EFFECTS[self.name].check(self.strength)
        if why:
            raise ValueError(f"effect '{self.name}': {why}")
        unknown = set(self.options) - set(OPTIONS[self.name])
        if unknown:
            raise ValueError(f"effect '{self.name}' has no option {', '.join(sorted(unknown))} "
                             f"(options: {', '.join(OPTIONS[self.name]) or 'none'})")

    def option(self, key: str) -> float:
        return self.options.get(key, OPTIONS[self.name][key])

    @property
    def all_options(self) -> dict[str, float]:
        """Every option of the effect, defaults filled in."""
        return {key: self.option(key) for key in OPTIONS[self.name]}

    def to_meta(self) -> dict[str, str]:
        meta = {"truth_effect": self.name,
                f"truth_{EFFECTS[self.name].parameter}": f"{self.strength:.10g}"}
        for key, value in self.options.items():
            meta[f"truth_effect_{key}"] = f"{value:.10g}"
        return meta


def as_effects(effect: HiddenEffect | Sequence[HiddenEffect] | None) -> tuple[HiddenEffect, ...]:
    """One effect, several or none as a tuple; ValueError when a name comes twice."""
    effects = () if effect is None else (effect,) if isinstance(effect, HiddenEffect) \
        else tuple(effect)
    names = [e.name for e in effects]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"effect '{twice[0]}' is given twice (each effect at most once)")
    return effects


def strength_of(effects: tuple[HiddenEffect, ...], name: str) -> float:
    """The strength of effect `name` among `effects`, 0 when it is not hidden."""
    return sum(e.strength for e in effects if e.name == name)


def effects_meta(effects: tuple[HiddenEffect, ...]) -> dict[str, str]:
    """The truth metadata of the hidden effects (docs/log-format.md): `truth_effect` lists
    their names separated by commas (`none` without any), then each effect's parameter and
    options as for one effect."""
    meta = {"truth_effect": ",".join(e.name for e in effects) or "none"}
    for e in effects:
        meta.update({k: v for k, v in e.to_meta().items() if k != "truth_effect"})
    return meta


def parse_effects(text: str) -> tuple[HiddenEffect, ...]:
    """`A=S1[:opt=v...],B=S2[:...]` -> the hidden effects, in the given order; ValueError says
    what is wrong (an empty item, a name given twice, or `parse_effect`'s reasons)."""
    items = [item.strip() for item in text.split(",")]
    if any(not item for item in items):
        raise ValueError(f"effect '{text}': an empty item between commas; expected "
                         "NAME=STRENGTH[:OPTION=VALUE...][,NAME=STRENGTH...]")
    return as_effects([parse_effect(item) for item in items])


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
    options = key_numbers(
        rest, lambda item: ValueError(f"effect '{text}': option '{item}' must read KEY=VALUE"),
        lambda key, val: ValueError(f"effect '{text}': option value '{val}' is not a number"))
    return HiddenEffect(name.strip(), strength, options)
