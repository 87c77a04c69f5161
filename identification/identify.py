"""The whole chain on one log: filter settings, regressor, least squares, physical parameters,
direct validation (Figure 2). Pure numerics: no I/O, no MuJoCo."""

from __future__ import annotations

import math

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from jointbench.identification import link_fit, regressors
from jointbench.identification.checks.fit import check_excitation, check_signals
from jointbench.identification.corrections import CORRECTIONS, check_corrections
from jointbench.identification.estimate import LSResult, NotIdentifiable, block_weighted, least_squares
from jointbench.identification.checks.band import band_warnings, check_f1
from jointbench.identification.band_choice import (MODE_DISAGREEMENT, BandChoice, choose_band,
                                                   wide_settings)
from jointbench.identification.filter_choice import choose_filter, is_paper_prototype, stencil_for
from jointbench.identification.first_mode import (FirstMode, given_first_mode,
                                                  measure_first_mode)
from jointbench.identification.filtering import FilterSettings, Lowpassed, lowpass
from jointbench.identification.instruments import instrument_log
from jointbench.identification.iv_check import compare
from jointbench.identification.log import Log, LogError
from jointbench.identification.physical import InversionError, invert_motor_only, table3
from jointbench.identification.saturation import exclude_clipped  # clipped torque rows out

MODEL_CHOICES = ("joint-motor", "motor-only", "motor-only-printed", "rigid", "auto")
REVERSAL_PASSES = 3   # at most this many fixed-point passes of `_place_reversals`
# a pass that moves each of REVERSAL_PARAMS by less than this share of its own standard
# deviation ends the passes (`ReversalPasses`)
REVERSAL_SETTLED = 0.1
# the parameters the passes settle: the stiffness, the inertias and the motor's friction,
# which the late reversals bias; the link's gravity and Coulomb terms (MX, MY, FS, FV) do not
# settle: from pass to pass they jitter by up to half a sigma with the discrete reversal and
# stick events, and the passes never bring them under REVERSAL_SETTLED
REVERSAL_PARAMS = ("K", "Jm", "JL", "FVm", "FSm")

def paper_chain(settings: FilterSettings, wanted: frozenset[str]) -> FilterSettings:
    """`settings` with the chain corrections switched off that `wanted` lacks: eq. (22)'s 3
    points without stencil5, the torque as logged (no ZOH alignment) without zoh."""
    if "stencil5" not in wanted and settings.stencil != 3:
        settings = replace(settings, stencil=3)
    if "zoh" not in wanted and settings.zoh:
        settings = replace(settings, zoh=False)
    return settings


def chain_corrections(settings: FilterSettings) -> tuple[str, ...]:
    """The chain corrections `settings` applies (names of CORRECTIONS)."""
    return tuple(n for n, on in (("zoh", settings.zoh), ("stencil5", settings.stencil == 5))
                 if on)


@dataclass(frozen=True)
class ReversalPasses:
    """How the reversal passes of `_place_reversals` ended. `moves`: each pass's largest
    move, max_i |X_i - X'_i| / sigma_i over REVERSAL_PARAMS (`pass_move`; X' the
    previous pass's estimate, sigma the paper's standard deviation of the new one); `stop`:
    `settled` (the last move under REVERSAL_SETTLED), `cap` (REVERSAL_PASSES run), `no_friction`
    (no positive FSm / Jm or FS / JL to place: the first fit kept) or `rows_moved` (the
    rebuilt columns lost or gained rows: the pass before kept)."""

    passes: int
    moves: tuple[float, ...]
    stop: str

    def to_json(self) -> dict:
        """The JSON object `identify --json` prints under "reversals"."""
        return {"passes": self.passes, "stop": self.stop,
                "moves_sigma": [m if math.isfinite(m) else None for m in self.moves],
                "settled_below_sigma": REVERSAL_SETTLED, "max_passes": REVERSAL_PASSES}


def pass_move(new: LSResult, old: LSResult) -> float:
    """The largest move of a pass: max over REVERSAL_PARAMS identified in both fits of
    |X_new - X_old| / sigma_new (the paper's sigma of the new fit); inf when none compares."""
    keep = [i for i, n in enumerate(new.names) if n in REVERSAL_PARAMS
            and n not in new.unidentifiable and n not in old.unidentifiable]
    if not keep or new.names != old.names:
        return math.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.abs(new.X[keep] - old.X[keep]) / new.sigma[keep]
    return float(np.max(z)) if np.all(np.isfinite(z)) else math.inf


