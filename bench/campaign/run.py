"""Running a campaign: one run (simulate, identify, optionally bias-correct; in a worker) and
the driver that hands the missing runs to an engine (bench.campaign.executors), appends each
finished row to the table and, when all are in, returns the rows and the Monte Carlo summary.
"""

from __future__ import annotations

import functools
import math
import pickle
import tempfile
import time
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from jointbench.bench.analysis.debias import debias
from jointbench.bench.campaign.executors import LocalExecutor, SerialExecutor
from jointbench.bench.campaign.host import call, check_refs, check_timeout, close_hosts
from jointbench.bench.campaign.methods import (DEFAULT_TIMEOUT_S, SCORED, BadResult, Method,
                                               blind, check_estimates, method_labels)
from jointbench.bench.campaign.scatter import scattered_factors, scattered_mjcf
from jointbench.bench.campaign.settings import (ID_MODELS, SWEEPABLE, CampaignError, RunSettings,
                                                debiased_models)
from jointbench.bench.campaign.spec import DEBIASED, PARAMS, TRUTH, CampaignSpec, RunTask
from jointbench.bench.campaign.summary import summarize
from jointbench.bench.campaign.table import CampaignTable
from jointbench.bench.campaign.times import read_times, times_path, write_times
from jointbench.bench.effects import parse_effects
from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ, run_experiment
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.filter_choice import choose_filter
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.first_mode import FirstMode
from jointbench.identification.identify import identify
from jointbench.identification.log.write import format_meta_number
from jointbench.identification.physical import invert_motor_only


# --------------------------------------------------------------------------------------------
# One run (executes in a worker: a top-level function of plain picklable data)


@dataclass(frozen=True)
class RunOutcome:
    """A finished run: its table row (strings) and the wall times it took in the worker:
    simulation, all identifications, and per method (built-in model, `MODEL+bc`, plug-in)."""

    index: int
    row: dict[str, str]
    sim_s: float = math.nan
    identify_s: float = math.nan
    times: dict[str, float] = field(default_factory=dict)


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


def _filter(settings: RunSettings, log) -> tuple[FilterSettings | None, FirstMode | None]:
    """The run's filter and the first mode it was designed from: the default one
    (`choose_filter`: the first mode measured on the log, never the truth) with the settings'
    wn, Nd and stencil ((None, None): the identification's own default)."""
    if settings.wn is None and settings.Nd is None and settings.stencil is None:
        return None, None
    choice = choose_filter(log)
    base = choice.settings
    return FilterSettings(wn=settings.wn if settings.wn is not None else base.wn, m=base.m,
                          Nd=settings.Nd if settings.Nd is not None else base.Nd, ts=log.ts,
                          stencil=settings.stencil if settings.stencil is not None
                          else base.stencil), choice.first_mode


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
    if ident.model == "motor-only":   # the link reconstruction's, not the X's (link_fit)
        return dict(ident.physical_sigma_corrected)
    if ident.model.startswith("motor-only"):
        swapped = replace(ls, cov=cov, sigma=np.sqrt(np.abs(np.diag(cov))))
        phys = invert_motor_only(swapped, g=log.gravity, qc=float(np.mean(log.q_m)))
        return {n: phys.std(n) for n in phys.names}
    return {n: float(np.sqrt(cov[i, i])) for i, n in enumerate(ls.names)
            if n not in ls.unidentifiable}


def _run_method(method: Method, log, timeout_s: float, row: dict[str, str],
                times: dict[str, float]) -> None:
    """One plug-in method on the (blind) log: its cells of the row and, when it answered, its
    wall time."""
    answer = call(method.ref, method.fn, log, timeout_s)
    label = method.label
    try:
        if answer.error is not None:
            raise BadResult(answer.error)
        est, sig = check_estimates(answer.value)
    except BadResult as err:
        row[f"{label}.status"] = "failed"
        row[f"{label}.reason"] = " ".join(str(err).split())[:300]
    else:
        row[f"{label}.status"] = "ok"
        for p in SCORED:
            row[f"{label}.{p}"] = _fmt(est.get(p))
            row[f"{label}.{p}.sigma"] = _fmt(sig.get(p))
        times[label] = answer.wall_s


def _run_model(task: RunTask, tmp: str) -> tuple[str, str | None]:
    """(model reference, joint) the run simulates: the spec's model, or its copy with the
    run's scattered parameters written into the folder `tmp`."""
    s = task.settings
    if s.scatter <= 0:
        return s.model, s.joint
    xml, joint = scattered_mjcf(s.model, s.joint, scattered_factors(s.scatter, task.scatter_seed))
    path = Path(tmp) / "scattered.xml"
    path.write_text(xml, encoding="utf-8")
    return str(path), joint


