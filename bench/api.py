"""The public Python API, for a notebook or a script (re-exported by `import jointbench`):

    import jointbench as jb
    log = jb.simulate("prototype", seed=1)     # a virtual experiment's Log
    fit = jb.identify(log)                     # fit.table(), fit.to_json(), fit.plot()
    d = jb.diagnose(log); d.write("out/")
    c = jb.campaign(runs=20, methods=["mymodule:estimate"], require="K.abs_bias_pct<1")
    print(c.table()); c.passed                 # every method side by side, the gates

Computations return frozen dataclasses; their text, JSON, figures and files come from the
presentation layer (`bench.present`, `bench.analysis.diagnose.report`), as on the command line.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

from jointbench.bench.analysis.diagnose import Diagnosis, summary_text
from jointbench.bench.analysis.diagnose import diagnose as diagnose_log
from jointbench.bench.analysis.diagnose import write as write_diagnosis
from jointbench.bench.api_args import check, output_path, path_like
from jointbench.bench.campaign.compare import entries
from jointbench.bench.campaign.executors import make_executor
from jointbench.bench.campaign.gates import (GateResult, check_gates, evaluate, gates_text,
                                             parse_gates)
from jointbench.bench.campaign.methods import (DEFAULT_TIMEOUT_S, Method, methods_of,
                                               with_methods)
from jointbench.bench.campaign.run import run_campaign
from jointbench.bench.campaign.settings import CampaignError, RunSettings
from jointbench.bench.campaign.spec import CampaignSpec
from jointbench.bench.campaign.summary import summary_text as campaign_text
from jointbench.bench.effects import HiddenEffect, parse_effects
from jointbench.bench.present.identify import identify_json, identify_text
from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.checks import estimate_flags
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.identify import Identification
from jointbench.identification.identify import identify as identify_log
from jointbench.bench.output import write_log
from jointbench.identification.log import Log, read_log, unit_warnings
from jointbench.identification.output import finite_json
from jointbench.identification.plots import plot_validation

if TYPE_CHECKING:
    import matplotlib.figure

__all__ = ["Fit", "DiagnosisResult", "Log", "simulate", "identify", "diagnose", "read_log",
           "write_log", "campaign", "CampaignReport"]

LogLike = Log | str | os.PathLike


def _as_log(log: LogLike) -> Log:
    return log if isinstance(log, Log) else read_log(log)


def simulate(model: str | os.PathLike = "prototype", joint: str | None = None, *,
             duration: float = 60.0, seed: int = 0, effect: str | HiddenEffect | None = None,
             **options) -> Log:
    """One virtual closed-loop chirp experiment on `model` (prototype, arm6 or an MJCF file
    following the axis convention), as a Log (docs/log-format.md; its truth in `log.truth()`).
    `duration` [s]; `effect` a hidden effect, e.g. "backlash=0.002", or several, "offset=5,backlash=0.002"
    (docs/effects.md);
    `options` go to `bench.sim.experiment.run_experiment` (amplitude, config, lock, sensors,
    sample_rate_hz, ...). Raises SimulationError, ModelStructureError, ValueError."""
    check("simulate", locals())
    if isinstance(effect, str):
        effect = parse_effects(effect)   # one or several: "offset=5,backlash=0.002"
    return run_experiment(model, joint, duration=duration, seed=seed, effect=effect,
                          **options).log


@dataclass(frozen=True)
class Fit:
    """An identification of a log (`identify`): `result` the estimator's answer, `truth` the
    log's ground truth (None for measured data), `flags` and `warnings` on the estimate and
    the log's units."""

    log: Log
    result: Identification
    truth: dict[str, float] | None
    flags: tuple[dict, ...]
    warnings: tuple[str, ...]

    @property
    def model(self) -> str:
        return self.result.model

    @property
    def parameters(self) -> dict[str, float]:
        """The physical parameters (SI, joint side)."""
        return dict(self.result.physical)

    @property
    def sigma(self) -> dict[str, float]:
        """Their standard deviations (the paper's, white residuals)."""
        return dict(self.result.physical_sigma)

    def table(self) -> str:
        """The text `jointbench identify` prints."""
        return identify_text(str(self.log.path or "log"), self.log, self.result, self.truth,
                             list(self.flags))

    def to_json(self) -> dict:
        """The `identify --json` object (docs/cli.md), strict JSON (NaN as null)."""
        return finite_json(identify_json(self.result, self.truth, list(self.flags),
                                         list(self.warnings)))

    def plot(self, path: str | os.PathLike | None = None) -> matplotlib.figure.Figure:
        """The direct validation (paper's Figure 2): measured and predicted torque; saved
        atomically to `path` when given. pyplot is used: pick the backend first."""
        output_path("path", path)
        r = self.result
        rows = r.block == 0
        return plot_validation(r.t[rows], r.y[rows], r.y_pred[rows], r.relative_error_pct,
                               path, title=f"Direct validation, {r.model} model",
                               unit="N" if r.prismatic else "N m")