@dataclass(frozen=True)
class Identification:
    """Everything `identify` found: the model, its LS estimate, the physical parameters (with
    standard deviations where available), the filter, and the direct validation arrays."""

    model: str
    ls: LSResult
    physical: dict[str, float]
    physical_sigma: dict[str, float]
    settings: FilterSettings
    y: np.ndarray
    y_pred: np.ndarray
    t: np.ndarray
    block: np.ndarray
    notes: tuple[str, ...] = ()
    table3: dict[str, float] = field(default_factory=dict)
    prismatic: bool = False  # the log's `axis: prismatic` (m, N, kg in place of rad, N m, kg m^2)
    # standard deviations from the autocorrelation-consistent covariance (LSResult.cov_corrected)
    physical_sigma_corrected: dict[str, float] = field(default_factory=dict)
    first_mode: FirstMode | None = None   # measured on the log or given (--f1); None: unknown
    warnings: tuple[str, ...] = ()        # honest checks of the band against the mode
    stencil_reason: str = ""              # why this central difference
    paper_axis: bool = False              # the paper's prototype (log metadata): paper columns
    # auto's fallback to rigid: why the flexible model was rejected, and its estimate if any
    # (identification.checks.plausibility reads both: a mislabelled log, data too short)
    rejected: tuple[str, dict[str, float]] | None = None
    # motor-only: the weighted inversion of eqs. (18)-(20)'s X's, from which the link
    # reconstruction (identification/link_fit.py, `physical`) starts; {} when it fails
    physical_eqs18_20: dict[str, float] = field(default_factory=dict)
    band: BandChoice | None = None        # joint-motor with defaults: the band_choice rule
    corrections: tuple[str, ...] = ()     # the corrections beyond the paper that ran (CORRECTIONS)
    reversals: ReversalPasses | None = None   # joint-motor with the reversal passes: how they ended

    @property
    def relative_error_pct(self) -> float:
        """Direct validation: 100 ||y - W X^|| / ||y|| over the torque rows."""
        rows = self.block == 0
        return float(100 * np.linalg.norm(self.y[rows] - self.y_pred[rows])
                     / np.linalg.norm(self.y[rows]))


def _check_length(log: Log, settings: FilterSettings, nd: int) -> None:
    need = settings.min_samples(nd)
    if len(log) < need:
        raise LogError(f"{len(log)} samples are too few for this filter and decimation "
                       f"(Nd = {settings.Nd}, derivatives to order {nd}): at least {need} "
                       "are needed", log.path)


STIFFNESS_REL_SIGMA = 0.5  # auto: K and JL must be known to better than 50 % (1 sigma)


def stiffness_rejection(result: Identification) -> str | None:
    """Why a flexible identification does NOT identify a stiffness in the band, or None when
    it does. `auto` keeps the flexible model only when all hold:
    - K, Jm, JL > 0 (identified) and FVm, FV, FSm >= 0 (a physical two-mass axis);
    - K and JL have relative standard deviations under 50 %;
    - motor-only only: the identified first mode sqrt(K (1/Jm + 1/JL)) / 2 pi lies inside the
      band the regressor sees, below the decimated cutoff 0.8 Fs / (2 Nd) (the joint-motor
      model measures the deflection q_m - q directly).
    """
    p, sd = result.physical, result.physical_sigma
    for k in ("K", "Jm", "JL"):
        if not p.get(k, 0.0) > 0:
            why = result.ls.reasons.get(k) if k in result.ls.names else None
            return (f"{k} is not identified: {why}" if why else
                    f"{k} = {p.get(k, float('nan')):.4g} is not positive")
    for k in ("K", "JL"):
        rel = sd.get(k, np.inf) / abs(p[k])
        if not rel < STIFFNESS_REL_SIGMA:
            return f"{k} has a relative standard deviation of {100 * rel:.0f} % (over 50 %)"
    if result.model == "joint-motor":
        return None if all(p.get(k, 0.0) >= 0 for k in ("FVm", "FV", "FSm")) else \
            "a friction coefficient is negative (unphysical)"
    f1 = float(np.sqrt(p["K"] * (1 / p["Jm"] + 1 / p["JL"])) / (2 * np.pi))
    cut = result.settings.decimated_cutoff_hz
    if f1 >= cut:
        return (f"the identified first mode {f1:.4g} Hz lies outside the band (decimated "
                f"cutoff {cut:.4g} Hz)")
    for k in ("FVm", "FV", "FSm"):
        if p.get(k, 0.0) < 0:
            return f"{k} = {p[k]:.4g} is negative (unphysical)"
    return None