def _setting_cells(task: RunTask) -> dict[str, str]:
    """The cells of a run's row that its settings fix (run_task_with writes them first)."""
    s = task.settings
    row = {"run": str(task.index), "repeat": str(task.repeat), "seed": str(task.seed),
           "model": s.model, "effect": s.effect or ""}
    for name in SWEEPABLE:
        row[name] = _fmt(getattr(s, name))
    return row


@functools.lru_cache(maxsize=1 << 16)
def _truth_cells(settings: RunSettings, scatter_seed: int) -> tuple[tuple[str, str], ...]:
    """The truth cells of a run with these settings (and, with scatter, this scatter seed):
    built once per process and key, as a resume of a table checks every row."""
    task = RunTask(index=0, repeat=0, seed=0, scatter_seed=scatter_seed, settings=settings)
    with tempfile.TemporaryDirectory(prefix="jointbench-truth-") as tmp:
        model_ref, joint = _run_model(task, tmp)
        rate = {} if settings.rate is None else {"sample_rate_hz": settings.rate}
        exp = build_experiment_model(
            model_ref, joint,
            effect=parse_effects(settings.effect) if settings.effect else None,
            **{"sample_rate_hz": SAMPLE_RATE_HZ, **rate})
    truth = exp.truth.as_dict()
    cells = []
    for p in TRUTH:
        v = truth.get(p)
        v = float(format_meta_number(v)) if v is not None else None   # as the log holds it
        cells.append((f"truth.{p}", _fmt(v) if v is not None and math.isfinite(v) else ""))
    return tuple(cells)


def expected_cells(task: RunTask) -> dict[str, str]:
    """The cells a resumed `ok` row of `task` must hold (bench.campaign.table): its settings
    and the truth of the spec's model (scattered as the run's), as run_task_with writes them
    from the log's `truth_*` metadata. Builds the model (about 30 ms), no simulation."""
    seed = task.scatter_seed if task.settings.scatter > 0 else 0
    return {**_setting_cells(task), **dict(_truth_cells(task.settings, seed))}


def expected_of(spec: CampaignSpec) -> Callable[[int], dict[str, str]]:
    """expected_cells by run index (CampaignTable's `expected`)."""
    return lambda index: expected_cells(spec.task(index))


def run_task(task: RunTask) -> RunOutcome:
    """Simulate and identify one run; never raises: a failure is the row's status and reason."""
    return run_task_with((), DEFAULT_TIMEOUT_S, task)


def run_task_with(methods: Sequence[Method], timeout_s: float, task: RunTask) -> RunOutcome:
    """run_task, then every plug-in method on the run's log (blind: without its truth), each
    under a deadline of `timeout_s`; a method's failure is its own status and reason."""
    s = task.settings
    row: dict[str, str] = {**_setting_cells(task), "status": "ok", "reason": "",
                           "joint": s.joint or ""}
    reasons: list[str] = []
    sim_s = identify_s = math.nan
    times: dict[str, float] = {}
    try:
        t0 = time.perf_counter()
        effect = parse_effects(s.effect) if s.effect else None
        with tempfile.TemporaryDirectory(prefix="jointbench-run-") as tmp:
            model_ref, joint = _run_model(task, tmp)
            rate = {} if s.rate is None else {"sample_rate_hz": s.rate}
            result = run_experiment(model_ref, joint, duration=s.duration, seed=task.seed,
                                    amplitude=s.amplitude, effect=effect,
                                    sensors=_sensors(s, model_ref, joint), **rate)
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
            tm = time.perf_counter()
            try:
                chosen, mode = _filter(s, log)
                ident = identify(log, m, chosen, first_mode=mode)
                corr = corrected_sigmas(ident, log)
            except Exception as err:  # noqa: BLE001 - recorded in the row
                reasons.append(f"{m}: {type(err).__name__}: {err}")
                continue
            times[m] = time.perf_counter() - tm
            pre = ID_MODELS[m]
            for p in PARAMS[m]:
                row[f"{pre}.{p}"] = _fmt(ident.physical.get(p))
                row[f"{pre}.{p}.sigma"] = _fmt(ident.physical_sigma.get(p))
                row[f"{pre}.{p}.sigma_c"] = _fmt(corr.get(p))
            if m in debiased_models(s):
                tm = time.perf_counter()
                try:
                    d = debias(log, ident, replicas=s.debias, seed=task.seed)
                except Exception as err:  # noqa: BLE001 - recorded in the row
                    reasons.append(f"{m} bias correction: {type(err).__name__}: {err}")
                    continue
                for p in PARAMS[m]:
                    row[f"{pre}{DEBIASED}.{p}"] = _fmt(d.estimate.get(p))
                    row[f"{pre}{DEBIASED}.{p}.sigma_c"] = _fmt(d.sigma.get(p))
                    row[f"{pre}{DEBIASED}.{p}.sigma_r"] = _fmt(d.sigma_replicas.get(p))
                times[m + DEBIASED] = time.perf_counter() - tm
        identify_s = time.perf_counter() - t1
        if methods:
            seen = blind(log)
            for method in methods:
                _run_method(method, seen, timeout_s, row, times)
    if reasons:
        row["status"] = "failed"
        row["reason"] = " ".join("; ".join(reasons).split())  # one line
    return RunOutcome(task.index, row, sim_s, identify_s, times)


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
    times: dict[int, dict[str, float]] = field(default_factory=dict)  # run -> method -> s
    # (every run's times: this invocation's and those of resumed rows, from TABLE.times.csv)


