"""The nominal model extended by several effects at once: the design a
candidate is tested against once other causes are named, and the design of a model with all
the named causes.

An effect's `design(rows, fixed)` (identification.effects.base) either adds columns
(`rows.extend`) or rebuilds the nominal columns with another torque or spring deflection
(`rows.columns`: torque lag, backlash). `Stacked` holds what the effects applied so far did;
an effect applied on top of it adds its columns to theirs and its torque or deflection to
theirs, so that any set of effects composes into one linear regression.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from jointbench.identification.discrepancy.nominal import Nominal
from jointbench.identification.discrepancy.signals import stack
from jointbench.identification.effects import EFFECTS
from jointbench.identification.effects.base import Column, Design
from jointbench.identification.filtering import derivatives


@dataclass(frozen=True)
class Stacked:
    """The nominal model of `nom` with `effects` ((name, fixed values), in order) applied."""

    nom: Nominal
    effects: tuple[tuple[str, dict], ...] = ()
    tau: np.ndarray | None = None          # the torque the nominal columns are built with
    deflection: np.ndarray | None = None   # the spring deflection they are built with
    lead: float = 0.0                      # the motor columns' lead [s] (torque lag)
    extra: tuple[tuple[str, np.ndarray], ...] = ()   # added columns, stacked rows
    # for each added column in order, its motor rows' derivative (a function giving the
    # decimated 3-point derivative, None for a column without motor rows); the columns added
    # past its end have none
    rates: tuple[Callable[[], np.ndarray] | None, ...] = ()

    def design(self) -> Design:
        """y, W and the column names: nominal columns, then the effects' columns, their
        motor rows led by `lead` as the nominal's are (`led_extra`)."""
        y, W, names = _core(self)
        if not self.extra:
            return y, W, names
        return (y, np.column_stack([W, *led_extra(self)]),
                names + tuple(n for n, _ in self.extra))


def led_extra(s: Stacked) -> list[np.ndarray]:
    """The added columns of `s`, each one's motor rows x led by the torque lag's T = s.lead
    as the nominal's motor columns are (Nominal.columns): x + T x'. The lag acts between the
    command and the rotor (effects.torque_lag: the command is (1 + T d/dt) of the torque the
    motor equation needs), and an effect's motor column is a torque on the rotor as the
    nominal's are, a ripple periodic in the motor angle, a friction, a spring's: the command
    holds T times its rate too. Left unled, a ripple's column cannot follow what the lag
    makes of it (T 2 pi qm' / p of the ripple, many times the ripple itself on a slow
    current loop), and the lag tested on top of a named ripple is fitted against a
    reference that holds the ripple in a form the lagged rotor never sees. The decimation
    is linear: dec(x + T x') = dec(x) + T dec(x'), the derivative decimated once."""
    cols = [c for _, c in s.extra]
    if not s.lead:
        return cols
    n = len(s.nom.sig.index)
    out = []
    for i, c in enumerate(cols):
        rate = s.rates[i] if i < len(s.rates) else None
        if rate is not None:
            c = c.copy()
            c[:n] += s.lead * rate()
        out.append(c)
    return out


def _rate(sig, motor: np.ndarray | None) -> Callable[[], np.ndarray] | None:
    """A function giving dec(x') of the raw-rate motor column `motor` (3-point difference,
    0 at the ends the decimation drops, as nominal._led), computed once on first call."""
    if motor is None:
        return None
    kept: list[np.ndarray] = []

    def rate() -> np.ndarray:
        if not kept:
            kept.append(sig.dec(np.nan_to_num(derivatives(motor, sig.ts, 1, 3)[1])))
        return kept[0]
    return rate


# The nominal columns of the last few states (tau, deflection, lead), most recent first, kept
# on the Nominal (its `memo`): every trial of an effect searched on top of a state rebuilds its
# design, and the columns a torque lag leads or a dead band rebuilds would be decimated again
# for each, a large share of `diagnose`'s time. Keyed by identity, holding
# the arrays: never a stale hit.
_KEEP = 8


def _core(s: Stacked) -> Design:
    """`s`'s nominal columns (Nominal.columns with its torque, deflection and lead)."""
    nom = s.nom
    if s.tau is None and s.deflection is None and not s.lead:
        return nom.y, nom.W, nom.names
    cores = nom.memo.setdefault("cores", [])
    key = (s.tau, s.deflection)
    for (k, lead), design in cores:
        if lead == s.lead and all(a is b for a, b in zip(k, key)):
            return design
    design = nom.columns(s.tau, s.deflection, s.lead)
    cores.insert(0, ((key, s.lead), design))
    del cores[_KEEP:]
    return design