def identify(log: Log, model: str = "auto", settings: FilterSettings | None = None,
             f1_hz: float | None = None, first_mode: FirstMode | None = None,
             corrections: tuple[str, ...] | frozenset[str] = CORRECTIONS) -> Identification:
    """Identify the axis of `log` with `model` (docs/cli.md names, plus
    `motor-only-printed`, the paper's eq. 18 as printed). `auto` takes joint-motor when `q`
    is logged, else motor-only, and falls back to rigid when the data does not identify a
    stiffness in the band (`stiffness_rejection`; with q, for example a rigid axis whose q
    follows q_m). Without settings the filter is `choose_filter(log, f1_hz)` (the first mode
    measured on the log when f1 is not given); the result carries the first mode, the
    stencil's reason and the warnings of `band_checks.band_warnings`, and a joint-motor fit
    with a mode found is fitted again in the wide band and the more precise kept
    (`band_choice.choose_band`, reported in `band`; the wide band looked at once from the
    chooser's Coulomb columns and fitted in full only when that look wins: `_wide_fit`);
    with `settings`,
    `first_mode` (what the caller measured, for example before overriding wn or Nd; measured
    here when neither it nor f1 is given) is reported and checked against them.
    `corrections`: the corrections beyond the paper's chain to apply (CORRECTIONS, all by
    default; empty: the paper's chain alone); those that ran are in `corrections` of the
    result. Raises LogError for unusable logs, NotIdentifiable when nothing is excited and
    ValueError for an unknown model or correction.
    """
    if model not in MODEL_CHOICES:
        raise ValueError(f"unknown model {model!r} (choices: {', '.join(MODEL_CHOICES)})")
    if f1_hz is not None:
        check_f1(log, f1_hz)
    wanted = check_corrections(corrections)
    warnings: list[str] = []
    notes: list[str] = []
    chooser = settings is None
    if chooser:
        choice = choose_filter(log, f1_hz)
        settings, mode, why = choice.settings, choice.first_mode, choice.stencil_reason
        warnings += choice.warnings
        notes += choice.notes
    else:
        # given settings without a mode: the mode is still measured on the log, for the
        # instruments' resolution and the band checks (without it the instruments' Welch
        # segments are too long for a sweep, and Jm is silently wrong)
        mode = first_mode or (given_first_mode(f1_hz) if f1_hz is not None
                              else measure_first_mode(log))
        why = f"given: {settings.stencil} points"
    if settings.stencil == 5 and "stencil5" not in wanted:
        why = "eq. (22): 3 points (the 5-point stencil switched off)"
    settings = paper_chain(settings, wanted)
    f1 = mode.f1_hz if mode is not None and mode.found else None
    # what both bands share, made once: the instruments' log, the Butterworth's outputs,
    # the chains' columns at each filter setting (the decimation apart)
    made: dict = {"lowpass": Lowpassed(), "columns": regressors.ChainColumns()}
    result = _identify(log, model, settings, notes, f1, wanted, made)
    if chooser and result.model == "joint-motor" and f1 is not None and "wide_band" in wanted:
        wide = wide_settings(log, settings)
        other = None
        if wide[0] is not None:
            try:
                other = _wide_fit(log, model, paper_chain(wide[0], wanted), result, wide, f1,
                                  wanted, made)
            except (ValueError, ArithmeticError, np.linalg.LinAlgError) as err:
                other = err
        result, band = choose_band(result, other, wide, _joint_motor_estimate, f1)
        settings = result.settings
        why = stencil_for(settings)[1] if band.used == "wide" else why
        warnings += [band.warning] if band.warning else []
        result = replace(result, band=band, corrections=result.corrections + (
            ("wide_band",) if band.used == "wide" else ()))
    warnings += result.warnings   # the kept fit's (the band's rule may have swapped it)
    if mode is not None and mode.found and mode.method != "given" and result.model != "rigid":
        mode, text = model_first_mode(result, mode)
        if text:
            warnings.append(text)
    if mode is not None and mode.found and result.model != "rigid":
        nd = 4 if result.model.startswith("motor-only") else 2
        warnings += band_warnings(log.sample_rate_hz, settings, mode.f1_hz, nd)
    if result.model == "rigid" and warnings:
        # a rigid model has no mode to miss: "no resonance found" is then a note
        result = replace(result, notes=result.notes + tuple(warnings))
        warnings = []
    return replace(result, first_mode=mode, warnings=tuple(warnings), stencil_reason=why,
                   paper_axis=is_paper_prototype(log))