def _check_methods(spec: CampaignSpec, methods: Sequence[Method], executor,
                   timeout_s: float) -> None:
    """The methods are the spec's, each named one imports in a host process within the
    deadline (bench.campaign.host.check_refs), and each can reach the executor's workers."""
    labels = [m.label for m in methods]
    if labels != method_labels(spec):
        raise ValueError(f"methods {labels} differ from the spec's {method_labels(spec)}")
    check_refs([m.ref for m in methods if m.ref is not None], timeout_s)
    if isinstance(executor, SerialExecutor):
        return
    for m in methods:
        try:
            pickle.dumps(m)
        except Exception:  # noqa: BLE001 - any pickling failure says the same
            raise CampaignError(f"method {m.label} ({m.source}) cannot be sent to worker "
                                "processes: define it in a module (MODULE:FUNCTION) or run "
                                "with one worker") from None


def _check_memory(spec: CampaignSpec, executor) -> None:
    """Before any run: one run per local process (this one, or each worker of a local pool)
    fits in the memory limit (bench.cli.resources: the longest run's samples at its rate, and
    the interpreter, per process). A Dask cluster's memory is its own. CampaignError in MB."""
    from jointbench.bench.cli.resources import check_memory

    if not isinstance(executor, (SerialExecutor, LocalExecutor)):
        return
    points = [spec.settings_at(p) for p in range(max(1, len(spec.values)))]
    s = max(points, key=lambda s: s.duration * (s.rate or SAMPLE_RATE_HZ))
    rate = s.rate or SAMPLE_RATE_HZ
    try:
        check_memory(s.duration * rate, f"duration {s.duration:g} s at {rate:g} Hz",
                     copies=executor.workers)
    except ValueError as err:
        raise CampaignError(str(err)) from None


def run_campaign(spec: CampaignSpec, table: str | Path, executor,
                 progress: Callable[[bool], None] | None = None,
                 methods: Sequence[Method] = (),
                 method_timeout: float = DEFAULT_TIMEOUT_S) -> CampaignResult:
    """Run the campaign's missing runs on `executor` (bench.executors), appending to `table`;
    when all are in, sort the table, write the times beside it (bench.campaign.times) and
    return the rows and summary. `methods` (those of
    `spec`, bench.campaign.methods.with_methods) run on every log, each call under a deadline
    of `method_timeout` s."""
    try:
        method_timeout = check_timeout(method_timeout)
    except ValueError as err:
        raise CampaignError(str(err)) from None
    _check_memory(spec, executor)
    _check_methods(spec, methods, executor, method_timeout)
    tab = CampaignTable(Path(table), spec, expected=expected_of(spec))
    resumed = len(tab.rows)
    pending = [spec.task(i) for i in range(spec.total) if i not in tab.rows]
    sim_s: list[float] = []
    identify_s: list[float] = []
    times = {i: t for i, t in read_times(times_path(Path(table))).items() if i in tab.rows} \
        if resumed else {}
    task = partial(run_task_with, tuple(methods), float(method_timeout))
    t0 = time.perf_counter()
    try:
        for done in executor.map_unordered(task, pending):
            outcome = done.value if done.error is None else lost_outcome(done.item, done.error)
            tab.append(outcome.row)
            if math.isfinite(outcome.sim_s):
                sim_s.append(outcome.sim_s)
            if math.isfinite(outcome.identify_s):
                identify_s.append(outcome.identify_s)
            times[outcome.index] = outcome.times
            if progress is not None:
                progress(outcome.row["status"] == "ok")
    finally:
        tab.close()
        close_hosts()
    wall = time.perf_counter() - t0
    tab.finalize()
    write_times(times_path(Path(table)), times)
    rows = [tab.rows[i] for i in sorted(tab.rows)]
    return CampaignResult(spec=spec, rows=rows, summary=summarize(spec, rows, times=times),
                          resumed=resumed, new=len(pending), wall_s=wall, sim_s=sim_s,
                          identify_s=identify_s, times=times)
