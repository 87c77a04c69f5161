"""Running a campaign: one run (simulate, identify, optionally bias-correct; in a worker) and
the driver that hands the missing runs to an engine (bench.campaign.executors), appends each
finished row to the table and, when all are in, returns the rows and the Monte Carlo summary.
"""

from __future__ import annotations

import math
import sys
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import numpy as np

from jointbench.bench.analysis.debias import debias, friction_timeconst_of
from jointbench.bench.campaign.scatter import scattered_factors, scattered_mjcf
from jointbench.bench.campaign.settings import ID_MODELS, SWEEPABLE, RunSettings, debiased_models
from jointbench.bench.campaign.spec import DEBIASED, PARAMS, TRUTH, CampaignSpec, RunTask
from jointbench.bench.campaign.summary import summarize
from jointbench.bench.campaign.table import CampaignTable
from jointbench.bench.effects import parse_effect
from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.sim.experiment import run_experiment
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.defaults import default_settings
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.identify import identify
from jointbench.identification.physical import invert_motor_only


# --------------------------------------------------------------------------------------------
# One run (executes in a worker: a top-level function of plain picklable data)


@dataclass(frozen=True)
class RunOutcome:
    """A finished run: its table row (strings) and the wall times it took in the worker."""

    index: int
    row: dict[str, str]
    sim_s: float = math.nan
    identify_s: float = math.nan


def _fmt(x) -> str:
    """Shortest round-trip text of a number (repr; integers as such), 'nan' when not finite,
    '' when missing; deterministic."""
    if x is None:
        return ""
    if isinstance(x, (int, np.integer)) and not isinstance(x, bool):
        return str(int(x))
    x = float(x)
    return repr(x) if math.isfinite(x) else "nan"


def _sensors(settings: RunSettings, model_ref: str, joint: str | None):
    """Sensors.default with the campaign's noise multiple and encoder resolutions (None: the
    default sensors)."""
    if settings.noise == 1.0 and settings.motor_bits is None and settings.link_bits is None:
        return None
    exp = build_experiment_model(model_ref, joint)
    base = Sensors.default(exp.truth.gear_ratio, exp.tau_max)
    N = exp.truth.gear_ratio or 100.0
    return Sensors(
        motor_resolution=(2 * math.pi / (2 ** settings.motor_bits * N)
                          if settings.motor_bits is not None else base.motor_resolution),
        link_resolution=(2 * math.pi / 2 ** settings.link_bits
                         if settings.link_bits is not None else base.link_resolution),
        torque_noise_std=settings.noise * base.torque_noise_std)


def _filter(settings: RunSettings, log) -> FilterSettings | None:
    """The run's filter: the default one with the settings' wn, Nd and stencil (None: the
    identification's own default)."""
    if settings.wn is None and settings.Nd is None and settings.stencil == 3:
        return None
    base = default_settings(log.sample_rate_hz, log.truth().get("f1_hz"))
    return FilterSettings(wn=settings.wn if settings.wn is not None else base.wn, m=base.m,
                          Nd=settings.Nd if settings.Nd is not None else base.Nd, ts=log.ts,
                          stencil=settings.stencil)


def corrected_sigmas(ident, log) -> dict[str, float]:
    """Standard deviations of the physical parameters from the corrected covariance that
    identification.uncertainty attaches to the LS result (`cov_corrected`), propagated through
    the motor-only inversion like the paper's; {} when the LS result carries none."""
    ls = ident.ls
    cov = getattr(ls, "cov_corrected", None)
    if callable(cov):
        cov = cov()
    if cov is None:
        return {}
    cov = np.asarray(cov, dtype=float)
    if ident.model.startswith("motor-only"):
        swapped = replace(ls, cov=cov, sigma=np.sqrt(np.abs(np.diag(cov))))
        phys = invert_motor_only(swapped, g=log.gravity, qc=float(np.mean(log.q_m)))
        return {n: phys.std(n) for n in phys.names}
    return {n: float(np.sqrt(cov[i, i])) for i, n in enumerate(ls.names)
            if n not in ls.unidentifiable}


