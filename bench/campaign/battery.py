"""The hidden-effect battery of `diagnose` (issue: "the tests hide an effect and require finding
it"): seeded virtual experiments, each hiding one effect of docs/effects.md (or none) at a
randomised strength, on the prototype axis and on arm joints. Only the log goes to `diagnose`.

Strengths are drawn relative to the axis (its torque limit, first mode, stiffness), in ranges
where the effect moves the motor torque by a few % or the link equation by 5 % or more: the
sizes `diagnose` calls practically significant (identification.discrepancy.SIZE_MIN_PCT).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from jointbench.bench.effects import BENCH_EFFECTS, HiddenEffect
from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.effects import EFFECTS, NONE
from jointbench.identification.defaults import PAPER_RATE
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