def identify(log: LogLike, model: str = "auto", settings: FilterSettings | None = None, *,
             f1_hz: float | None = None) -> Fit:
    """Identify the axis parameters of `log` (a Log or a log file) with `model`
    (joint-motor, motor-only, motor-only-printed, rigid or auto; paper eqs. 13, 18-20, 6).
    Raises LogError, NotIdentifiable, InversionError (ValueErrors)."""
    check("identify", locals())
    log = _as_log(log)
    result = identify_log(log, model, settings, f1_hz=f1_hz)
    flags = estimate_flags(result.physical, result.physical_sigma, log.prismatic)
    return Fit(log, result, log.truth() or None, tuple(flags), tuple(unit_warnings(log)))


@dataclass(frozen=True)
class DiagnosisResult:
    """What the simulation gets wrong on a log (`diagnose`): the named causes, the extended
    model and its gain; `diagnosis` holds everything the analysis found."""

    diagnosis: Diagnosis

    @property
    def named_cause(self) -> str:
        return self.diagnosis.named_cause

    @property
    def files(self) -> tuple[str, ...]:
        return self.diagnosis.files

    def table(self) -> str:
        """The text `jointbench diagnose` prints."""
        return summary_text(self.diagnosis)

    def to_json(self) -> dict:
        """The `diagnose --json` object (docs/cli.md)."""
        return self.diagnosis.to_json()

    def write(self, out: str | os.PathLike,
              progress: Callable[[str], None] | None = None) -> DiagnosisResult:
        """Write figures, report.md, diagnosis.json and the models into folder `out`
        (created); the result with the files written."""
        path_like("out", out)
        done = write_diagnosis(self.diagnosis, Path(out), progress or (lambda msg: None))
        return dataclasses.replace(self, diagnosis=done)


def diagnose(log: LogLike, forward: bool = True,
             progress: Callable[[str], None] | None = None) -> DiagnosisResult:
    """Diagnose `log` (a Log or a log file) against its own nominal model: the candidate
    effects, the named causes, the extended model, its gain in the inverse and (with
    `forward`) the closed-loop forward views. Writes nothing (see DiagnosisResult.write)."""
    check("diagnose", locals())
    return DiagnosisResult(diagnose_log(_as_log(log), forward=forward, progress=progress))


