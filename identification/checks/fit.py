"""Is the data rich enough for the model, and are the estimates physical?

Checks around the least squares of eq. (21), on numpy arrays (no I/O):

- `check_signals`, before the regressor is built:
  - a constant q_m (or q for the joint-motor model, or tau_m) excites nothing; filtered, the
    constant would leave only rounding noise in the derivative columns, which the column
    scaling of the rank check would blow up into fake excitation;
  - too few frequencies: at one frequency the motor equation's linear terms
    Jm qm'' + FVm qm' + K (qm - q) (and the link equation's JL q'' + FV q' - K (qm - q)) span
    two directions for three parameters, and eq. (18)'s six linear parameters X1..X6 need
    three frequencies. `excited_lines` counts the frequency lines of the motor velocity in
    the band the regressor sees: the participation ratio (sum P)^2 / sum P^2 of its Welch
    spectrum, divided by that of a pure tone at the strongest frequency (1 for a sine, its
    friction harmonics included). Measured: 1.03-1.06 on 1 Hz and 3 Hz sines (simulated or
    exact), 10-15 on the 60 s chirps of the prototype and arm6 axis3.
- `check_excitation`, after it: conditioning. The rank check of `estimate.least_squares`
  leaves out directions of the column-scaled regressor under 1e-8 of the largest singular
  value. Degenerate data (an exact sine) leaves ratios between 1e-8 and 1e-4 that only the
  filters' end transients and small nonlinearities (sign, sin q) create; a direction under
  EXCITATION_LIMIT = 1e-4 is left out too (one parameter per direction, named with the
  others whose combination alone is identified) and the rest re-estimated. Measured smallest
  ratios on good data: 0.14-0.4 (prototype chirp, all models), 0.0067-0.18 (arm6 chirps).
  A homogeneous equation (the link equation, y = 0) gets its scale from the parameters it
  shares with the torque equation (K); when those are not identifiable, neither are the
  others of that equation. Then it refuses the model when none of its dynamic parameters is
  left, or when the model explains less than 19 % of the torque's variation (direct
  validation error over MAX_RELATIVE_ERROR = 90 %, mean removed): the motion is then too
  small against the noise.
- `estimate_flags`: unphysical values (a negative stiffness, inertia or friction) and values
  within two standard deviations of zero, for the `flags` of `identify --json`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from functools import lru_cache

import numpy as np

from jointbench.identification.estimate import LSResult, NotIdentifiable, block_weighted, least_squares
from jointbench.identification.filtering import FilterSettings, lowpass
from jointbench.identification.log import Log
from jointbench.identification.spectra import welch

EXCITATION_LIMIT = 1e-4     # smallest / largest singular value of the column-scaled W
MAX_RELATIVE_ERROR = 0.90   # ||residual|| / ||y - mean y|| over the torque rows
# Parameters that describe the dynamics; the others (gravity, offset) are constant-like
# columns that even motionless data fits.
DYNAMIC = {"joint-motor": ("Jm", "FVm", "FSm", "K", "JL", "FV", "FS"),
           "motor-only": tuple(f"X{i}" for i in range(1, 10)),
           "motor-only-printed": tuple(f"X{i}" for i in range(1, 8)),
           "rigid": ("J", "FV", "FS")}
# Frequency lines each model needs (two independent directions per line for its linear terms)
LINES_NEEDED = {"joint-motor": (2, "Jm, FVm, K in the motor equation and JL, FV, K in the link "
                                   "equation: three linear terms each"),
                "motor-only": (3, "X1 ... X6 of eq. (18): six linear terms"),
                "motor-only-printed": (3, "X1 ... X6 of eq. (18): six linear terms")}
NONNEGATIVE = {"K": "a stiffness", "Jm": "an inertia", "JL": "an inertia", "J": "an inertia",
               "FVm": "a viscous friction", "FV": "a viscous friction",
               "FSm": "a Coulomb friction", "FS": "a Coulomb friction"}
NONNEGATIVE_PRISMATIC = {"J": "a mass", "Jm": "a mass", "JL": "a mass"}


def _constant(x: np.ndarray) -> bool:
    """Constant up to floating-point rounding."""
    scale = float(np.max(np.abs(x))) if len(x) else 0.0
    return float(np.ptp(x)) <= 8 * np.finfo(float).eps * scale


def excited_lines(log: Log, settings: FilterSettings, lp: Callable = lowpass
                  ) -> tuple[float, float, float]:
    """(lines, f_peak, band_hz): the effective number of frequency lines of the motor velocity
    (the filtered q_m differenced) in 0 < f <= the decimated cutoff, the strongest frequency,
    and that cutoff. See the module docstring. `lp`: the Butterworth (`lowpass`, or a
    `filtering.Lowpassed` shared with the regressor's chain)."""
    v = np.diff(lp(log.q_m, settings.wn, settings.ts, settings.m))
    fs = 1.0 / settings.ts
    nperseg = int(min(len(v), 4096))
    f, P = welch(v, fs, nperseg, detrend="linear")
    band = (f > 0) & (f <= settings.decimated_cutoff_hz)
    P, f = P[band], f[band]
    if not len(P) or not P.sum() > 0:
        return 0.0, float("nan"), settings.decimated_cutoff_hz
    peak = float(f[int(np.argmax(P))])
    tone = _tone_spectrum(peak, len(v), fs, nperseg)[band]

    def participation(p: np.ndarray) -> float:
        return float(p.sum() ** 2 / (p ** 2).sum())

    return participation(P) / participation(tone), peak, settings.decimated_cutoff_hz


@lru_cache(maxsize=16)
def _tone_spectrum(f_hz: float, n: int, fs: float, nperseg: int) -> np.ndarray:
    """The Welch spectrum (linear detrend) of n samples of a unit sine at f_hz, the single
    line `excited_lines` measures a motion's participation against: made once per setting
    (read-only: shared)."""
    _, tone = welch(np.sin(2 * np.pi * f_hz * np.arange(n) / fs), fs, nperseg,
                    detrend="linear")
    tone.setflags(write=False)
    return tone


def check_signals(log: Log, model: str, settings: FilterSettings | None = None,
                  lp: Callable = lowpass) -> None:
    """NotIdentifiable when a signal the model needs does not vary at all, or (given the
    filter `settings`) when the motion holds fewer frequency lines than the model needs
    (`lp` as `excited_lines`')."""
    where = f"{log.path or '<log>'}: "
    if _constant(log.q_m):
        raise NotIdentifiable(
            f"{where}q_m is constant ({log.q_m[0]:.6g}) over all {len(log)} samples: the motor "
            f"does not move, so no parameter of the {model} model can be identified (every "
            "motion column is zero)")
    if model == "joint-motor" and log.q is not None and _constant(log.q):
        raise NotIdentifiable(
            f"{where}q is constant ({log.q[0]:.6g}) over all {len(log)} samples: the link does "
            "not move, so the joint-motor model's link equation identifies nothing (JL, FV, "
            "FS, MX, MY, K); use --model motor-only or rigid")
    if _constant(log.tau_m):
        raise NotIdentifiable(
            f"{where}tau_m is constant ({log.tau_m[0]:.6g}) over all {len(log)} samples: "
            f"there is no torque variation for the {model} model to explain")
    if settings is None or model not in LINES_NEEDED:
        return
    need, why = LINES_NEEDED[model]
    lines, peak, band = excited_lines(log, settings, lp)
    if lines < need - 0.5:
        raise NotIdentifiable(
            f"{where}the motion excites about {lines:.2g} frequency line(s) in the band "
            f"0-{band:.3g} Hz (the strongest at {peak:.3g} Hz): the {model} model needs at least "
            f"{need} ({why}, two independent directions per frequency), so they cannot be "
            "separated and no parameter is identified; excite more frequencies (a chirp) or "
            "use --model rigid")


def poorly_excited(W: np.ndarray, names: tuple[str, ...],
                   limit: float = EXCITATION_LIMIT) -> dict[str, str]:
    """Parameters to leave out, one per direction of the column-scaled W whose singular value
    is under `limit` times the largest: the one with the largest share of that direction,
    with a reason naming the others in it. Zero columns must be removed beforehand."""
    Ws = W / np.linalg.norm(W, axis=0)
    reasons: dict[str, str] = {}
    live = list(range(len(names)))
    while len(live) > 1:
        _, sv, Vt = np.linalg.svd(Ws[:, live], full_matrices=False)
        ratio = sv[-1] / sv[0]
        if ratio >= limit:
            break
        v = np.abs(Vt[-1])
        worst = int(np.argmax(v))
        others = [names[live[i]] for i in np.flatnonzero(v > 0.1 * v.max()) if i != worst]
        combo = (f"its column is nearly a combination of {', '.join(others)}"
                 if others else "its column is nearly zero")
        reasons[names[live[worst]]] = (
            f"poorly excited: {combo} (singular value ratio {ratio:.1e}, under {limit:.0e}): "
            "the data excites too few frequencies to separate them; only their combination "
            "is identified")
        live.pop(worst)
    return reasons


def unanchored(reg, dropped: set[str]) -> dict[str, str]:
    """Parameters of a homogeneous equation (a block whose y is zero, the link equation of
    eq. 13) that lose their scale: no parameter outside `dropped` appears both in it and in
    a torque block (K does, when identified), so it only fixes ratios of the others."""
    blocks = np.unique(reg.block)
    homogeneous = [b for b in blocks if not np.any(reg.y[reg.block == b])]
    torque = np.isin(reg.block, [b for b in blocks if b not in homogeneous])
    if not homogeneous or not torque.any():
        return {}
    active = reg.W != 0
    in_torque = active[torque].any(axis=0)
    out: dict[str, str] = {}
    for b in homogeneous:
        here = active[reg.block == b].any(axis=0)
        anchors = [n for i, n in enumerate(reg.names) if here[i] and in_torque[i]
                   and n not in dropped]
        if anchors:
            continue
        lost = [n for n in dropped if n in reg.names]
        for i, n in enumerate(reg.names):
            if here[i] and not in_torque[i] and n not in dropped:
                out[n] = ("its equation has y = 0, so only ratios of its parameters are "
                          "defined, and the parameter that sets their scale against the "
                          f"torque ({', '.join(lost) or 'none'}) is not identifiable")
    return out


def _solve(reg, W: np.ndarray) -> LSResult:
    """The solver `identify` uses: block-weighted with several equation blocks."""
    if len(np.unique(reg.block)) > 1:
        return block_weighted(W, reg.y, reg.names, reg.block)
    return least_squares(W, reg.y, reg.names)


def relative_error(reg, ls: LSResult) -> float:
    """||residual|| / ||y - mean y|| over the torque rows (block 0); inf when y is constant."""
    rows = reg.block == 0
    y = reg.y[rows]
    spread = float(np.linalg.norm(y - np.mean(y)))
    res = float(np.linalg.norm(ls.residual[rows]))
    return res / spread if spread > 0 else float("inf")


def check_excitation(log: Log, reg, ls: LSResult) -> LSResult:
    """The conditioning check of the module docstring on the regressor `reg`
    (identification.models.Regressor) and its estimate `ls`. Returns `ls`, or the estimate
    without the poorly excited parameters (their reasons in `reasons`). Raises NotIdentifiable
    when no dynamic parameter is identifiable or the model explains almost nothing."""
    where = f"{log.path or '<log>'}: "
    live = [i for i, n in enumerate(ls.names) if n not in ls.unidentifiable]
    poor = poorly_excited(reg.W[:, live], tuple(ls.names[i] for i in live)) if live else {}
    poor.update(unanchored(reg, set(ls.unidentifiable) | set(poor)))
    if poor:
        W = reg.W.copy()
        W[:, [ls.names.index(n) for n in poor]] = 0.0  # same estimate as leaving them out
        try:
            solved = _solve(reg, W)
        except NotIdentifiable:
            reasons = {**ls.reasons, **poor}
            raise NotIdentifiable(
                f"{where}no parameter of the {reg.model} model is identifiable from this data: "
                + "; ".join(f"{n}: {reasons[n]}" for n in ls.names if n in reasons)) from None
        ls = replace(solved, reasons={**solved.reasons, **poor})
    dynamic = [n for n in DYNAMIC.get(reg.model, ls.names) if n in ls.names]
    if dynamic and all(n in ls.unidentifiable for n in dynamic):
        raise NotIdentifiable(
            f"{where}no dynamic parameter of the {reg.model} model is identifiable from this "
            "data: " + "; ".join(f"{n}: {ls.reasons[n]}" for n in ls.names
                                 if n in ls.unidentifiable))
    err = relative_error(reg, ls)
    if not err <= MAX_RELATIVE_ERROR:
        rel = ", ".join(f"{n} {100 * ls.std(n) / abs(ls.value(n)):.0f} %"
                        for n in dynamic if n not in ls.unidentifiable and ls.value(n) != 0)
        explained = 100 * max(0.0, 1 - err ** 2) if np.isfinite(err) else 0.0
        raise NotIdentifiable(
            f"{where}the {reg.model} model explains only {explained:.1f} % of the torque's "
            f"variation (direct validation error {100 * err:.0f} % with the mean removed, over "
            f"{100 * MAX_RELATIVE_ERROR:.0f} %): the motion does not excite the model above the "
            "noise (too small an amplitude?), so no parameter is identified"
            + (f"; relative standard deviations: {rel}" if rel else ""))
    return ls


def estimate_flags(physical: dict[str, float], sigma: dict[str, float],
                   prismatic: bool = False) -> list[dict]:
    """Flags on the physical estimates: `unphysical` for a negative stiffness, inertia (mass)
    or friction; `not_significant` for a value within two standard deviations of zero.
    Each flag is {"parameter", "flag", "value", "message"}."""
    flags = []
    kinds = {**NONNEGATIVE, **(NONNEGATIVE_PRISMATIC if prismatic else {})}
    for name, value in physical.items():
        if name in kinds and value < 0:
            flags.append({"parameter": name, "flag": "unphysical", "value": value,
                          "message": f"{name} = {value:.4g} is negative: {kinds[name]} cannot be"})
    for name, value in physical.items():
        s = sigma.get(name)
        if s is not None and np.isfinite(s) and value != 0 and abs(value) <= 2 * s:
            flags.append({"parameter": name, "flag": "not_significant", "value": value,
                          "message": f"{name} = {value:.4g} is within 2 sigma ({2 * s:.3g}) of "
                                     "zero: the data does not tell it from zero"})
    return flags
