"""`jointbench survey`: the chirp experiment on every axis of a robot in turn, the others
locked, each identified with the defaults and compared with the model's truth.

One task per axis (`survey_joint`, a top-level function of plain data: it runs in a worker of
bench.campaign.executors). An axis is simulated exactly as `jointbench simulate --model M
--joint J --duration D --seed S` would (same log, bit for bit) and identified as `jointbench
identify` would: the joint-motor model (eq. 13) when the log has the link position q and the
axis is flexible, else `auto`; the filter from the first mode measured on the log
(identification.filter_choice.choose_filter), never from the truth.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from jointbench.bench.campaign.executors import make_executor
from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ, run_experiment
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.first_mode import FirstMode
from jointbench.identification.identify import identify
from jointbench.identification.log import Log
from jointbench.identification.output_values import pct_error
from jointbench.identification.parameters import FRICTIONS, STIFFNESS_AND_INERTIAS
from jointbench.models import load_model, select_axis

SURVEYED = STIFFNESS_AND_INERTIAS + FRICTIONS   # K, Jm, JL, FVm, FSm, FV, FS: the table's rows
# The bar for any axis identified at the paper's rate: the joint-motor model's K, Jm and JL within
# 0.5 % of the truth; the survey reports, per axis, whether each is inside.
ACCURACY_BAR_PCT = 0.5


@dataclass(frozen=True)
class SurveyTask:
    """One axis to survey: the model (a shipped name or an MJCF path), the axis name, the
    chirp's length [s] and the noise seed."""

    model: str
    joint: str
    duration: float
    seed: int


@dataclass(frozen=True)
class Estimate:
    """One identified parameter: value, standard deviation (the paper's, white residuals),
    the autocorrelation-consistent one (`sigma_c`), the truth (None when the model has none)
    and the error in % of the truth."""

    value: float
    sigma: float
    sigma_c: float
    truth: float | None

    @property
    def error_pct(self) -> float | None:
        return pct_error(self.value, self.truth)

    @property
    def z(self) -> float | None:
        """(value - truth) / sigma_c: the error in corrected standard deviations."""
        if self.truth is None or not self.sigma_c > 0:
            return None
        return (self.value - self.truth) / self.sigma_c


@dataclass(frozen=True)
class JointSurvey:
    """What the survey found on one axis. `status` "ok", or "failed" with `reason`."""

    joint: str
    status: str = "ok"
    reason: str = ""
    log: Log | None = field(default=None, repr=False)
    model: str = ""                                 # the identification model
    settings: FilterSettings | None = None
    stencil_reason: str = ""
    first_mode: FirstMode | None = None
    f1_truth_hz: float | None = None
    estimates: dict[str, Estimate] = field(default_factory=dict)
    relative_error_pct: float = math.nan            # direct validation (Figure 2)
    saturated: int = 0
    warnings: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    sim_s: float = math.nan
    identify_s: float = math.nan

    def within_bar(self, bar_pct: float = ACCURACY_BAR_PCT) -> bool:
        """K, Jm and JL all identified within `bar_pct` % of their truth."""
        errs = [self.estimates[n].error_pct if n in self.estimates else None
                for n in STIFFNESS_AND_INERTIAS]
        return all(e is not None and abs(e) <= bar_pct for e in errs)


@dataclass(frozen=True)
class Survey:
    """Every axis of `model` surveyed, in the model's axis order."""

    model: str
    source: Path
    duration: float
    seed: int
    sample_rate_hz: float
    joints: tuple[JointSurvey, ...]
    workers: int = 1
    wall_s: float = math.nan

    @property
    def failed(self) -> tuple[JointSurvey, ...]:
        return tuple(j for j in self.joints if j.status != "ok")

    def worst(self, names: tuple[str, ...] = STIFFNESS_AND_INERTIAS
              ) -> tuple[str, str, float] | None:
        """(joint, parameter, error %) of the largest |error| among `names`, None if none."""
        errs = [(j.joint, n, j.estimates[n].error_pct) for j in self.joints for n in names
                if n in j.estimates and j.estimates[n].error_pct is not None]
        return max(errs, key=lambda e: abs(e[2])) if errs else None


