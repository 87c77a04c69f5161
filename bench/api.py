"""The public Python API, for a notebook or a script (re-exported by `import jointbench`):

    import jointbench as jb
    log = jb.simulate("prototype", seed=1)     # a virtual experiment's Log
    fit = jb.identify(log)                     # fit.table(), fit.to_json(), fit.plot()
    fit.parameters["K"]                        # Estimate(value, sigma, sigma_hac, unit)
    d = jb.diagnose(log); d.write("out/")
    c = jb.campaign(runs=20, methods=["mymodule:estimate"], require="K.abs_bias_pct<1")
    print(c.table()); c.passed                 # every method side by side, the gates

Every function takes the options of the `jointbench` command of the same name, and returns a
frozen dataclass (bench.results) whose `table()` and `to_json()` are what that command prints:
the command line parses its arguments, calls these and prints the result.
"""

from __future__ import annotations

import dataclasses
import math
import os
from pathlib import Path
from typing import Callable, Sequence

from jointbench.bench.campaign.compare import entries
from jointbench.bench.campaign.gates import check_gates, parse_gates
from jointbench.bench.campaign.methods import DEFAULT_TIMEOUT_S, Method, methods_of, with_methods
from jointbench.bench.campaign.session import ProgressFactory, run_report
from jointbench.bench.campaign.settings import SWEEPABLE, CampaignError, RunSettings
from jointbench.bench.campaign.spec import CampaignSpec
from jointbench.bench.effects import HiddenEffect, parse_effects
from jointbench.bench.results import (CampaignReport, DiagnosisResult, Estimate, Fit,
                                      ImportReport, SurveyResult)
from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.checks import estimate_flags
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.identify import identify as identify_log
from jointbench.identification.log import Log, read_log, unit_warnings, write_log

__all__ = ["Estimate", "Fit", "DiagnosisResult", "CampaignReport", "SurveyResult",
           "ImportReport", "Log", "simulate", "identify", "diagnose", "campaign", "survey",
           "import_log", "read_log", "write_log"]

LogLike = Log | str | os.PathLike


def _as_log(log: LogLike) -> Log:
    return log if isinstance(log, Log) else read_log(log)


def _source(log: LogLike, loaded: Log) -> str:
    """The log's name in reports: the path as given, else the Log's own, else "log"."""
    return str(log) if not isinstance(log, Log) else str(loaded.path or "log")


def simulate(model: str | os.PathLike = "prototype", joint: str | None = None, *,
             duration: float = 60.0, seed: int = 0, effect: str | HiddenEffect | None = None,
             **options) -> Log:
    """One virtual closed-loop chirp experiment, as a log (`jointbench simulate`).

    Parameters
    ----------
    model : str or PathLike
        prototype, arm6 or an MJCF file following the axis convention.
    joint : str, optional
        The axis to move, by name or index from 1 (default: the first).
    duration : float
        Length of the experiment [s].
    seed : int
        Noise seed: same seed, same log, bit for bit.
    effect : str or HiddenEffect, optional
        A hidden effect, e.g. "backlash=0.002", or several, "offset=5,backlash=0.002"
        (docs/effects.md).
    **options
        The other options of `bench.sim.experiment.run_experiment` (amplitude, config, lock,
        sensors, sample_rate_hz, ...).

    Returns
    -------
    Log
        The experiment's log (docs/log-format.md); its ground truth in `log.truth()`.

    Raises
    ------
    SimulationError
        The closed loop diverged.
    ModelStructureError
        The model does not follow the axis convention.
    ValueError
        A bad option or effect.

    Examples
    --------
    >>> import jointbench as jb
    >>> log = jb.simulate("prototype", seed=1, duration=10)   # doctest: +SKIP
    """
    if isinstance(effect, str):
        effect = parse_effects(effect)   # one or several: "offset=5,backlash=0.002"
    return run_experiment(model, joint, duration=duration, seed=seed, effect=effect,
                          **options).log