def run_task(task: RunTask) -> RunOutcome:
    """Simulate and identify one run; never raises: a failure is the row's status and reason."""
    s = task.settings
    row: dict[str, str] = {"run": str(task.index), "repeat": str(task.repeat),
                           "seed": str(task.seed), "status": "ok", "reason": "",
                           "model": s.model, "joint": s.joint or "", "effect": s.effect or ""}
    for name in SWEEPABLE:
        row[name] = _fmt(getattr(s, name))
    reasons: list[str] = []
    sim_s = identify_s = math.nan
    try:
        t0 = time.perf_counter()
        effect = parse_effect(s.effect) if s.effect else None
        with tempfile.TemporaryDirectory(prefix="jointbench-run-") as tmp:
            model_ref, joint = s.model, s.joint
            if s.scatter > 0:
                xml, joint = scattered_mjcf(s.model, s.joint,
                                            scattered_factors(s.scatter, task.scatter_seed))
                model_ref = str(Path(tmp) / "scattered.xml")
                Path(model_ref).write_text(xml, encoding="utf-8")
            result = run_experiment(model_ref, joint, duration=s.duration, seed=task.seed,
                                    amplitude=s.amplitude, effect=effect,
                                    sensors=_sensors(s, model_ref, joint))
        sim_s = time.perf_counter() - t0
    except Exception as err:  # noqa: BLE001 - recorded in the row
        reasons.append(f"simulation: {type(err).__name__}: {err}")
        result = None
    if result is not None:
        log = result.log
        row["joint"] = log.meta.get("joint", row["joint"])
        row["saturated"] = str(result.saturated)
        truth = log.truth()
        for p in TRUTH:
            row[f"truth.{p}"] = _fmt(truth.get(p))
        t1 = time.perf_counter()
        for m in s.id_models:
            try:
                ident = identify(log, m, _filter(s, log))
                corr = corrected_sigmas(ident, log)
            except Exception as err:  # noqa: BLE001 - recorded in the row
                reasons.append(f"{m}: {type(err).__name__}: {err}")
                continue
            pre = ID_MODELS[m]
            for p in PARAMS[m]:
                row[f"{pre}.{p}"] = _fmt(ident.physical.get(p))
                row[f"{pre}.{p}.sigma"] = _fmt(ident.physical_sigma.get(p))
                row[f"{pre}.{p}.sigma_c"] = _fmt(corr.get(p))
            if m in debiased_models(s):
                try:
                    d = debias(log, ident, replicas=s.debias, seed=task.seed,
                               friction_timeconst=friction_timeconst_of(
                                   result.experiment.model, result.experiment.axis))
                except Exception as err:  # noqa: BLE001 - recorded in the row
                    reasons.append(f"{m} bias correction: {type(err).__name__}: {err}")
                    continue
                for p in PARAMS[m]:
                    row[f"{pre}{DEBIASED}.{p}"] = _fmt(d.estimate.get(p))
                    row[f"{pre}{DEBIASED}.{p}.sigma_c"] = _fmt(d.sigma.get(p))
                    row[f"{pre}{DEBIASED}.{p}.sigma_r"] = _fmt(d.sigma_replicas.get(p))
        identify_s = time.perf_counter() - t1
    if reasons:
        row["status"] = "failed"
        row["reason"] = " ".join("; ".join(reasons).split())  # one line
    return RunOutcome(task.index, row, sim_s, identify_s)


def lost_outcome(task: RunTask, error: str) -> RunOutcome:
    """The row of a run the engine lost (worker died)."""
    row = {"run": str(task.index), "repeat": str(task.repeat), "seed": str(task.seed),
           "status": "failed", "reason": " ".join(error.split()), "model": task.settings.model,
           "joint": task.settings.joint or "", "effect": task.settings.effect or ""}
    for name in SWEEPABLE:
        row[name] = _fmt(getattr(task.settings, name))
    return RunOutcome(task.index, row)


# --------------------------------------------------------------------------------------------
# Driver


class Progress:
    """A one-line progress bar on a stream (stderr), redrawn at most 10 times a second."""

    def __init__(self, total: int, done: int = 0, stream=None, enabled: bool = True,
                 label: str = "campaign"):
        self.total, self.done, self.failed = total, done, 0
        self.start_done = done
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.label = label
        self.t0 = time.perf_counter()
        self._last = 0.0

    def update(self, ok: bool) -> None:
        self.done += 1
        self.failed += 0 if ok else 1
        now = time.perf_counter()
        if self.enabled and (now - self._last > 0.1 or self.done == self.total):
            self._last = now
            rate = (self.done - self.start_done) / max(now - self.t0, 1e-9)
            eta = (self.total - self.done) / rate if rate > 0 else math.inf
            width = 30
            fill = int(width * self.done / max(self.total, 1))
            self.stream.write(f"\r{self.label}: [{'#' * fill}{'.' * (width - fill)}] "
                              f"{self.done}/{self.total} runs, {self.failed} failed, "
                              f"{rate:.2f} runs/s, eta {eta:.0f} s ")
            if self.done == self.total:
                self.stream.write("\n")
            self.stream.flush()


@dataclass(frozen=True)
class CampaignResult:
    spec: CampaignSpec
    rows: list[dict[str, str]]
    summary: dict
    resumed: int          # rows found in the table before this invocation
    new: int              # runs done by this invocation
    wall_s: float
    sim_s: list[float]
    identify_s: list[float]


def run_campaign(spec: CampaignSpec, table: str | Path, executor,
                 progress: Callable[[bool], None] | None = None) -> CampaignResult:
    """Run the campaign's missing runs on `executor` (bench.executors), appending to `table`;
    when all are in, sort the table and return the rows and summary."""
    tab = CampaignTable(Path(table), spec)
    resumed = len(tab.rows)
    pending = [spec.task(i) for i in range(spec.total) if i not in tab.rows]
    sim_s: list[float] = []
    identify_s: list[float] = []
    t0 = time.perf_counter()
    try:
        for done in executor.map_unordered(run_task, pending):
            outcome = done.value if done.error is None else lost_outcome(done.item, done.error)
            tab.append(outcome.row)
            if math.isfinite(outcome.sim_s):
                sim_s.append(outcome.sim_s)
            if math.isfinite(outcome.identify_s):
                identify_s.append(outcome.identify_s)
            if progress is not None:
                progress(outcome.row["status"] == "ok")
    finally:
        tab.close()
    wall = time.perf_counter() - t0
    tab.finalize()
    rows = [tab.rows[i] for i in sorted(tab.rows)]
    return CampaignResult(spec=spec, rows=rows, summary=summarize(spec, rows), resumed=resumed,
                          new=len(pending), wall_s=wall, sim_s=sim_s, identify_s=identify_s)
