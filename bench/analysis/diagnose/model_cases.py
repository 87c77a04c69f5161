"""Cases for checking `diagnose --model` against ground truth ("wrong parameters"):
a copy of a shipped MJCF with some of K, Jm, JL, FS, FVm off by a known factor, the log of
the true model, and the score of a diagnosis of that log against the copy.

Used by tests/validation/test_diagnose_model.py (a few cases) and benchmarks/diagnose_model.py (the
battery of at least 20)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from jointbench.bench.analysis.diagnose.against_model import (COMPARED, FLOOR_PCT,
                                                              ModelDiagnosis)
from jointbench.bench.analysis.diagnose.model_edit import corrected_spec, spec_truth
from jointbench.bench.analysis.diagnose.model_floor import excess
from jointbench.bench.analysis.diagnose.model_precision import POINTS
from jointbench.bench.sim.nominal import write_xml
from jointbench.models import model_path

OFF = ("K", "Jm", "JL", "FS", "FVm")   # the parameters a case puts off
# POINTS (model_precision): the reported error must be this close to the truth


@dataclass(frozen=True)
class Case:
    """One wrong copy: `factors` multiply the true values of the model's axis `joint`."""

    model: str
    joint: str
    factors: dict[str, float]
    seed: int = 0

    @property
    def label(self) -> str:
        return (f"{self.model}/{self.joint} " + (", ".join(
            f"{k} x{v:.3f}" for k, v in self.factors.items()) or "true model"))


def draw_cases(rng: np.random.Generator, model: str, joint: str, n: int) -> list[Case]:
    """`n` cases on one axis: one or two of OFF, each off by a factor 1 +- U(0.10, 0.30)."""
    out = []
    for _ in range(n):
        names = rng.choice(OFF, size=int(rng.integers(1, 3)), replace=False)
        out.append(Case(model, joint, {str(k): float(1 + rng.choice((-1, 1))
                                                     * rng.uniform(0.10, 0.30))
                                       for k in names}))
    return out


def true_errors(case: Case, config: dict[str, float], path: Path) -> dict[str, float]:
    """Write the wrong copy to `path`; return the error of every parameter it changed, in %
    of the true value (as `diagnose --model` reports it: MX, MY over the gravity moment),
    those under 0.01 % left out."""
    source = model_path(case.model)
    truth = spec_truth(mujoco.MjSpec.from_file(str(source)), case.joint, config)[0]
    wrong = corrected_spec(source, case.joint, config,
                           {k: getattr(truth, k) * f for k, f in case.factors.items()})
    write_xml(wrong.spec, path)
    after = spec_truth(wrong.spec, case.joint, config)[0]
    g = float(np.hypot(truth.MX, truth.MY))
    out = {}
    for k in COMPARED:
        t, a = getattr(truth, k), getattr(after, k)
        scale = g if k in ("MX", "MY") else abs(t)
        if scale > 0 and abs(a - t) > 1e-4 * scale:
            out[k] = 100 * (a - t) / scale
    return out


@dataclass(frozen=True)
class Score:
    """How a diagnosis did on one case."""

    expected: dict[str, float]      # true errors (%) of the parameters put off
    named: dict[str, float]         # reported errors (%) of the parameters named wrong
    right: bool                     # named == the expected beyond the floor, each within POINTS
    named_right: bool               # the same names, whatever the errors reported
    torque_before: float            # forward torque error (% RMS), the wrong copy
    torque_after: float             # the corrected model
    floor: float = np.nan           # the replay's noise floor estimated from the log (% RMS)
    # the parameters put off whose error the diagnosis says it cannot tell within POINTS
    coarse: tuple[str, ...] = ()

    @property
    def misses(self) -> tuple[str, ...]:
        """The parameters put off beyond the floor that are not named, or named but reported
        over POINTS off."""
        want = {k: v for k, v in self.expected.items() if abs(v) > FLOOR_PCT}
        return tuple(k for k, v in want.items()
                     if k not in self.named or abs(self.named[k] - v) > POINTS)

    @property
    def flagged(self) -> bool:
        """Not right, but only on parameters put off whose error the diagnosis said it could
        not tell within POINTS (every miss among `coarse`); never with a parameter named that
        was not put off (a naming claims 3 sigma, whatever the precision)."""
        extra = set(self.named) - {k for k, v in self.expected.items() if abs(v) > FLOOR_PCT}
        return (not self.right and not extra and bool(self.misses)
                and set(self.misses) <= set(self.coarse))

    @property
    def ratio(self) -> float:
        return self.torque_before / self.torque_after if self.torque_after > 0 else np.inf

    @property
    def ceiling(self) -> float:
        """The largest gain a perfect model could show: wrong copy / floor."""
        return self.torque_before / self.floor

    @property
    def excess(self) -> tuple[float, float]:
        """(wrong copy, corrected): torque error above the floor, sqrt(err^2 - floor^2)."""
        return excess(self.torque_before, self.floor), excess(self.torque_after, self.floor)


def score(md: ModelDiagnosis, expected: dict[str, float]) -> Score:
    """Right when the parameters named wrong are exactly those put off by more than the
    floor, each reported within POINTS of its true error."""
    named = {n: md.errors[n].error_pct for n in md.wrong_parameters}
    want = {k: v for k, v in expected.items() if abs(v) > FLOOR_PCT}
    same = set(named) == set(want)
    right = same and all(abs(named[k] - want[k]) <= POINTS for k in want)
    g = md.gain()
    return Score(expected=expected, named=named, right=right, named_right=same,
                 torque_before=float(g.get("model", np.nan)),
                 torque_after=float(g.get("corrected", np.nan)),
                 floor=float(g.get("floor", np.nan)),
                 coarse=tuple(k for k in md.coarse if k in want))