def survey_joint(task: SurveyTask) -> JointSurvey:
    """Simulate and identify one axis (module docstring); never raises: a failure is the
    result's status and reason."""
    t0 = time.perf_counter()
    try:
        result = run_experiment(task.model, task.joint, duration=task.duration, seed=task.seed)
    except Exception as err:  # noqa: BLE001 - recorded in the row
        return JointSurvey(task.joint, "failed", f"simulation: {type(err).__name__}: {err}")
    t1 = time.perf_counter()
    log = result.log
    truth = log.truth()
    flexible = math.isfinite(result.experiment.truth.K)
    model = "joint-motor" if log.q is not None and flexible else "auto"
    try:
        ident = identify(log, model)
    except Exception as err:  # noqa: BLE001 - recorded in the row
        return JointSurvey(task.joint, "failed", f"identification ({model}): "
                           f"{type(err).__name__}: {err}", log=log, saturated=result.saturated,
                           sim_s=t1 - t0)
    if "J" in ident.physical and "Jm" in truth and "JL" in truth:
        truth["J"] = truth["Jm"] + truth["JL"]   # a rigid axis: one inertia
    names = [n for n in (*SURVEYED, "J") if n in ident.physical]
    estimates = {n: Estimate(ident.physical[n], ident.physical_sigma.get(n, math.nan),
                             ident.physical_sigma_corrected.get(n, math.nan), truth.get(n))
                 for n in names}
    return JointSurvey(
        task.joint, log=log, model=ident.model, settings=ident.settings,
        stencil_reason=ident.stencil_reason, first_mode=ident.first_mode,
        f1_truth_hz=truth.get("f1_hz"), estimates=estimates,
        relative_error_pct=ident.relative_error_pct, saturated=result.saturated,
        warnings=ident.warnings, notes=ident.notes, sim_s=t1 - t0,
        identify_s=time.perf_counter() - t1)


def survey_axes(model: str | Path, joints: list[str] | None = None) -> tuple[Path, list[str]]:
    """The model's file and the axes to survey (names, in the model's order): `joints` given
    by name or index from 1, or every axis. ModelStructureError for a model off the axis
    convention or an unknown axis."""
    _, axes, path = load_model(model)
    if not joints:
        return path, [a.name for a in axes]
    chosen = {select_axis(axes, j, str(path)).name for j in joints}
    return path, [a.name for a in axes if a.name in chosen]


def run_survey(model: str | Path, joints: list[str] | None = None, *, duration: float = 60.0,
               seed: int = 0, workers: int | None = None,
               progress: Callable[[JointSurvey, int, int], None] | None = None) -> Survey:
    """Survey the axes of `model` (`survey_axes`) on `workers` processes (1: in this process;
    None: every core, at most one per axis); `progress(result, done, total)` after each axis.
    Same arguments, same survey (the wall times aside), whatever the number of workers."""
    path, names = survey_axes(model, joints)
    tasks = [SurveyTask(str(model), name, float(duration), int(seed)) for name in names]
    workers = max(1, min(workers or os.cpu_count() or 1, len(tasks)))
    t0 = time.perf_counter()
    done: dict[str, JointSurvey] = {}
    executor = make_executor(workers)
    try:
        for d in executor.map_unordered(survey_joint, tasks):
            done[d.item.joint] = d.value if d.error is None else \
                JointSurvey(d.item.joint, "failed", d.error)
            if progress is not None:
                progress(done[d.item.joint], len(done), len(tasks))
    finally:
        executor.close()
    return Survey(str(model), path, float(duration), int(seed), SAMPLE_RATE_HZ,
                  tuple(done[n] for n in names), workers, time.perf_counter() - t0)