def _wide_fit(log: Log, model: str, wide: FilterSettings, chosen: Identification,
              candidate: tuple, f1_hz: float, wanted: frozenset[str], made: dict
              ) -> Identification:
    """The joint-motor fit in the wide band `wide` for `band_choice.choose_band` against the
    chooser's `chosen`. The reversal passes converge on the axis' friction, which does not
    depend on the band: the wide band is first fitted once with the Coulomb columns of the
    chooser's estimate (its reversals and stick phases, the estimator chosen's: instruments
    only when `chosen` kept them), and fitted in full, its passes started there, only when
    that fit wins `choose_band`'s rule; the rule then reads the full fit. The look's
    instruments are unpaired (`_instruments`). `candidate`: what `wide_settings` gave."""
    look = wanted if chosen.ls.instrumental else wanted - {"instruments"}
    first = _identify(log, model, wide, [], f1_hz, look, made, chosen.physical, settle=False)
    if choose_band(chosen, first, candidate, _joint_motor_estimate, f1_hz)[1].used != "wide":
        return first
    return _identify(log, model, wide, [], f1_hz, wanted, made, chosen.physical)


def _joint_motor_estimate(r: Identification) -> tuple[dict, dict] | None:
    return (r.physical, r.physical_sigma_corrected) if r.model == "joint-motor" else None


def model_first_mode(result: Identification, measured: FirstMode) -> tuple[FirstMode, str]:
    """The first mode of the identified two-mass model, sqrt(K (1/Jm + 1/JL)) / 2 pi, with its
    standard deviation (corrected covariance of K, Jm, JL for the joint-motor model, their
    corrected sigmas otherwise), as the reported first mode: the frequency response's phase
    crossing drifts on strongly damped (friction-heavy) axes (+11 % on the independent
    simulator's heavy-link family) while the identified K, Jm, JL hold it within 1 %. The
    frequency-response estimate, which designed the band, stays in the note. The text is a
    warning when the two differ by more than 20 % (the band then misses its design), else ''.
    Returns `measured` unchanged when K, Jm, JL are not all positive."""
    p = result.physical
    K, Jm, JL = (p.get(n, math.nan) for n in ("K", "Jm", "JL"))
    if not (K > 0 and Jm > 0 and JL > 0):
        return measured, ""
    f1 = math.sqrt(K * (1 / Jm + 1 / JL)) / (2 * math.pi)
    grad = {"K": f1 / (2 * K), "Jm": -f1 / 2 * K / Jm ** 2 / (K * (1 / Jm + 1 / JL)),
            "JL": -f1 / 2 * K / JL ** 2 / (K * (1 / Jm + 1 / JL))}
    names = result.ls.names
    if result.model == "joint-motor" and result.ls.cov_corrected is not None:
        idx = [names.index(n) for n in grad]
        g = np.array(list(grad.values()))
        var = float(g @ result.ls.cov_corrected[np.ix_(idx, idx)] @ g)
    else:
        sc = result.physical_sigma_corrected or result.physical_sigma
        var = sum((grad[n] * sc.get(n, math.nan)) ** 2 for n in grad)
    sigma = math.sqrt(var) if var >= 0 else math.nan
    note = (f"the frequency response gave {measured.f1_hz:.4g} +- {measured.sigma_hz:.2g} Hz "
            f"({measured.method}), which designed the band; {measured.note}")
    mode = FirstMode(f1, sigma, "identified two-mass model, sqrt(K (1/Jm + 1/JL)) / 2 pi", True,
                     note)
    gap = abs(measured.f1_hz / f1 - 1)
    text = "" if gap <= MODE_DISAGREEMENT else (
        f"the frequency response puts the first mode at {measured.f1_hz:.4g} Hz, the identified "
        f"model at {f1:.4g} Hz ({100 * gap:.0f} % apart): the band was designed for the "
        f"former; give --f1 {f1:.3g} to design it for the latter")
    return mode, text


