"""`torque_ripple`: a torque A sin(2 pi qm / p + phase) periodic in the motor angle."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows

ORDER = 30


def design(rows: Rows, fixed: dict) -> Design:
    """The columns sin and cos of 2 pi qm / p as the aligned torque holds them (held), and
    their pointwise samples as the rate a torque lag leads them by (`rated`).

    The aligned torque (identification.filtering.zoh_align) is the mean of the held command
    over [t_k-1, t_k+1]; a ripple acts on the rotor continuously in the motor angle, so the
    torque holds the ripple's mean over that window, not its sample at t_k. Where the motor
    turns a sizeable part of a period in a sample the two differ: the mean shrinks as
    sinc, the sample keeps its size and, past half a period a sample, aliases. A lag's
    command is u + T u' on each hold exactly (torque_lag), whose mean over the window is
    T (u(t_k+1) - u(t_k-1)) / 2 ts: the lead is the 3-point difference of the pointwise
    samples (stacked.led_extra), whatever the ripple's frequency."""
    ph = 2 * np.pi * rows.sig.qm / fixed["ripple_period_rad"]
    s, c = np.sin(ph), np.cos(ph)
    hs, hc = held(ph, s, c)
    return rows.extend(("As", hs, None), ("Ac", hc, None), rated=(s, c))


def held(ph: np.ndarray, s: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The means of sin and cos of the phase over [t_k-1, t_k+1] from the sampled phases `ph`
    (`s`, `c` their sin and cos), the phase linear between samples: over [t_k, t_k+1] the mean
    is f(m) sinc(d / 2), m the interval's middle phase and d its step (the mean of sin(m + x)
    over |x| < d / 2); the window's, the mean of two intervals'. The sample itself at the ends
    and where a neighbour's phase is undefined."""
    if len(ph) < 3:
        return s, c
    d = np.diff(ph)
    m = ph[:-1] + d / 2
    g = np.sinc(d / (2 * np.pi))
    finite = bool(np.isfinite(d).all())
    out = []
    for f, at in ((np.sin, s), (np.cos, c)):
        interval = f(m)
        interval *= g
        window = at.copy()
        np.add(interval[:-1], interval[1:], out=window[1:-1])
        window[1:-1] *= 0.5
        if not finite:
            window[1:-1] = np.where(np.isfinite(window[1:-1]), window[1:-1], at[1:-1])
        out.append(window)
    return out[0], out[1]


# Periods from encoder-scale steps to the motion span: the span over this many.
SHORTEST = 2000
# The coarse geometric grid's points, and the periodogram's peaks added to it.
COARSE, PEAKS = 160, 3
# A ripple is seen while the motor turns: the samples where its column lies in the band must
# be this many times those where it does at the encoder-scale step, so that most of them are
# samples where the motor turns (seen_from, check).
SEEN = 2.0
# Periods the span of the motor angle must hold for a ripple to show that it repeats (check):
# every phase of the period then seen at two angles a period apart.
REPEATS = 2
# Bins of the motor angle a shortest period holds in the periodogram's FFT.
BINS = 8


