"""`jointbench.identify`: the identification of a log with every option of `jointbench
identify` (filter overrides, refinement, bias correction, validation on another log), the
warnings on the log and the estimate, as one Fit (bench.results.identify)."""

from __future__ import annotations

import math
from typing import Callable

from jointbench.bench.api_args import check
from jointbench.bench.api_log import LogLike, as_log, log_name
from jointbench.bench.results.identify import Fit
from jointbench.bench.results.runs import RunsFit
from jointbench.identification.checks.fit import estimate_flags
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.identify import identify as identify_log
from jointbench.identification.log import Log, unit_warnings


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
    """(FilterSettings, first mode) overriding the chosen filter (identification.filter_choice
    .choose_filter: eqs. 28-29 from the log's first mode, or `f1_hz`) with the options given;
    (None, None) when every option is at its default (identify then chooses the band)."""
    from jointbench.identification.filter_choice import choose_filter

    if wn is None and Nd is None and order == 4 and \
            chain == {"zoh": True, "filter_torque": True, "skip": 0, "stencil": None}:
        return None, None
    choice = choose_filter(log, f1_hz)   # what the options override, and the first mode
    base = choice.settings
    chain = {**chain, "stencil": chain["stencil"] or base.stencil}
    settings = FilterSettings(wn=wn if wn is not None else base.wn, m=order,
                              Nd=Nd if Nd is not None else base.Nd, ts=log.ts, **chain)
    return settings, choice.first_mode


def identify(log: LogLike | list[LogLike] | tuple[LogLike, ...], model: str = "auto", settings: FilterSettings | None = None, *,
             wn: float | None = None, fc_hz: float | None = None, order: int = 4,
             Nd: int | None = None, skip: int = 0, zoh: bool = True,
             filter_torque: bool = True, stencil: int | None = None,
             f1_hz: float | None = None, refine: bool = False,
             refine_max_nfev: int | None = None, debias: int | None = None,
             friction_timeconst: float | None = None, validate: LogLike | None = None,
             corrections: tuple[str, ...] | None = None,
             progress: Callable[[str], None] | None = None,
             replica_progress: Callable[[int, int], None] | None = None,
             warn: Callable[[str], None] | None = None) -> Fit | RunsFit:
    """Identify the axis parameters of a log (`jointbench identify`; paper eqs. 13, 18-20, 6).

    Parameters
    ----------
    log : Log, str or PathLike, or a list or tuple of them
        The log, or its file (docs/log-format.md). A list: several runs of one axis, each
        identified with the same options, then pooled (bench.results.runs: the run-to-run
        spread beside each run's sigma, a pooled sigma that covers it); the answer is then
        a RunsFit.
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
    corrections : tuple of str, optional
        The corrections beyond the paper's chain to apply (`--corrections`; names of
        identification.identify.CORRECTIONS, docs/method.md); default all of them; () is
        the paper's chain alone (`--plain`: eqs. 26-29, 22, 13 or 18-20, least squares).
        The fit's report lists those that ran.
    progress : callable, optional
        Called with a line of refinement progress.
    replica_progress : callable, optional
        Called as (done, total) after each bias-correction replica.
    warn : callable, optional
        Called with each warning as it arises (the same lines end in `Fit.warnings`).

    Returns
    -------
    Fit or RunsFit
        `parameters` {name: Estimate(value, sigma, sigma_hac, unit)}, `warnings`, `notes`,
        `flags`; `table()`, `to_json()`, `plot()`. For a list of logs a RunsFit: `fits`,
        `pooled`, `notes`; `table()`, `to_json()`.

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
    if isinstance(log, (list, tuple)):
        if not log:
            raise ValueError("identify: no log given")
        opts = dict(wn=wn, fc_hz=fc_hz, order=order, Nd=Nd, skip=skip, zoh=zoh,
                    filter_torque=filter_torque, stencil=stencil, f1_hz=f1_hz, refine=refine,
                    refine_max_nfev=refine_max_nfev, debias=debias,
                    friction_timeconst=friction_timeconst, validate=validate,
                    progress=progress, replica_progress=replica_progress, warn=warn)
        fits = [identify(one, model, settings, **opts) for one in log]
        names = [f.source for f in fits]
        if len(set(names)) < len(names):
            names = [f"{i + 1}:{nm}" for i, nm in enumerate(names)]
        return RunsFit.of(fits, names)
    check("identify", locals())
    from jointbench.identification.physical import InversionError
    from jointbench.identification.saturation import clipping_warnings
    from jointbench.identification.checks.plausibility import sanity_warnings

    from jointbench.identification.corrections import CORRECTIONS, check_corrections

    wanted = check_corrections(CORRECTIONS if corrections is None else corrections)
    if stencil == 5 and "stencil5" not in wanted:
        raise ValueError("--stencil 5 is the stencil5 correction, which is switched off "
                         "(--plain or --corrections without it)")
    say = warn or (lambda text: None)
    loaded = as_log(log)
    source = log_name(log, loaded)
    other = None if validate is None else as_log(validate)
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
        result = identify_log(loaded, model, settings, f1_hz=f1_hz, first_mode=mode,
                              corrections=wanted)
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
                              friction_timeconst=friction_timeconst, corrections=wanted)
    if other is not None:
        from jointbench.bench.present.cross_validation import forward_validation
        from jointbench.identification.cross_validation import validate_on
        validation = validate_on(result, other, f1_hz)
        forward = forward_validation(result, loaded, other)
    for text in sanity_warnings(result, loaded):   # mislabelled, too short, explains too little
        say(text)
        warnings.append(text)
    warnings += [w for w in result.warnings if w not in warnings]   # the band's checks
    return Fit(loaded, result, loaded.truth() or None, tuple(flags), tuple(warnings),
               source=source, refined=refined, debiased=debiased, validation=validation,
               forward=forward, validate_source=None if validate is None else (
                   log_name(validate, other)))