class _Rows:
    """The identification.effects.base.Rows an effect's design sees on top of `base`; it
    records the state the effect leaves (`after`)."""

    def __init__(self, base: Stacked):
        self.base = base
        self.after = base
        self.sig = base.nom.sig
        self.link_v0 = base.nom.link_v0   # the link friction law's speed (nominal.link_law)
        self.deflection = base.deflection   # the spring's, when a cause rebuilt it (backlash)
        self.added: tuple[tuple[str, np.ndarray], ...] | None = None   # by extend alone

    def value(self, name: str) -> float:
        return self.base.nom.value(name)

    def extend(self, *columns: Column,
               rated: tuple[np.ndarray | None, ...] | None = None) -> Design:
        cols = tuple((n, stack(self.sig, m, li)) for n, m, li in columns)
        self.added = cols
        rated = rated if rated is not None else tuple(m for _, m, _ in columns)
        self.after = dataclasses.replace(
            self.base, extra=self.base.extra + cols,
            rates=_rates_of(self.base) + tuple(_rate(self.sig, r) for r in rated))
        return self.after.design()

    def columns(self, tau: np.ndarray | None = None,
                deflection: np.ndarray | None = None, lead: float | None = None) -> Design:
        b = self.base
        self.added = None   # its columns depend on the state it rebuilds: never reused
        self.after = dataclasses.replace(
            b, tau=b.tau if tau is None else tau,
            deflection=b.deflection if deflection is None else deflection,
            lead=b.lead if lead is None else lead)
        return self.after.design()


def apply(base: Stacked, effect: str, fixed: dict) -> tuple[Stacked, Design]:
    """`base` with one more effect (nonlinear values `fixed`), and its design. An effect
    applied on top of one that reduces to it (registry `reduces_to`: an offset on top of an
    asymmetric friction on a physical reference, _richer_in) is stacked under it
    (_under_richer): the richer's design reads whether the simpler is beside it, and the
    model holding both is then the same whichever entered first."""
    effects = base.effects + ((effect, dict(fixed)),)
    if _richer_in(base, effect):
        return _under_richer(base, effect, fixed)
    key = (effect, tuple(sorted(fixed.items())), _beside_simpler(base, effect))
    added = _added(base.nom, key)
    if added is not None:
        rates = tuple(_recomputed(base, effect, fixed, k) for k in range(len(added)))
        after = dataclasses.replace(base, extra=base.extra + added, effects=effects,
                                    rates=_rates_of(base) + rates)
        return after, after.design()
    rows = _Rows(base)
    d = EFFECTS[effect].design(rows, fixed)
    if rows.added is not None:
        _keep_added(base.nom, key, rows.added)
    return dataclasses.replace(rows.after, effects=effects), d


# The suffix of an effect's reference values in its fixed values (Effect.reference).
REFERENCE = "_ref"


def _richer_in(base: Stacked, effect: str) -> bool:
    """`base` holds an effect that reduces to `effect` (registry `reduces_to`) on a physical
    reference: its reference values (Effect.reference: an asymmetric friction's FV_ref,
    FS_ref, the friction it scales) all positive. The (1 + a s) law's tie orders the
    viscous and Coulomb parts the same way only when both frictions are; where the nominal
    fits a negative FVm the tie asks the opposite of the law, and an offset beside it would
    be credited with the law's own viscous part."""
    return any(name in EFFECTS and EFFECTS[name].reduces_to == effect
               and all(v > 0 for k, v in fixed.items() if k.endswith(REFERENCE))
               for name, fixed in base.effects)


def _under_richer(base: Stacked, effect: str, fixed: dict) -> tuple[Stacked, Design]:
    """`base` with `effect` applied before the effects of `base` that reduce to it, and
    after the rest; its `effects` in the order given (`base`'s, then `effect`). While the
    motor moves an asymmetric friction's Coulomb part is a constant torque, and its design
    beside an offset keeps the (1 + a s) law's viscous-to-Coulomb split
    (identification.effects.asymmetric_friction.design); stacked after it, an offset would
    find the asymmetry's column at the split it took alone, which is the offset's own
    constant where the asymmetry's search chose no viscous part (a constant opposing the
    viscous part, which the (1 + a s) law cannot hold), and the offset could add nothing on
    top of it by construction, and the model holding both would depend on which was named first."""
    richer = tuple(e for e in base.effects
                   if e[0] in EFFECTS and EFFECTS[e[0]].reduces_to == effect)
    rest = tuple(e for e in base.effects if e not in richer)
    s = stacked(base.nom, rest + ((effect, fixed),) + richer)
    after = dataclasses.replace(s, effects=base.effects + ((effect, dict(fixed)),))
    return after, after.design()


