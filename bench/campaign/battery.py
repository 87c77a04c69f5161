"""The hidden-effect batteries of `diagnose`: seeded virtual experiments, each hiding effects
of docs/effects.md (or none). Only the log goes to `diagnose`.

- The battery by visibility (`plan`, `run_spec`, benchmarks/battery.py):
  every case at the paper's rate, on bench axes and (through a `Runner`) on other
  simulators; each effect's strength is searched so that its in-band visibility
  (bench.campaign.visibility) hits a target drawn uniformly in VISIBILITY_RANGE, whatever
  the detector's thresholds; two-effect cases hide two effects of visibility >= PAIR_MIN each.
- The older battery (`cases`, `run_case`, benchmarks/diagnose_battery.py) draws strengths
  relative to the axis, in ranges where `diagnose` calls the effect practically significant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np

from jointbench.bench.campaign.visibility import Search, strength_for, visibility
from jointbench.bench.effects import BENCH_EFFECTS, HiddenEffect
from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.sim.controller import gains_rule
from jointbench.bench.sim.defaults import AMPLITUDE_REDUCTION, default_substeps
from jointbench.bench.sim.experiment import default_chirp, run_experiment
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.effects import EFFECTS, NONE
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.log import Log
from jointbench.identification.parameters import TWO_MASS
from jointbench.models import load_model, torque_limit
from jointbench.models.truth import axis_truth

# (model, joint, sample rate): the prototype at the paper's rate; arm joints at 1 kHz, where
# the central differences keep their 15-19 Hz modes (eq. 29 wants about 53 f1).
AXES = (("prototype", None, PAPER_RATE), ("arm6", "axis1", 1000.0), ("arm6", "axis2", 1000.0),
        ("arm6", "axis4", 1000.0), ("arm6", "axis6", 1000.0))
# Joints whose link carries a gravity torque (the `gravity` effect needs one).
GRAVITY_AXES = (("prototype", None, PAPER_RATE), ("arm6", "axis2", 1000.0))


@dataclass(frozen=True)
class Case:
    index: int
    model: str
    joint: str | None
    rate_hz: float
    seed: int
    effect: str                      # an EFFECTS name or "none"
    strength: float = 0.0
    options: dict[str, float] = field(default_factory=dict)

    @property
    def hidden(self) -> HiddenEffect | None:
        return None if self.effect == NONE else HiddenEffect(self.effect, self.strength,
                                                             self.options)

    @property
    def label(self) -> str:
        axis = self.model if self.joint is None else f"{self.model}:{self.joint}"
        what = NONE if self.effect == NONE else f"{self.effect}={self.strength:.4g}"
        return f"#{self.index} {axis} {what}"


def draw_strength(effect: str, rng: np.random.Generator, tau_max: float, f1_hz: float,
                  K: float) -> tuple[float, dict[str, float]]:
    """A random strength for `effect` on an axis with this torque limit, mode and stiffness
    (the effect's `draw` in bench.effects)."""
    u = rng.uniform
    sign = 1.0 if rng.random() < 0.5 else -1.0
    if effect not in BENCH_EFFECTS:
        raise ValueError(f"unknown effect {effect!r}")
    return BENCH_EFFECTS[effect].draw(u, sign, tau_max, f1_hz, K)


def cases(per_effect: int = 5, seed: int = 2026, effects: tuple[str, ...] | None = None,
          axes: tuple = AXES, clean: int | None = None) -> list[Case]:
    """`per_effect` cases for every effect and `clean` (default `per_effect`) clean ones,
    cycling over `axes`."""
    rng = np.random.default_rng(seed)
    names = list(effects or (NONE, *EFFECTS))
    truth_cache: dict = {}
    out: list[Case] = []
    for name in names:
        pool = GRAVITY_AXES if name == "gravity" else axes
        for k in range(clean if name == NONE and clean is not None else per_effect):
            model, joint, rate = pool[k % len(pool)]
            key = (model, joint)
            if key not in truth_cache:
                m, found, _ = load_model(model)
                axis = next(a for a in found if joint in (None, a.name))
                tr = axis_truth(m, axis, m.qpos0.copy())
                truth_cache[key] = (torque_limit(m, axis), tr.f1_hz, tr.K)
            tau_max, f1, K = truth_cache[key]
            strength, options = (0.0, {}) if name == NONE else draw_strength(
                name, rng, tau_max, f1, K)
            out.append(Case(len(out), model, joint, rate, int(rng.integers(1, 2**31 - 1)),
                            name, strength, options))
    return out


def run_case(case: Case, duration: float = 40.0):
    """The case's virtual experiment (bench.sim.experiment.run_experiment): its log."""
    return run_experiment(case.model, case.joint, duration=duration, seed=case.seed,
                          effect=case.hidden, sample_rate_hz=case.rate_hz).log


def confusion(results: list[tuple[str, str]]) -> tuple[list[str], np.ndarray]:
    """Rows: hidden effect; columns: named cause."""
    labels = [NONE, *EFFECTS]
    M = np.zeros((len(labels), len(labels)), int)
    for hidden, named in results:
        M[labels.index(hidden), labels.index(named)] += 1
    return labels, M


# ---- the battery by visibility ----

VISIBILITY_RANGE = (0.03, 0.40)   # single-effect targets, drawn uniformly (ratios)
PAIR_RANGE = (0.10, 0.40)         # each effect's target in a two-effect case
# An effect whose strength is a parameter of the two-mass nominal model (link_coulomb's FS:
# Table 1 has it) is left out: a log-only diagnosis identifies it with the nominal and never
# names it.
BATTERY_EFFECTS = tuple(name for name, e in EFFECTS.items() if e.parameter not in TWO_MASS)

Effect = tuple[str, float, dict]   # (name, strength, options): simulator-neutral


@dataclass(frozen=True)
class Place:
    """Where a case runs: a `source` simulator ("bench" or another runner's name), its
    model (prototype, arm6, a family) and joint; `gravity`: its link carries a gravity
    torque, so the `gravity` effect applies."""

    source: str
    model: str
    joint: str | None = None
    gravity: bool = False

    @property
    def label(self) -> str:
        return f"{self.source}:{self.model}" + (f":{self.joint}" if self.joint else "")

    @property
    def family(self) -> str:
        """The axis family (the model: arm6's joints are one family)."""
        return f"{self.source}:{self.model}"


BENCH_PLACES = (Place("bench", "prototype", None, True), Place("bench", "arm6", "axis2", True),
                Place("bench", "arm6", "axis4"))


@dataclass(frozen=True)
class Spec:
    """One planned case: where, seed, velocity feedforward, torque noise, and the hidden
    effects with their target visibilities (empty: a clean log)."""

    index: int
    place: Place
    seed: int
    feedforward: bool
    noise: bool
    effects: tuple[str, ...] = ()
    targets: tuple[float, ...] = ()

    @property
    def kind(self) -> str:
        return ("clean", "single", "pair")[min(len(self.effects), 2)]


# (velocity feedforward, torque noise): the conditions a case runs under
CONDITIONS = ((True, True), (False, True), (True, False), (False, False))


def condition_index(k: int, cycle: int, group: int) -> int:
    """The CONDITIONS index of the k-th case of a group (the clean cases, one effect's, the
    pairs: `group` 0, 1, ...) that cycles over `cycle` places: (k + k // M + group) mod 4,
    M = lcm(cycle, 4). Consecutive cases walk the conditions (each block of M cases takes
    each one M / 4 times); a place met again `cycle` cases later moves on by cycle mod 4,
    and after M cases, where that has brought it back, by one more; the next group starts
    one further. So every place, every effect and every kind sees all four."""
    n = len(CONDITIONS)
    return (k + k // math.lcm(cycle, n) + group) % n


def plan(places: tuple[Place, ...], per_effect: int = 8, clean: int = 24, pairs: int = 20,
         seed: int = 2026, effects: tuple[str, ...] = BATTERY_EFFECTS) -> list[Spec]:
    """The cases: `per_effect` for every effect, `clean` clean ones and `pairs` two-effect
    ones, cycling over `places` (gravity only where the link has a gravity torque) and over
    the four (feedforward, noise) CONDITIONS; targets uniform in VISIBILITY_RANGE, pairs'
    in PAIR_RANGE, two distinct effects each. A case's condition is `condition_index`'s:
    every place and every effect sees each condition. The draw (seeds, targets, effects)
    is the seed's alone: the conditions take nothing from it."""
    rng = np.random.default_rng(seed)
    out: list[Spec] = []

    def add(place: Place, condition: int, names: tuple[str, ...], targets: tuple) -> None:
        ff, noise = CONDITIONS[condition]
        out.append(Spec(len(out), place, int(rng.integers(1, 2**31 - 1)), ff, noise, names,
                        tuple(float(t) for t in targets)))

    for k in range(clean):
        add(places[k % len(places)], condition_index(k, len(places), 0), (), ())
    for group, name in enumerate(effects, start=1):
        pool = tuple(p for p in places if p.gravity) if name == "gravity" else places
        for k in range(per_effect):
            add(pool[k % len(pool)], condition_index(k, len(pool), group), (name,),
                (rng.uniform(*VISIBILITY_RANGE),))
    motor_side = [e for e in effects if e != "gravity"]
    for k in range(pairs):
        place = places[k % len(places)]
        names = [e for e in effects if e != "gravity" or place.gravity] if k % 3 == 0 \
            else motor_side
        a, b = rng.choice(len(names), 2, replace=False)
        add(place, condition_index(k, len(places), len(effects) + 1), (names[a], names[b]),
            rng.uniform(*PAIR_RANGE, 2))
    return out


class Runner(Protocol):
    """A simulator the battery runs cases on (the bench's: BenchRunner)."""

    rate_hz: float

    def scales(self, place: Place) -> tuple[float, float, float]:
        """(torque limit [N m], first mode f1 [Hz], stiffness K [N m/rad]) of the axis."""

    def log(self, place: Place, effects: tuple[Effect, ...], seed: int, feedforward: bool,
            noise: bool) -> Log:
        """The case's log with these hidden effects (torque noise on or off)."""


class BenchRunner:
    """The bench (bench.sim.experiment.run_experiment) at `rate_hz`, `duration` s logs. Every
    run of an axis and feedforward setting keeps the chirp of its clean run (shrunk as that
    run needed), so that an effect changes nothing else; the bench's default substeps, or for
    a torque lag more if MuJoCo's RK4 needs them to stay stable on the actuator filter
    (h <= 2 lag)."""

    def __init__(self, duration: float = 40.0, rate_hz: float = PAPER_RATE):
        self.duration, self.rate_hz = duration, rate_hz
        self._axes: dict = {}
        self._chirps: dict = {}

    def _chirp(self, place: Place, feedforward: bool, seed: int):
        key = (place, feedforward)
        if key not in self._chirps:
            exp, gains = self._axis(place)
            clean = run_experiment(place.model, place.joint, duration=self.duration,
                                   seed=seed, sample_rate_hz=self.rate_hz,
                                   sensors=self._sensors(exp, False),
                                   gains=replace(gains, velocity_feedforward=feedforward)).log
            chirp = default_chirp(exp, self.duration)
            for _ in range(int(clean.meta["amplitude_reductions"])):
                chirp = replace(chirp, amplitude=AMPLITUDE_REDUCTION * chirp.amplitude,
                                max_acceleration=0.6 * chirp.max_acceleration)
            self._chirps[key] = chirp
        return self._chirps[key]

    @staticmethod
    def _sensors(exp, noise: bool) -> Sensors:
        sensors = Sensors.default(exp.truth.gear_ratio, exp.tau_max)
        return sensors if noise else replace(sensors, torque_noise_std=0.0)

    def _axis(self, place: Place):
        if place not in self._axes:
            exp = build_experiment_model(place.model, place.joint, sample_rate_hz=self.rate_hz)
            t = exp.truth
            gains = gains_rule(t.Jm, t.JL, t.K, exp.tau_max, 1.0 / self.rate_hz)
            self._axes[place] = (exp, gains)
        return self._axes[place]

    def scales(self, place: Place) -> tuple[float, float, float]:
        exp, _ = self._axis(place)
        return exp.tau_max, exp.truth.f1_hz, exp.truth.K

    def log(self, place: Place, effects: tuple[Effect, ...], seed: int, feedforward: bool,
            noise: bool) -> Log:
        exp, gains = self._axis(place)
        hidden = tuple(HiddenEffect(n, s, o) for n, s, o in effects)
        lag = sum(s for n, s, _ in effects if n == "torque_lag")
        substeps = max(default_substeps(self.rate_hz), math.ceil(1.0 / (self.rate_hz * 2.0 * lag))
                       if lag > 0 else 1)
        return run_experiment(place.model, place.joint, duration=self.duration, seed=seed,
                              effect=hidden, sensors=self._sensors(exp, noise),
                              sample_rate_hz=self.rate_hz, substeps=substeps,
                              chirp=self._chirp(place, feedforward, seed),
                              gains=replace(gains, velocity_feedforward=feedforward)).log


@dataclass(frozen=True)
class Outcome:
    """A run case: the strengths and options found, each effect's visibility alone (its
    search), the visibility of all of them together, and the log handed to `diagnose`."""

    spec: Spec
    strengths: tuple[float, ...]
    options: tuple[dict, ...]
    visibilities: tuple[float, ...]
    combined: float
    searches: tuple[Search, ...]
    log: Log = field(repr=False)


def clean_key(spec: Spec, runner: Runner) -> tuple:
    """The key of a case's clean noise-free command in run_spec's cache: its place and
    feed-forward, and its seed where the runner's excitation depends on it (a random-phase
    multisine: `seeded_excitation`); a chirp is the same for every seed."""
    seeded = getattr(runner, "seeded_excitation", False)
    return (spec.place, spec.feedforward, spec.seed if seeded else None)


def run_spec(spec: Spec, runner: Runner, cache: dict | None = None) -> Outcome:
    """Search each effect's strength for its target visibility (noise off, same seed), then
    run the case's log with all of them (its own noise setting). `cache` keeps the clean
    noise-free commands between cases (without torque noise the seed changes nothing)."""
    place = spec.place
    tau_max, f1, K = runner.scales(place)
    cache = {} if cache is None else cache
    key = clean_key(spec, runner)
    if key not in cache:
        cache[key] = runner.log(place, (), spec.seed, spec.feedforward, False).tau_m
    clean = cache[key]
    quiet: dict = {}       # noise-free logs of the search, by effects: the final log of a
                           # case without torque noise is one of them

    def vis(effects: tuple[Effect, ...]) -> float:
        log = runner.log(place, effects, spec.seed, spec.feedforward, False)
        quiet[repr(effects)] = log
        return visibility(clean, log.tau_m, f1, runner.rate_hz)

    found: list[Effect] = []
    searches: list[Search] = []
    for k, (name, target) in enumerate(zip(spec.effects, spec.targets)):
        rng = np.random.default_rng([spec.seed, k])
        start, options = draw_strength(name, rng, tau_max, f1, K)
        search = strength_for(target, lambda s: vis(((name, s, options),)), start,
                              BENCH_EFFECTS[name].largest)
        found.append((name, search.strength, options))
        searches.append(search)
    effects = tuple(found)
    combined = searches[0].visibility if len(effects) == 1 else vis(effects) if effects else 0.0
    log = quiet.get(repr(effects)) if not spec.noise else None
    if log is None:
        log = runner.log(place, effects, spec.seed, spec.feedforward, spec.noise)
    return Outcome(spec, tuple(e[1] for e in effects), tuple(e[2] for e in effects),
                   tuple(s.visibility for s in searches), combined, tuple(searches), log)