def _identify(log: Log, model: str, settings: FilterSettings, notes: list[str],
              f1_hz: float | None = None, wanted: frozenset[str] = frozenset(CORRECTIONS),
              made: dict | None = None, start: Mapping[str, float] | None = None,
              settle: bool = True) -> Identification:
    """`identify` with the settings chosen and the corrections `wanted`; the joint-motor
    model is solved with the reference's instruments when the log has q_ref
    (`_instruments`). `made` keeps what does not depend on the band (the instruments' log,
    the Butterworth's outputs: `filtering.Lowpassed`, the chains' undecimated columns per
    filter setting: `regressors.ChainColumns`) for another band's fit of the log. `start`:
    eq. (13)'s parameters from another fit of the log (the chooser's band), from which the
    joint-motor fit's first Coulomb columns are built (`_place_reversals`' columns) instead
    of the filtered velocity's own reversals; `settle` False: that one fit alone, with its
    corrected covariance, without the reversal passes and the instruments' check
    (`identify`'s look at the wide band)."""
    made = {} if made is None else made
    lp = made.setdefault("lowpass", Lowpassed())
    columns = made.setdefault("columns", regressors.ChainColumns())
    if model == "auto":
        flexible = "joint-motor" if log.q is not None else "motor-only"
        try:
            result = _identify(log, flexible, settings, [], f1_hz, wanted, made, start, settle)
        except (InversionError, NotIdentifiable) as err:
            notes.append(f"auto: {flexible} model rejected ({err}); rigid model used")
            rejected = (str(err), {})
        else:
            why = stiffness_rejection(result)
            if why is None:
                return replace(result, notes=tuple(notes) + result.notes)
            notes.append(f"auto: the data does not identify a stiffness in the band "
                         f"({flexible} model: {why}); rigid model used")
            rejected = (why, dict(result.physical))
        return replace(_identify(log, "rigid", settings, notes, f1_hz, wanted, made, start,
                                 settle),
                       rejected=rejected)
    if model != "rigid" and not (settings.zoh and settings.filter_torque):
        notes.append("the no-ZOH / unfiltered-torque options apply to the rigid model only")
    nd = 4 if model.startswith("motor-only") else 2
    _check_length(log, settings, nd)
    check_signals(log, model, settings, lp)
    ran = list(chain_corrections(settings))
    warnings: list[str] = []
    passes: ReversalPasses | None = None
    if model == "joint-motor":
        chain = regressors.JointMotorChain(log, settings, lp, columns)
        stick = "stick_phases" in wanted
        friction: tuple[float, float] | Mapping[str, float] = (0.0, 0.0)
        if start is not None and "reversals" in wanted and any(reversal_rates(start)):
            friction = dict(start) if stick else reversal_rates(start)
        reg = exclude_clipped(chain.regressor(friction), log)
        mark = len(notes)
        if "instruments" in wanted:
            # the look at another band (settle False) takes the instruments unpaired
            Z = _instruments(log, reg, f1_hz, notes, made, paired=settle)
        else:
            Z = None
            notes.append("least squares: instruments switched off")
        ran += ["instruments"] if Z is not None else []
        # with the reversal passes, only the last pass's corrected covariance is used
        passing = "reversals" in wanted and settle
        ls = block_weighted(reg.W, reg.y, reg.names, reg.block, time=reg.index, instruments=Z,
                            corrected=not passing)
        if passing:
            reg, ls, placed, passes = _place_reversals(log, chain, reg, ls, Z, notes, stick)
            if not placed and friction != (0.0, 0.0) and passes.stop == "rows_moved":
                # the first columns, kept, already placed the start's reversals
                placed = ("reversals", "stick_phases") if stick and reversal_rates(start)[0] \
                    and start.get("K", 0.0) > 0 else ("reversals",)
            ran += placed
        if Z is not None and settle:
            reg, ls, ran, passes = _check_instruments(log, chain, reg, ls, Z, wanted, ran, notes,
                                                      warnings, mark, passes)
    elif model == "motor-only" and "motor_only_columns" not in wanted:
        reg = exclude_clipped(regressors.motor_only(log, settings, corrected=False, lp=lp), log)
        ls = least_squares(reg.W, reg.y, reg.names)
    elif model == "motor-only":
        # least squares: the torque's own derivatives are columns here, and instruments
        # predicted for them are weak and bias K more than least squares does
        reg = exclude_clipped(regressors.motor_only(log, settings, corrected=True, lp=lp), log)
        ls = least_squares(reg.W, reg.y, reg.names)
        ran.append("motor_only_columns")
    elif model == "motor-only-printed":
        reg = exclude_clipped(regressors.motor_only(log, settings, corrected=False, lp=lp), log)
        ls = least_squares(reg.W, reg.y, reg.names)
    else:
        reg = exclude_clipped(regressors.rigid(log, settings), log)
        ls = least_squares(reg.W, reg.y, reg.names)
    ls = check_excitation(log, reg, ls)
    physical: dict[str, float] = {}
    sigma: dict[str, float] = {}
    t3: dict[str, float] = {}
    eqs18_20: dict[str, float] = {}
    if model.startswith("motor-only"):
        X = {n: ls.value(n) for n in ls.names if n not in ls.unidentifiable}
        try:
            t3 = table3(X, {n: ls.std(n) for n in X})
        except InversionError as err:
            notes.append(f"Table 3 not computed: {err}")
        except KeyError:
            t3 = {}
        try:
            phys = invert_motor_only(ls, g=log.gravity, qc=float(np.mean(log.q_m)))
        except InversionError as err:
            if reg.model != "motor-only":
                raise
            notes.append(f"eqs. (18)-(20) do not invert ({err})")
            physical, sigma, sigma_corr = {}, {}, {}
        else:
            physical, sigma = phys.as_dict(), {n: phys.std(n) for n in phys.names}
            sigma_corr = _motor_only_sigma_corrected(ls, log)
        eqs18_20 = dict(physical)
        if reg.model == "motor-only" and "link_reconstruction" in wanted:
            stick = "stick_phases" in wanted
            physical, sigma, sigma_corr = _link_reconstructed(log, settings, physical, f1_hz,
                                                              notes, warnings, lp, stick)
            ran.append("link_reconstruction")
            if stick and physical.get("FSm", 0.0) > 0:   # `link_fit._Rows.profiles`' rule
                ran.append("stick_phases")
    else:
        for n in ls.names:
            if n not in ls.unidentifiable:
                physical[n] = ls.value(n)
                sigma[n] = ls.std(n)
        sigma_corr = {n: ls.std_corrected(n) for n in physical
                      if np.isfinite(ls.std_corrected(n))}
    y_pred = reg.W[:, [i for i, n in enumerate(ls.names) if n not in ls.unidentifiable]] @ \
        ls.X[[i for i, n in enumerate(ls.names) if n not in ls.unidentifiable]]
    for n in ls.unidentifiable:
        notes.append(f"{n} not identifiable: {ls.reasons[n]}")
    for n, v in physical.items():
        if n in ("K", "Jm", "JL", "J", "FVm", "FSm", "FV", "FS") and v < 0:
            notes.append(f"{n} = {v:.4g} is unphysical (negative)")
    return Identification(model=reg.model, ls=ls, physical=physical, physical_sigma=sigma,
                          settings=settings, y=reg.y, y_pred=y_pred, t=log.t[reg.index],
                          block=reg.block, notes=tuple(notes), table3=t3,
                          prismatic=log.prismatic, physical_sigma_corrected=sigma_corr,
                          physical_eqs18_20=eqs18_20, warnings=tuple(warnings),
                          corrections=tuple(n for n in CORRECTIONS if n in ran),
                          reversals=passes)