def _rates_of(base: Stacked) -> tuple[Callable[[], np.ndarray] | None, ...]:
    """`base`'s rates, padded with None to one per added column."""
    return base.rates + (None,) * (len(base.extra) - len(base.rates))


def _recomputed(base: Stacked, effect: str, fixed: dict,
                k: int) -> Callable[[], np.ndarray] | None:
    """The rate (Stacked.rates) of the k-th column `effect` adds on `base`, for columns kept
    decimated (_added) without their raw-rate rows: the effect's design run again on first
    call, only when a lag leads them."""
    kept = base.nom.memo.setdefault("rates", {})
    key = (effect, tuple(sorted(fixed.items())), _beside_simpler(base, effect), k)

    def rate() -> np.ndarray:
        if key not in kept:
            rows = _Rows(base)
            EFFECTS[effect].design(rows, fixed)
            r = rows.after.rates[len(base.extra) + k] if rows.added is not None else None
            kept[key] = np.zeros(len(base.nom.sig.index)) if r is None else r()
        return kept[key]
    return rate


def _beside_simpler(base: Stacked, effect: str) -> bool:
    """Whether `base` holds the effect `effect` reduces to (registry `reduces_to`): the one
    thing besides the signals and its values an effect's design reads (an asymmetric
    friction beside an offset keeps the reference's viscous-to-Coulomb split whatever its
    searched share, identification.effects.asymmetric_friction.design), and so a part of the
    key of the columns kept for it (_added)."""
    simpler = EFFECTS[effect].reduces_to if effect in EFFECTS else ""
    return bool(simpler) and any(name == simpler for name, _ in base.effects)


# The decimated columns an effect added (extend) with given values, kept on the Nominal (its
# `memo`): they depend on the log's signals and those values alone (identification.effects:
# `design` reads `rows.sig`, `rows.value` of the nominal and `fixed`; and, for an effect that
# reduces to another, whether the base holds that one: _beside_simpler), and every round of
# `diagnose` searches the same grid again on top of the causes named, as do the parsimony
# checks (two thirds of the ripple's and the hardening's decimations on a 60 s log). Least
# recently used first out beyond _BYTES; they go with the Nominal.
_BYTES = 64 * 2 ** 20


def _added(nom: Nominal, key: tuple) -> tuple[tuple[str, np.ndarray], ...] | None:
    """The columns kept on `nom` for (effect, values), or None."""
    kept = nom.memo.setdefault("added", {})
    hit = kept.pop(key, None)
    if hit is not None:
        kept[key] = hit   # most recent last
    return hit


def _keep_added(nom: Nominal, key: tuple, cols: tuple[tuple[str, np.ndarray], ...]) -> None:
    """Keep `cols` on `nom` for (effect, values); the least recently used go beyond _BYTES."""
    kept = nom.memo.setdefault("added", {})
    old = kept.pop(key, None)
    kept[key] = cols
    size = nom.memo.get("added_bytes", 0) + _nbytes(cols) - (_nbytes(old) if old else 0)
    while size > _BYTES and len(kept) > 1:
        size -= _nbytes(kept.pop(next(iter(kept))))
    nom.memo["added_bytes"] = size


def _nbytes(cols: tuple[tuple[str, np.ndarray], ...]) -> int:
    return sum(c.nbytes for _, c in cols)


def stacked(nom: Nominal, effects: Sequence[tuple[str, dict]]) -> Stacked:
    """The nominal model of `nom` extended by every effect of `effects`, in order."""
    s = Stacked(nom)
    for name, fixed in effects:
        if name not in EFFECTS:
            raise ValueError(f"unknown effect {name!r}")
        s, _ = apply(s, name, fixed)
    return s


def design_many(nom: Nominal, effects: Sequence[tuple[str, dict]]) -> Design:
    """y, W and names of the nominal model extended by several effects (name, fixed values)
    at once: the inverse view of a model with all the named causes."""
    return stacked(nom, effects).design()