def _check_band(log: Log, wn: float, flag: str, value: float) -> None:
    """ValueError unless the Butterworth frequency `wn` [rad/s] lies in [2 pi / duration,
    pi Fs): at least one cycle over the log, below the Nyquist frequency."""
    duration = float(log.t[-1] - log.t[0])
    lo, hi = 2 * math.pi / duration, math.pi * log.sample_rate_hz
    if not lo <= wn < hi:
        raise ValueError(f"{flag} {value:g}: the Butterworth frequency must lie in "
                         f"[{lo:.3g}, {hi:.4g}) rad/s: at least one cycle over the "
                         f"{duration:.3g} s log, below the Nyquist frequency")


def _filter_settings(log: Log, wn: float | None, order: int, Nd: int | None, chain: dict,
                     f1_hz: float | None):
    """(FilterSettings, first mode) overriding the chosen filter (identification.defaults
    .choose_filter: eqs. 28-29 from the log's first mode, or `f1_hz`) with the options given;
    (None, None) when every option is at its default (identify then chooses the band)."""
    from jointbench.identification.defaults import choose_filter

    if wn is None and Nd is None and order == 4 and \
            chain == {"zoh": True, "filter_torque": True, "skip": 0, "stencil": None}:
        return None, None
    choice = choose_filter(log, f1_hz)   # what the options override, and the first mode
    base = choice.settings
    chain = {**chain, "stencil": chain["stencil"] or base.stencil}
    settings = FilterSettings(wn=wn if wn is not None else base.wn, m=order,
                              Nd=Nd if Nd is not None else base.Nd, ts=log.ts, **chain)
    return settings, choice.first_mode