def _periodogram_peaks(rows: Rows, span: float) -> np.ndarray:
    """The wavenumbers k = 2 pi / p of the PEAKS highest local maxima of the periodogram
    |sum r(q_m) e^(-i k q_m)|^2 of the motor-equation residual r of `rows` (the nominal's,
    or what the causes named before leave: discrepancy.candidates._Left) as a function of
    the motor angle q_m of its rows, on a uniform grid of step pi / (2 span): a period p off
    by dp drifts by span dp / p^2 periods over the span, and a quarter period is where the
    column stops following the torque, dk = 2 pi dp / p^2 < pi / (2 span). A coarse geometric
    grid (COARSE points, a few % apart) misses a short period entirely when the span holds
    many of them (a drive's ripple 2 pi / (6 N) with the gear ratio N: some 80 periods over a
    rad). The sum is an FFT of r binned on q_m (BINS bins a shortest period, the phase within
    a bin at most pi / BINS), zero-padded to 4 spans, each bin holding the mean of its rows'
    r: a sum over the rows would weigh each angle by the time the motor dwells there, and a
    strong ripple modulates that time at its own period (the motor slows where the ripple
    opposes it and rests in its wells), so the sum carries the product of two sinusoids of
    the period, a peak at half the period that can outgrow the period's own."""
    sig = rows.sig
    res, block = getattr(rows, "residual", None), getattr(rows, "block", None)
    if res is None or block is None:
        return np.empty(0)
    r = np.asarray(res)[np.asarray(block) == 0]
    q = sig.qm[sig.index]
    if len(q) != len(r) or len(r) < 8 or not np.all(np.isfinite(r)):
        return np.empty(0)
    n = BINS * SHORTEST
    dx = span / n
    at = np.minimum(((q - q.min()) / dx).astype(int), n - 1)
    count = np.bincount(at, minlength=n)
    binned = np.bincount(at, weights=r - r.mean(), minlength=n) / np.maximum(count, 1)
    pw = np.abs(np.fft.rfft(binned, 4 * n)) ** 2   # wavenumber j 2 pi / (4 n dx)
    step = np.pi / (2 * span)
    j = np.arange(len(pw))
    usable = (j * step >= 2 * np.pi / span) & (j * step <= 2 * np.pi * SHORTEST / span)
    peak = np.flatnonzero(usable[1:-1] & (pw[1:-1] > pw[:-2]) & (pw[1:-1] >= pw[2:])) + 1
    top = peak[np.argsort(pw[peak])[::-1][:PEAKS]]
    return top * step


def grid(rows: Rows) -> np.ndarray:
    """Periods from encoder-scale steps to the motion span (the column must vary): a coarse
    geometric grid and, around each of the periodogram's peaks (_periodogram_peaks), the
    peak and its neighbours one wavenumber step either side, sorted so that the search's
    refinement (candidates._search) brackets the best between its grid neighbours. A peak
    below the coarse grid's start is kept where the motor's rests repeat at it
    (rests_repeat): the rests in a strong ripple's wells raise that start (seen_from)."""
    sig = rows.sig
    span = float(np.ptp(sig.qm[sig.sl]))
    coarse = _coarse(rows)
    if span <= 0:
        return coarse
    step = np.pi / (2 * span)
    k = _periodogram_peaks(rows, span)
    fine = 2 * np.pi / np.concatenate([k - step, k, k + step]) if len(k) else np.empty(0)
    fine = fine[(fine > 0) & (fine <= coarse[-1])]
    below = fine < coarse[0]
    if below.any():
        # a strong ripple's rests, counted as still samples, raise the grid's start
        # (seen_from) above its period: a peak below it is searched where the rests repeat
        below[below] = ~rests_repeat(rest_angles(rows), fine[below])
    return np.unique(np.concatenate([coarse, fine[~below]]))


def _coarse(rows: Rows) -> np.ndarray:
    """The coarse geometric grid of periods (grid): encoder-scale steps to the motion span,
    its points from the shortest period seen while the motor turns (seen_from) on, the
    last two at least."""
    sig = rows.sig
    span = float(np.ptp(sig.qm[sig.sl]))
    g = np.geomspace(_encoder_step(span), max(span, 2e-4), COARSE)
    return g[min(int(np.searchsorted(g, seen_from(rows))), COARSE - 2):]


def _encoder_step(span: float) -> float:
    return max(span / SHORTEST, 1e-4)


def seen_from(rows: Rows) -> float:
    """The shortest period whose column sin(2 pi qm / p) is in the band (its frequency
    |qm'| / p under the band's decimated cutoff f_c) over at least SEEN times the samples
    where it is at the encoder-scale step (check): the |qm'| quantile of that share over
    f_c; 0 where the column is in the band nowhere at that step, or the signals carry no
    speed or band."""
    sig = rows.sig
    qmd, settings = getattr(sig, "qmd", None), getattr(sig, "settings", None)
    if qmd is None or settings is None:
        return 0.0
    v = np.abs(np.nan_to_num(np.asarray(qmd)[sig.sl]))
    if not len(v):
        return 0.0
    fc = settings.decimated_cutoff_hz
    still = float(np.mean(v < fc * _encoder_step(float(np.ptp(sig.qm[sig.sl])))))
    return float(np.quantile(v, min(1.0, SEEN * still))) / fc if still > 0 else 0.0


