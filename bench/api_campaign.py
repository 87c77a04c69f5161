"""`jointbench.campaign` and `jointbench.survey`: many virtual experiments, each identified,
with every option of `jointbench campaign` and `jointbench survey`, as one CampaignReport or
SurveyResult (bench.results)."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Callable, Sequence

from jointbench.bench.api_args import check
from jointbench.bench.campaign.compare import entries
from jointbench.bench.campaign.gates import check_gates, parse_gates
from jointbench.bench.campaign.methods import DEFAULT_TIMEOUT_S, Method, methods_of, with_methods
from jointbench.bench.campaign.session import ProgressFactory, run_report
from jointbench.bench.campaign.settings import SWEEPABLE, CampaignError, RunSettings
from jointbench.bench.campaign.spec import CampaignSpec
from jointbench.bench.results.campaign import CampaignReport
from jointbench.bench.results.survey import SurveyResult
from jointbench.identification.log import Log


_FLOAT_SETTINGS = ("amplitude", "noise", "scatter", "wn", "rate")


def campaign(model: str | os.PathLike = "prototype", joint: str | None = None, *,
             runs: int = 50, seed: int = 0, duration: float = 60.0,
             methods: Sequence[str | Callable[[Log], dict] | Method]
             | dict[str, str | Callable[[Log], dict]] = (),
             method_timeout: float = DEFAULT_TIMEOUT_S, require: str | Sequence[str] | None = None,
             id_models: Sequence[str] = ("joint-motor", "motor-only"),
             sweep: tuple[str, Sequence[float]] | None = None, workers: int | None = None,
             scheduler: str | None = None, out: str | os.PathLike | None = None,
             junit: str | os.PathLike | None = None,
             progress: ProgressFactory | None = None, **settings) -> CampaignReport:
    """Monte Carlo campaign of virtual experiments, each identified (`jointbench campaign`).

    Parameters
    ----------
    model : str or PathLike
        prototype, arm6 or an MJCF file following the axis convention.
    joint : str, optional
        The axis to move (default: the first).
    runs : int
        Runs (per sweep value with `sweep`).
    seed : int
        Campaign seed; each run's seed derives from it.
    duration : float
        Experiment length [s].
    methods : sequence or dict
        Plug-in estimators run on every log beside the built-in models: callables of a Log
        returning {name: value} or {name: (value, sigma)} with the paper's names, or
        "[LABEL=]MODULE:FUNCTION" texts; a {label: method} dict names them
        (bench/campaign/methods.py).
    method_timeout : float
        Deadline of one plug-in call [s].
    require : str or sequence of str, optional
        Accuracy gates (docs/cli.md grammar), e.g. "K.abs_bias_pct<0.5, failed==0".
    id_models : sequence of str
        The built-in identification models.
    sweep : (str, sequence of float), optional
        One setting swept: (NAME, values).
    workers : int, optional
        Local processes (default: all cores; 1: this process, needed for a callable that
        cannot be imported by name, e.g. a lambda).
    scheduler : str, optional
        An existing Dask cluster, tcp://HOST:PORT.
    out : str or PathLike, optional
        The table (resumed when it holds the same campaign), with its summaries beside it;
        default: a temporary file, not kept.
    junit : str or PathLike, optional
        Write the gates as a JUnit report (needs `require`).
    progress : callable, optional
        Called once before the runs as (total, already in the table, engine); returns the
        callback called after each run with its success, or None.
    **settings
        The other RunSettings: amplitude, rate, noise, motor_bits, link_bits, scatter, wn,
        Nd, stencil, effect, debias.

    Returns
    -------
    CampaignReport
        `summary`, `passed`, `comparison`; `table()`, `to_json()`.

    Raises
    ------
    CampaignError
        Bad input (a ValueError), before any run.

    Examples
    --------
    >>> import jointbench as jb
    >>> c = jb.campaign(runs=4, duration=10, require="K.abs_bias_pct<5")   # doctest: +SKIP
    >>> c.passed                                                          # doctest: +SKIP
    """
    check("campaign", locals())
    allowed = {f.name for f in dataclasses.fields(RunSettings)} - {"model", "joint", "duration",
                                                                  "id_models"}
    unknown = sorted(set(settings) - allowed)
    if unknown:
        raise CampaignError(f"campaign: unknown setting(s) {', '.join(unknown)} "
                            f"(known: {', '.join(sorted(allowed))})")
    # floats as floats: the table's spec line (and so its resumption) must not depend on
    # whether 10 or 10.0 was written
    settings = {k: float(v) if k in _FLOAT_SETTINGS and v is not None else v
                for k, v in settings.items()}
    base = RunSettings(model=str(model), joint=joint, duration=float(duration),
                       id_models=tuple(id_models), **settings)
    name, values = sweep if sweep is not None else (None, ())
    kind = SWEEPABLE.get(name, float) if name is not None else float
    chosen = methods_of(methods)
    spec = with_methods(CampaignSpec(base=base, runs=runs, seed=seed, sweep=name,
                                     values=tuple(kind(v) for v in values)), chosen)
    gates = parse_gates(require)
    check_gates(gates, entries(spec))
    return run_report(spec, chosen, gates, out, workers=workers, scheduler=scheduler,
                      method_timeout=method_timeout, junit=junit, progress=progress)


def survey(model: str | os.PathLike = "arm6", joints: Sequence[str] | None = None, *,
           duration: float = 60.0, seed: int = 0, workers: int | None = None,
           out: str | os.PathLike | None = None,
           progress: Callable[..., None] | None = None) -> SurveyResult:
    """Every axis of a robot in turn, the others locked (`jointbench survey`).

    Each axis: the chirp experiment, its identification with the defaults, the estimates
    against the truth (bench.campaign.robot_survey).

    Parameters
    ----------
    model : str or PathLike
        arm6, prototype or an MJCF file following the axis convention.
    joints : sequence of str, optional
        The axes, by name or index from 1 (default: every axis).
    duration : float
        Chirp experiment per axis [s].
    seed : int
        Noise seed, the same for every axis.
    workers : int, optional
        Processes, one axis each (default: every core, at most one per axis; 1: this process).
    out : str or PathLike, optional
        Folder for survey.csv, survey.png and logs/AXIS.csv, checked before any run and
        written all or nothing; nothing is written when None.
    progress : callable, optional
        Called as (axis result, done, total) after each axis.

    Returns
    -------
    SurveyResult
        `survey`, `failed`; `table()`, `to_json()`.

    Raises
    ------
    ModelStructureError
        The model does not follow the axis convention, or no such axis.
    ValueError
        A bad option.

    Examples
    --------
    >>> import jointbench as jb
    >>> s = jb.survey("arm6", ["axis1"], duration=10)   # doctest: +SKIP
    """
    # argument checks: here, before any run
    from jointbench.bench.campaign.robot_survey import run_survey, survey_axes
    from jointbench.bench.cli.resources import check_survey_memory
    from jointbench.bench.output_files import OutputFolder
    from jointbench.bench.present.survey import FILES, write_survey
    from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ

    chosen = None if joints is None else list(joints)
    _, names = survey_axes(model, chosen)       # ModelStructureError before any work
    folder = None if out is None else OutputFolder(Path(out), FILES)
    check_survey_memory(len(names), duration, SAMPLE_RATE_HZ, workers)
    sv = run_survey(model, chosen, duration=duration, seed=seed, workers=workers,
                    progress=progress)
    if folder is not None:
        with folder.writing() as path:
            write_survey(sv, path)
    return SurveyResult(sv, None if out is None else Path(out))