def reversal_rates(p: dict[str, float]) -> tuple[float, float]:
    """(FSm / Jm, FS / JL) [rad/s^2 or m/s^2] of joint-motor parameters `p`, 0 where a
    friction or inertia is missing or not positive: where `regressors.joint_motor` places the
    Coulomb reversals."""
    return tuple(p[f] / p[j] if p.get(j, 0) > 0 and p.get(f, 0) > 0 else 0.0
                 for f, j in (("FSm", "Jm"), ("FS", "JL")))


def _place_reversals(log: Log, chain: regressors.JointMotorChain, reg: regressors.Regressor,
                     ls: LSResult, Z: np.ndarray | None, notes: list[str],
                     stick: bool = True
                     ) -> tuple[regressors.Regressor, LSResult, tuple[str, ...], ReversalPasses]:
    """Eq. (13) solved again with the Coulomb columns built from the previous pass's
    parameters (the log's `regressors.JointMotorChain` with them): the velocity's zero
    crossings put back where the friction's kink and the held torque's steps have them
    (`filtering.kink_corrected`), placed inside the sample interval with the kink
    (`filtering.crossing_share`), and the motor's stick phases, where the friction holds the
    drive instead of +-FSm (`friction_state`). The filtered velocity's own crossings come late
    by an amount that grows with FS / J, and Jm with them. The passes iterate X_k =
    F(X_{k-1}) until one moves each of REVERSAL_PARAMS by less than REVERSAL_SETTLED of its
    own standard deviation (`pass_move`): from there the passes only jitter within what the
    data can tell (the reversal and stick events are discrete in X); at most REVERSAL_PASSES.
    Only the
    last pass's corrected covariance is computed. `stick` False: the reversals alone (the
    rates), no stick phases. Also returns the corrections that ran (names of CORRECTIONS)
    and how the passes ended."""
    def corrected(reg: regressors.Regressor, ls: LSResult) -> LSResult:
        """`ls` with its corrected covariance (the passes skip it)."""
        return ls if ls.hac is not None else block_weighted(
            reg.W, reg.y, reg.names, reg.block, time=reg.index, instruments=Z)

    rates = (0.0, 0.0)
    stuck = False
    moves: list[float] = []
    stop = "cap"
    for _ in range(REVERSAL_PASSES):
        p = {n: ls.value(n) for n in ls.names if n not in ls.unidentifiable}
        rates = reversal_rates(p)
        if not any(rates):
            return reg, corrected(reg, ls), (), ReversalPasses(len(moves), tuple(moves),
                                                               "no_friction")
        stuck = stick and rates[0] > 0 and p.get("K", 0.0) > 0   # `_friction_models`' rule
        again = exclude_clipped(chain.regressor(p if stick else rates), log)
        if not np.array_equal(again.index, reg.index):   # NaN rows moved: keep the pass before
            return reg, corrected(reg, ls), (), ReversalPasses(len(moves), tuple(moves),
                                                               "rows_moved")
        reg, previous = again, ls
        ls = block_weighted(reg.W, reg.y, reg.names, reg.block, time=reg.index, instruments=Z,
                            corrected=False)
        moves.append(pass_move(ls, previous))
        if moves[-1] < REVERSAL_SETTLED:
            stop = "settled"
            break
    passes = ReversalPasses(len(moves), tuple(moves), stop)
    ls = corrected(reg, ls)
    notes.append(f"Coulomb reversals placed by the identified FSm / Jm = {rates[0]:.4g} and "
                 f"FS / JL = {rates[1]:.4g} (the filtered velocity's zero crossings come late "
                 f"by the friction's kink; {passes.passes} passes, "
                 + (f"the last moving {', '.join(REVERSAL_PARAMS)} by under "
                    f"{REVERSAL_SETTLED:g} sigma)"
                    if stop == "settled" else
                    f"the last still moving one by {moves[-1]:.2g} sigma)"))
    return reg, ls, ("reversals", "stick_phases") if stuck else ("reversals",), passes