@dataclass(frozen=True)
class CampaignReport:
    """A finished campaign (`campaign`): `summary` (the `campaign --json` object: Monte Carlo
    statistics per model, `comparison` of every method side by side, `timing`), `rows` the
    table's rows, `gates` the accuracy gates checked, `table_path` the CSV (None: not kept),
    `times` run -> method -> wall time of the call [s]."""

    summary: dict
    rows: tuple[dict[str, str], ...]
    gates: tuple[GateResult, ...]
    table_path: str | None
    wall_s: float
    times: dict[int, dict[str, float]] = dataclasses.field(default_factory=dict)

    @property
    def passed(self) -> bool:
        """Every gate passed (True without gates)."""
        return all(g.passed for g in self.gates)

    @property
    def comparison(self) -> list[dict]:
        """Per sweep point, every method's counts, time and per-parameter statistics."""
        return self.summary["comparison"]

    def table(self) -> str:
        """The text `jointbench campaign` prints: statistics, methods side by side, gates."""
        text = campaign_text(self.summary, True)
        return text + ("\n\n" + gates_text(list(self.gates)) if self.gates else "")

    def to_json(self) -> dict:
        """The `campaign --json` object, strict JSON (NaN as null)."""
        return finite_json(self.summary)


def campaign(model: str | os.PathLike = "prototype", joint: str | None = None, *,
             runs: int = 50, seed: int = 0, duration: float = 60.0,
             methods: Sequence[str | Callable[[Log], dict] | Method]
             | dict[str, str | Callable[[Log], dict]] = (),
             method_timeout: float = DEFAULT_TIMEOUT_S, require: str | Sequence[str] | None = None,
             id_models: Sequence[str] = ("joint-motor", "motor-only"),
             sweep: tuple[str, Sequence[float]] | None = None, workers: int | None = None,
             scheduler: str | None = None, out: str | os.PathLike | None = None,
             **settings) -> CampaignReport:
    """`runs` virtual experiments on `model`, each identified by the built-in `id_models` and
    by every plug-in of `methods` (callables of a Log returning {name: value} or {name: (value,
    sigma)} with the paper's names, or "MODULE:FUNCTION" texts; a {label: method} dict names
    them; bench/campaign/methods.py),
    each call under a deadline of `method_timeout` s; then the accuracy gates `require`
    (docs/cli.md grammar, e.g. "K.abs_bias_pct<0.5, failed==0"). `settings`: the other
    RunSettings (amplitude, noise, motor_bits, link_bits, scatter, wn, Nd, stencil, effect,
    debias); `sweep` (NAME, values). The table goes to `out` (resumed when it exists) or to a
    temporary file. `workers` local processes (default all cores; 1: this process, needed for
    a callable that is not importable, e.g. a lambda). Raises CampaignError (a ValueError) for
    bad input, before any run."""
    check("campaign", locals())
    allowed = {f.name for f in dataclasses.fields(RunSettings)} - {"model", "joint", "duration",
                                                                  "id_models"}
    unknown = sorted(set(settings) - allowed)
    if unknown:
        raise CampaignError(f"campaign: unknown setting(s) {', '.join(unknown)} "
                            f"(known: {', '.join(sorted(allowed))})")
    base = RunSettings(model=str(model), joint=joint, duration=duration,
                       id_models=tuple(id_models), **settings)
    name, values = sweep if sweep is not None else (None, ())
    chosen = methods_of(methods)
    spec = with_methods(CampaignSpec(base=base, runs=runs, seed=seed, sweep=name,
                                     values=tuple(float(v) for v in values)), chosen)
    gates = parse_gates(require)
    check_gates(gates, entries(spec))
    executor = make_executor(workers, scheduler)
    try:
        with tempfile.TemporaryDirectory(prefix="jointbench-campaign-") as tmp:
            table = Path(out) if out is not None else Path(tmp) / "campaign.csv"
            result = run_campaign(spec, table, executor, methods=chosen,
                                  method_timeout=method_timeout)
    finally:
        executor.close()
    summary = dict(result.summary)
    results = evaluate(gates, summary["comparison"])
    summary["gates"] = [r.as_dict() for r in results]
    summary["timing"] = {"engine": executor.description, "wall_s": result.wall_s,
                         "runs_this_invocation": result.new, "resumed_rows": result.resumed}
    return CampaignReport(summary, tuple(result.rows), tuple(results),
                          str(out) if out is not None else None, result.wall_s, result.times)