def identify(log: LogLike, model: str = "auto", settings: FilterSettings | None = None, *,
             wn: float | None = None, fc_hz: float | None = None, order: int = 4,
             Nd: int | None = None, skip: int = 0, zoh: bool = True,
             filter_torque: bool = True, stencil: int | None = None,
             f1_hz: float | None = None, refine: bool = False,
             refine_max_nfev: int | None = None, debias: int | None = None,
             friction_timeconst: float | None = None, validate: LogLike | None = None,
             progress: Callable[[str], None] | None = None,
             replica_progress: Callable[[int, int], None] | None = None,
             warn: Callable[[str], None] | None = None) -> Fit:
    """Identify the axis parameters of a log (`jointbench identify`; paper eqs. 13, 18-20, 6).

    Parameters
    ----------
    log : Log, str or PathLike
        The log, or its file (docs/log-format.md).
    model : str
        joint-motor (eq. 13), motor-only (eqs. 18-20), motor-only-printed (eq. 18 as
        printed), rigid (eq. 6 with q = qm) or auto (joint-motor when q is logged, else
        motor-only; rigid when the data do not identify a stiffness).
    settings : FilterSettings, optional
        The whole filter chain; default: chosen from the log's first mode (eqs. 28-29).
    wn : float, optional
        Butterworth frequency [rad/s], overriding the chosen one (`--wn`).
    fc_hz : float, optional
        The same in Hz (`--fc`); give `wn` or `fc_hz`, not both.
    order : int
        Butterworth order m (`--order`).
    Nd : int, optional
        Decimation factor, overriding the chosen one (`--decimate`).
    skip : int
        Samples dropped after filtering, before decimation (`--skip`).
    zoh : bool
        Rigid model: pair the torque with the positions through the zero-order-hold
        alignment (False: `--no-zoh`).
    filter_torque : bool
        Rigid model: the torque goes through the Butterworth too (False:
        `--no-torque-filter`).
    stencil : {3, 5}, optional
        Central-difference points: 3, the paper's eq. (22), or 5 (default: from f1 / Fs).
    f1_hz : float, optional
        The first mode [Hz], to design wn and Nd from (default: measured on the log).
    refine : bool
        Continue by closed-loop output error (bench.analysis.refine; needs q_ref and gains).
    refine_max_nfev : int, optional
        Residual evaluations allowed to the refinement (each one replay).
    debias : int, optional
        Bias-correct by this many closed-loop replicas (bench.analysis.debias; needs q_ref,
        the gains and the sensor metadata).
    friction_timeconst : float, optional
        Debias: the nominal axis' Coulomb friction time constant [s] (default: the log's).
    validate : Log, str or PathLike, optional
        Another log, predicted by the identified model (inverse and forward views).
    progress : callable, optional
        Called with a line of refinement progress.
    replica_progress : callable, optional
        Called as (done, total) after each bias-correction replica.
    warn : callable, optional
        Called with each warning as it arises (the same lines end in `Fit.warnings`).

    Returns
    -------
    Fit
        `parameters` {name: Estimate(value, sigma, sigma_hac, unit)}, `warnings`, `notes`,
        `flags`; `table()`, `to_json()`, `plot()`.

    Raises
    ------
    LogError
        An unusable log (missing column, too few samples, mostly clipped torque).
    NotIdentifiable, InversionError
        The data do not determine the model's parameters.
    DebiasError
        `debias` on a log without the sensor metadata.
    ValueError
        A bad option (LogError, NotIdentifiable, InversionError and DebiasError are
        ValueErrors too).

    Examples
    --------
    >>> import jointbench as jb
    >>> fit = jb.identify(jb.simulate(seed=1, duration=20))   # doctest: +SKIP
    >>> fit.parameters["K"].sigma_hac                         # doctest: +SKIP
    """
    # argument checks: here, before any reading
    from jointbench.identification.physical import InversionError
    from jointbench.identification.saturation import clipping_warnings
    from jointbench.identification.sanity import sanity_warnings

    say = warn or (lambda text: None)
    loaded = _as_log(log)
    source = _source(log, loaded)
    other = None if validate is None else _as_log(validate)
    warnings = unit_warnings(loaded) + clipping_warnings(loaded)
    for text in warnings:
        say(text)
    if refine or debias is not None:
        from jointbench.bench.analysis.refine import require_replayable
        require_replayable(loaded)  # before the least squares: no half answer
    if debias is not None:
        from jointbench.bench.analysis.debias import DebiasError
        from jointbench.bench.sim.sensors import Sensors
        if Sensors.from_log(loaded) is None:
            raise DebiasError(f"{source}: --debias replays the experiment with the log's "
                              "sensors: the metadata needs motor_encoder_resolution_rad, "
                              "link_encoder_resolution_rad and torque_noise_std")
    if fc_hz is not None and wn is not None:
        raise ValueError("give the Butterworth frequency once: wn (rad/s) or fc_hz (Hz)")
    mode = None
    if settings is None:
        chain = {"zoh": zoh, "filter_torque": filter_torque, "skip": skip, "stencil": stencil}
        band = wn if fc_hz is None else 2 * math.pi * fc_hz
        if band is not None:
            _check_band(loaded, band, "--wn" if fc_hz is None else "--fc",
                        wn if fc_hz is None else fc_hz)
        settings, mode = _filter_settings(loaded, band, order, Nd, chain, f1_hz)
    try:
        result = identify_log(loaded, model, settings, f1_hz=f1_hz, first_mode=mode)
    except InversionError as err:
        raise InversionError(f"{source}: {err}") from None
    flags = estimate_flags(result.physical, result.physical_sigma, loaded.prismatic)
    refined = debiased = validation = forward = None
    if refine:
        from jointbench.bench.analysis.refine import refine as refine_fit
        refined = refine_fit(loaded, result, max_nfev=refine_max_nfev, progress=progress)
    if debias is not None:
        from jointbench.bench.analysis.debias import debias as debias_fit
        debiased = debias_fit(loaded, result, replicas=debias, progress=replica_progress,
                              friction_timeconst=friction_timeconst)
    if other is not None:
        from jointbench.bench.present.validate import forward_validation
        from jointbench.identification.validate import validate_on
        validation = validate_on(result, other, f1_hz)
        forward = forward_validation(result, loaded, other)
    for text in sanity_warnings(result, loaded):   # mislabelled, too short, explains too little
        say(text)
        warnings.append(text)
    return Fit(loaded, result, loaded.truth() or None, tuple(flags), tuple(warnings),
               source=source, refined=refined, debiased=debiased, validation=validation,
               forward=forward, validate_source=None if validate is None else (
                   _source(validate, other)))