def _check_instruments(log: Log, chain: regressors.JointMotorChain, reg: regressors.Regressor,
                       ls: LSResult, Z: np.ndarray, wanted: frozenset[str], ran: list[str],
                       notes: list[str], warnings: list[str], mark: int,
                       passes: ReversalPasses | None = None
                       ) -> tuple[regressors.Regressor, LSResult, list[str],
                                  ReversalPasses | None]:
    """The instruments' fit `ls` (of rows `reg`, after the reversal passes) held against
    least squares on the same rows (`iv_check.compare`). When the two agree, or when they
    disagree but the instrument passes started from the chain without instruments (its
    least-squares estimate, passes and all) end where they did, the instruments' fit is kept
    unchanged with a warning (least squares' own closed-loop bias, which grows in sigmas with
    the log's length, or instruments invalid wherever they start). When the passes depend on
    their start, the first pass's instruments were correlated with the model's error and the
    passes fed it back: the chain without instruments is kept, with a warning naming the
    cause, and its notes replace those of the instruments' passes (`notes[mark:]`). Returns
    the kept rows, fit, corrections that ran and how the kept fit's reversal passes ended
    (`passes`, those of the instruments' fit, unless the chain without them is kept)."""
    check = compare(ls, block_weighted(reg.W, reg.y, reg.names, reg.block, time=reg.index))
    if check is None or not check.fired:
        return reg, ls, ran, passes
    stick = "stick_phases" in wanted
    first = exclude_clipped(chain.regressor(), log)
    plain_notes: list[str] = []
    plain_reg, plain, placed = first, block_weighted(
        first.W, first.y, first.names, first.block, time=first.index,
        corrected="reversals" not in wanted), ()
    plain_passes = None
    if "reversals" in wanted:
        plain_reg, plain, placed, plain_passes = _place_reversals(log, chain, first, plain,
                                                                  None, plain_notes, stick)
        # the instrument passes again, from the chain without instruments (without friction
        # to place they return its fit: the instruments on its rows then)
        _, again, _, _ = _place_reversals(log, chain, plain_reg, plain, Z, [], stick)
        if not again.instrumental:
            again = block_weighted(plain_reg.W, plain_reg.y, plain_reg.names, plain_reg.block,
                                   time=plain_reg.index, instruments=Z)
        restart = compare(ls, again)
    else:
        restart = None   # no passes: nothing fed back, the start cannot matter
    if restart is None or not restart.fired:
        warnings.append(check.kept_warning(None if restart is None else restart.b))
        return reg, ls, ran, passes
    warnings.append(check.warning(restart.b))
    del notes[mark:]
    notes.append("least squares: the instruments failed the check against it (warnings)")
    notes.extend(plain_notes)
    kept = [n for n in ran if n not in ("instruments", "reversals", "stick_phases")]
    return plain_reg, plain, kept + list(placed), plain_passes