def check(v: dict, rows: Rows) -> str:
    """A ripple is a torque that repeats with the motor angle: the log shows that only where
    it holds the same phase at two angles a period apart, and every phase of a period p is
    seen so when the span of the motor angle it covers holds REPEATS periods (p <= span / 2).
    A longer period is one arch of a sinusoid over the travel, which a constant and the slow
    terms of the nominal (the spring's and gravity's torques, a function of the angle where
    the motor spends its time) follow as well: an offset fits it, and the search's top, the
    span itself, is where it runs to when the log carries a constant torque. Such a fit is
    not a physical instance of the effect.

    A period in the first step of its search grid is where the search ran to its bound,
    not a period the log identifies. The grid starts at encoder-scale steps, where the column
    sin(2 pi qm / p) is in the band (its frequency |qm'| / p under the band's decimated
    cutoff) only where the motor creeps or sticks, or where the samples that put it in the
    band stop being mostly ones where the motor turns (seen_from: fewer than SEEN times those
    of the encoder-scale step; on a motor that sticks for long, a third of the samples, the
    step is well short of that). Shorter, the column is in the band mostly where the motor
    creeps or sticks, at the reversals and in the small strokes of a chirp's top, and there
    it takes up what the nominal's friction law near zero speed misses (a sticking motor's
    friction holds a torque that grows with its small displacement, a presliding stiffness,
    which a short sinusoid of the angle follows) and the position's resolution: a function of
    the angle where the motor creeps, not a ripple of the drive. (A sticking motor does not
    show a ripple either: its friction holds it.) Unless the motor rests in the fitted
    ripple's wells (rests_in_wells): a strong ripple stops the motor there, its still samples
    then raise the grid's start above the period that holds them, and a period in the first
    step, or below it (grid), is the ripple's own."""
    p = v.get("ripple_period_rad", 0.0)
    if not p:
        return ""
    span = float(np.ptp(rows.sig.qm[rows.sig.sl]))
    if p * REPEATS > span:
        return (f"period {p:.3g} rad: the motor angle the log covers ({span:.3g} rad) holds "
                f"fewer than {REPEATS} periods, so no phase of it is seen at two angles a "
                "period apart: a smooth function of the angle over the travel (a constant "
                "and slow terms), not a periodic torque")
    g = _coarse(rows)
    if p >= g[1] or rests_in_wells(v, rows):
        return ""
    return (f"period {p:.3g} rad in the first step of its search grid ({g[0]:.3g} to "
            f"{g[1]:.3g} rad, from encoder-scale steps or the shortest period seen while "
            "the motor turns): the search ran to its bound, a function of the angle where "
            "the motor creeps, not a ripple")