def diagnose(log: LogLike, forward: bool = True,
             progress: Callable[[str], None] | None = None, *,
             model: str | os.PathLike | None = None, joint: str | None = None,
             config: dict[str, float] | None = None, validate: LogLike | None = None,
             disturbance_column: str | None = None, disturbance_gain: float = 1.0,
             disturbance_at: str = "link", out: str | os.PathLike | None = None,
             warn: Callable[[str], None] | None = None) -> DiagnosisResult:
    """What the simulation gets wrong on a log (`jointbench diagnose`).

    Against the log's own nominal model: the candidate effects, the named causes, the
    extended model and its gain in the inverse and (with `forward`) the closed-loop forward
    views. With `model`, against the user's MJCF: its parameter errors, the corrected and
    extended models.

    Parameters
    ----------
    log : Log, str or PathLike
        The log, or its file (docs/log-format.md).
    forward : bool
        Run the closed-loop replays (forward view); False: `--no-forward`.
    progress : callable, optional
        Called with one line per step.
    model : str or PathLike, optional
        An MJCF (prototype, arm6 or a file following the axis convention) to compare with.
    joint : str, optional
        With `model`: the axis the log moves (default: the log's joint metadata).
    config : dict of str to float, optional
        With `model`: locked angles of the other axes [rad] (default: the log's).
    validate : Log, str or PathLike, optional
        Another log: cross-validation of the models identified on `log`.
    disturbance_column : str, optional
        A column of the `validate` log applied as a disturbance in its replay.
    disturbance_gain : float
        Scale of the disturbance column (e.g. N/V).
    disturbance_at : {"link", "motor"}
        Where the disturbance acts.
    out : str or PathLike, optional
        Folder for figures, report.md, diagnosis.json and the models; checked before any
        computation, written all or nothing.
    warn : callable, optional
        Called with each warning on the log (units, clipped torque).

    Returns
    -------
    DiagnosisResult
        `named_cause`, `warnings`, `files`; `table()`, `to_json()`, `write()`.

    Raises
    ------
    LogError
        An unusable log, or no such disturbance column.
    ModelStructureError
        `model` does not follow the axis convention.
    ValueError
        A bad option (LogError and ModelStructureError are ValueErrors too).

    Examples
    --------
    >>> import jointbench as jb
    >>> d = jb.diagnose(jb.simulate(seed=1, effect="backlash=0.002"))   # doctest: +SKIP
    >>> d.named_cause                                                   # doctest: +SKIP
    """
    # argument checks: here, before any reading
    from jointbench.identification.log import LogError
    from jointbench.identification.saturation import clipping_warnings

    say = progress or (lambda msg: None)
    loaded = _as_log(log)
    source = _source(log, loaded)
    clipping_warnings(loaded)   # LogError over a third, before any computation
    folder = None if out is None else Path(out)
    if folder is not None:
        if model is not None:
            from jointbench.bench.analysis.diagnose.model_report import output_folder
        else:
            from jointbench.bench.analysis.diagnose.report import output_folder
        output_folder(folder)
    other = None if validate is None else _as_log(validate)
    if other is not None and not isinstance(log, Log) and not isinstance(validate, Log) \
            and Path(validate).resolve() == Path(log).resolve():
        raise ValueError("--validate must name another log than FILE (cross-validation)")
    if model is not None:
        from jointbench.bench.analysis.diagnose.against_model import diagnose_against_model
        md = diagnose_against_model(loaded, model, joint, config or {}, forward=forward,
                                    validate=other, progress=say)
        result = DiagnosisResult(md, source=source)
        return result if folder is None else result.write(folder, say)
    from jointbench.bench.analysis.diagnose import cross_validate
    from jointbench.bench.analysis.diagnose import diagnose as diagnose_log
    from jointbench.bench.analysis.diagnose.run import diagnosis_settings

    dist = None
    if disturbance_column is not None:
        if other is None:
            raise ValueError("--disturbance-column applies to the --validate log")
        if disturbance_column not in other.extra:
            raise LogError(f"no column '{disturbance_column}' (columns: "
                           f"{', '.join(['t', 'q_m', 'tau_m', *other.extra])})", other.path,
                           column=disturbance_column)
        dist = disturbance_gain * other.extra[disturbance_column]
    d = diagnose_log(loaded, forward=forward, progress=say)
    for text in d.warnings:   # units, clipped torque (left out of the fits)
        (warn or (lambda text: None))(text)
    xval, validate_source = None, None
    if other is not None:
        validate_source = _source(validate, other)
        say(f"cross-validation on {validate_source} (its own band)")
        xval = cross_validate(d, other, dist, disturbance_at, diagnosis_settings(other)[0])
    result = DiagnosisResult(d, xval, source, validate_source)
    return result if folder is None else result.write(folder, say)


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
    # argument checks: here, before any run
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
    against the truth (bench.campaign.survey).

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
    from jointbench.bench.campaign.survey import run_survey, survey_axes
    from jointbench.bench.cli.resources import check_memory
    from jointbench.bench.output import OutputFolder
    from jointbench.bench.present.survey import FILES, write_survey
    from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ

    chosen = None if joints is None else list(joints)
    _, names = survey_axes(model, chosen)       # ModelStructureError before any work
    folder = None if out is None else OutputFolder(Path(out), FILES)
    check_memory(len(names) * duration * SAMPLE_RATE_HZ,
                 f"--duration {duration:g} s on {len(names)} axes")
    sv = run_survey(model, chosen, duration=duration, seed=seed, workers=workers,
                    progress=progress)
    if folder is not None:
        with folder.writing() as path:
            write_survey(sv, path)
    return SurveyResult(sv, None if out is None else Path(out))