def _instruments(log: Log, reg: regressors.Regressor, f1_hz: float | None,
                 notes: list[str], made: dict | None = None, paired: bool = True
                 ) -> np.ndarray | None:
    """The regressor rebuilt from the reference's predictions (identification/instruments.py),
    or None (least squares) without q_ref; a note says which. The predicted log is made once
    per f1 in `made` (it does not depend on the band). `paired` False: its columns without
    the 5-point chain's pairing (`regressors.JointMotorChain`)."""
    made = {} if made is None else made
    key = ("instrument_log", f1_hz)
    if key not in made:
        made[key] = instrument_log(log, f1_hz)
    inst = made[key]
    if inst is None:
        why = "no q_ref to build instruments from" if log.q_ref is None else \
            "the log is too short for instruments (under four Welch segments at f1 / 40)"
        notes.append(f"least squares: {why}; closed-loop torque noise may bias Jm up and K "
                     "down")
        return None
    Z = regressors.JointMotorChain(inst, reg.settings, made.get("lowpass", lowpass),
                                   made.get("columns"), paired).regressor()
    # the same rows (block, sample) as the regressor's, which may have lost clipped ones
    span = int(max(Z.index.max(initial=0), reg.index.max(initial=0))) + 1
    keys, wanted = Z.block * span + Z.index, reg.block * span + reg.index
    order = np.argsort(keys, kind="stable")
    at = np.minimum(np.searchsorted(keys, wanted, sorter=order), len(keys) - 1)
    pick = order[at] if len(keys) else at
    if not (len(keys) and np.array_equal(keys[pick], wanted)):
        notes.append("least squares: the instruments do not cover the regressor's rows")
        return None
    notes.append("instrumental variables: the regressor rebuilt from q_ref's predictions")
    return Z.W[pick]


def _link_reconstructed(log: Log, settings: FilterSettings, start: dict[str, float],
                        f1_hz: float | None, notes: list[str], warnings: list[str],
                        lp: Lowpassed | None = None, stick: bool = True
                        ) -> tuple[dict[str, float], dict[str, float], dict[str, float]]:
    """The physical parameters of the motor-only model from the link reconstructed out of q_m
    (identification/link_fit.py), started from the eqs. (18)-(20) inversion `start` (or, when
    it gives no positive K and JL, from the best link antiresonance in the band): those
    columns hold the torque's derivatives, which the closed loop's torque noise biases. The
    X's, Table 3 and the direct validation stay those of eqs. (18)-(20). `stick`: the motor's
    Coulomb column with its stick phases (`link_fit.fit`). Raises
    InversionError when neither start gives a positive stiffness."""
    if not (start.get("K", 0) > 0 and start.get("JL", 0) > 0):
        try:
            start = link_fit.start_from_band(log, settings)
        except ValueError as err:
            raise InversionError(str(err)) from err
        notes.append("the link reconstruction started from the best link antiresonance in "
                     "the band")
    try:
        result = link_fit.fit(log, settings, start, f1_hz, lp or Lowpassed(), stick)
    except ValueError as err:
        raise InversionError(str(err)) from err
    notes.extend(result.notes)
    warnings.extend(result.warnings)
    return result.physical, result.sigma, result.sigma_corrected


def _motor_only_sigma_corrected(ls: LSResult, log: Log) -> dict[str, float]:
    """Physical standard deviations of the motor-only model from the corrected covariance of
    the X's, through the same weighted inversion as the paper's; {} when unavailable."""
    if ls.cov_corrected is None:
        return {}
    keep = [i for i, n in enumerate(ls.names) if n not in ls.unidentifiable]
    if not np.all(np.isfinite(ls.cov_corrected[np.ix_(keep, keep)])):
        return {}
    swapped = replace(ls, cov=ls.cov_corrected, sigma=ls.sigma_corrected)
    try:
        phys = invert_motor_only(swapped, g=log.gravity, qc=float(np.mean(log.q_m)))
    except (InversionError, np.linalg.LinAlgError):
        return {}
    return {n: phys.std(n) for n in phys.names}