def rests_repeat(rest: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """Per period p, do the rest angles `rest` (rest_angles) repeat at it? They span
    REPEATS periods (the span check asks of the motor angle: rests within one period of
    each other cluster at any period longer than their scatter, and tell no period), their
    phases 2 pi rest / p are not uniform (rayleigh_p under the held-out test's level ALPHA)
    and repeat less at 2 p (mean resultant length R(2 p) < R(p)). A ripple stronger than the
    motor's friction stops it in its wells, one a period apart: the rests repeat at the
    period, at its harmonics p / m less (R^(m^2) for phases spread normally) and at its
    multiples hardly (alternate wells fall half a period apart), so a harmonic of the wells'
    period repeats more at twice its own. A presliding stiffness or the position's
    resolution leave the phases uniform at a period much shorter than the rests' spread."""
    from jointbench.identification.discrepancy.heldout import ALPHA

    out = []
    for p in np.atleast_1d(periods):
        if not len(rest) or np.ptp(rest) < REPEATS * p:
            out.append(False)
            continue
        r1 = abs(np.mean(np.exp(2j * np.pi * rest / p)))
        r2 = abs(np.mean(np.exp(1j * np.pi * rest / p)))
        out.append(rayleigh_p(rest, p) < ALPHA and r2 < r1)
    return np.array(out, bool)


def rests_in_wells(v: dict, rows: Rows) -> bool:
    """Does the motor rest in the wells of the fitted ripple A sin(2 pi qm / p + phase)
    (params' convention, the torque added to the rotor)? A ripple stronger than the motor's
    Coulomb friction stops the motor where its torque pushes it back, 2 pi qm / p + phase
    near pi (mod 2 pi): the rest angles' phases at p cluster there. A presliding stiffness or
    the position's resolution, which a short sinusoid of the angle also follows where the
    motor creeps, leaves them uniform at any period much shorter than the angles the motor
    rests at. The rests repeat at the fitted period (rests_repeat) and their mean phase is
    on the wells' side (within pi / 2 of pi - phase)."""
    p = v.get("ripple_period_rad", 0.0)
    if not p or not {"As", "Ac"} <= v.keys():
        return False
    rest = rest_angles(rows)
    if not rests_repeat(rest, np.array([p]))[0]:
        return False
    m = np.mean(np.exp(2j * np.pi * rest / p))
    phase = float(np.arctan2(-v["Ac"], -v["As"]))
    off = np.angle(m * np.exp(1j * (phase - np.pi)))
    return bool(abs(off) < np.pi / 2)


def rest_angles(rows: Rows) -> np.ndarray:
    """One motor angle per rest, in time order: the mean angle of each rest's still rows.
    A still row is one of the regression's decimated rows (the band's independent samples)
    where |qm'| is under the band's decimated cutoff times the encoder-scale step, as
    seen_from counts it. Successive runs of still rows between which the motor does not
    leave the position's resolution (its angle within one encoder-scale step) are one rest:
    a motor settling about one angle reverses there again and again, and those runs are not
    independent samples of the wells, as Rayleigh's test (rayleigh_p) takes its samples. A
    rest holds the motor still over two rows at least: one still row alone is as well the
    motor reversing through zero speed. A rest at the angle of an earlier one (within one
    encoder-scale step) counts once: a motor the command returns to one angle has the same
    phase there at every period, which tells none."""
    sig = rows.sig
    qmd, settings = getattr(sig, "qmd", None), getattr(sig, "settings", None)
    idx = getattr(sig, "index", None)
    if qmd is None or settings is None or idx is None:
        return np.empty(0)
    idx = np.asarray(idx)
    span = float(np.ptp(sig.qm[sig.sl]))
    step = _encoder_step(span)
    still = np.abs(np.nan_to_num(np.asarray(qmd)[idx])) < settings.decimated_cutoff_hz * step
    edges = np.diff(np.concatenate([[0], still.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    qm = np.asarray(sig.qm)[idx]
    rests: list[tuple[int, int]] = []
    for a, b in zip(starts, ends):
        if rests and np.ptp(qm[rests[-1][0]:b]) < step:
            rests[-1] = (rests[-1][0], b)
        else:
            rests.append((a, b))
    out: list[float] = []
    for a, b in rests:
        angle = float(np.mean(qm[a:b][still[a:b]]))
        if np.count_nonzero(still[a:b]) >= 2 and all(abs(angle - o) >= step for o in out):
            out.append(angle)
    return np.array(out)


def rayleigh_p(angles: np.ndarray, period: float) -> float:
    """Rayleigh's test that the phases 2 pi angles / period are uniform: the p-value of
    their mean resultant length R (Zar, Biostatistical Analysis, eq. 27.4:
    p = exp(sqrt(1 + 4 n + 4 (n^2 - (n R)^2)) - (1 + 2 n)))."""
    n = len(angles)
    if n < 2 or not period > 0:
        return 1.0
    r = n * abs(np.mean(np.exp(2j * np.pi * np.asarray(angles) / period)))
    return float(np.exp(np.sqrt(1 + 4 * n + 4 * (n ** 2 - r ** 2)) - (1 + 2 * n)))


def params(v: dict, fixed: dict, rows: Rows) -> dict[str, float]:
    # The bench's ripple adds A sin(2 pi qm / p + phase) to the rotor torque: the logged
    # torque carries -A sin(...).
    return {"ripple_amplitude": float(np.hypot(v["As"], v["Ac"])),
            "ripple_period_rad": fixed["ripple_period_rad"],
            "ripple_phase_rad": float(np.arctan2(-v["Ac"], -v["As"]))}


EFFECT = Effect(
    "torque_ripple", "ripple_amplitude", "N m", "N",
    "torque ripple periodic in the motor angle (cogging, drive ripple)",
    needs_link=False, rigid_axis=True, block=0, k=3, design=design, params=params,
    search="ripple_period_rad", grid=grid, period="ripple_period_rad", check=check)