def import_log(file: str | os.PathLike, out: str | os.PathLike | None = None, *,
               columns: dict[str, str] | None = None, units: dict[str, str] | None = None,
               gear_ratio: float | None = None,
               motor_side: Sequence[str] = ("q_m", "tau_m", "q_ref"),
               counts_per_turn: float | None = None,
               link_counts_per_turn: float | None = None,
               torque_constant: float | None = None, rate_hz: float | None = None,
               meta: dict[str, str] | None = None, gains_side: str = "joint",
               delimiter: str | None = None) -> ImportReport:
    """Convert a measured file into a jointbench log (`jointbench import`).

    Parameters
    ----------
    file : str or PathLike
        The raw CSV: a header row, then one row of numbers per sample.
    out : str or PathLike, optional
        The log file to write (never the input; checked before reading); not written when
        None.
    columns : dict of str to str, optional
        Log column -> raw column, e.g. {"t": "time_ms", "q_m": "motor_counts"} (default:
        the raw columns already named t, q_m, q, tau_m, q_ref).
    units : dict of str to str, optional
        Log column -> unit of the raw column (s|ms|us; rad|deg|rev|counts|m|mm|um;
        Nm|N|A|V).
    gear_ratio : float, optional
        Refers the `motor_side` columns to the joint side (angles / N, torque x N).
    motor_side : sequence of str
        The columns measured on the motor shaft.
    counts_per_turn : float, optional
        Motor encoder counts per turn of the motor shaft.
    link_counts_per_turn : float, optional
        Link encoder counts per turn.
    torque_constant : float, optional
        N m/A (or per V) for a torque column in A or V.
    rate_hz : float, optional
        The drive's fixed sample rate: t rebuilt as k / rate.
    meta : dict of str to str, optional
        Metadata keys of docs/log-format.md section 1.3.
    gains_side : {"joint", "motor"}
        "motor": kv, ki, tau_max in `meta` are motor-side (x N^2, N^2, N).
    delimiter : str, optional
        Column separator (default: found from the header).

    Returns
    -------
    ImportReport
        `log`, `warnings`; `table()`, `to_json()`.

    Raises
    ------
    LogError
        What cannot be converted, naming the file, line and column (a ValueError).
    ValueError
        `out` is the input file or a file jointbench did not write.
    """
    # argument checks: here, before any reading
    from jointbench.bench.output import check_file
    from jointbench.identification.log_import import (LOG_COLUMNS, ImportSpec, convert,
                                                      read_raw)

    src = Path(file)
    target = None if out is None else Path(out)
    if target is not None:
        if src.exists() and target.exists() and target.resolve() == src.resolve():
            raise ValueError(f"--out {target}: is the input file; choose another name")
        check_file(target, "--out")
    raw = read_raw(src, delimiter)
    if columns is None:
        columns = {c: c for c in LOG_COLUMNS if c in raw.header}
    spec = ImportSpec(columns=dict(columns), units=dict(units or {}), gear_ratio=gear_ratio,
                      motor_side=tuple(motor_side), counts_per_turn=counts_per_turn,
                      link_counts_per_turn=link_counts_per_turn,
                      torque_constant=torque_constant, rate_hz=rate_hz, meta=dict(meta or {}),
                      gains_side=gains_side)
    result = convert(raw, spec)
    if target is not None:
        write_log(result.log, target)
    return ImportReport(result, target)
