"""The first mode f1 of an axis measured from its log, for the band of section 3.2.

With the link position `q` the link response q / tau_m = K / (s^2 (Jm JL s^2 + K (Jm + JL)))
(eqs. 5-6, undamped) is used: |H| f^2 is flat with a single peak at the mode
f1 = sqrt(K (1/Jm + 1/JL)) / 2 pi. Without `q` the motor response
q_m / tau_m = (JL s^2 + K) / (s^2 (Jm JL s^2 + K (Jm + JL))) is used: |H| f^2 dips at the
antiresonance sqrt(K / JL) / 2 pi and peaks at f1 above it.

Both are the closed-loop indirect estimate S(q_ref, out) / S(q_ref, tau_m) when `q_ref` is
logged (unbiased by the feedback), else the H1 estimate; only bins where the excitation is
coherent with both the output and the torque are used. The peak is refined by a least-squares
fit of the two-mass FRF shape (a second-order resonance, times the antiresonance for the motor
response) to log |H f^2|, which gives the undamped f1 between the bins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy import signal

from jointbench.identification.log import Log
from jointbench.identification.spectra import Spectra

COHERENCE_MIN = 0.5     # bins kept: coherence of the excitation with output and with torque
SEGMENT_S = 8.0         # Welch segment length [s] (resolution 1 / 8 s = 0.125 Hz or finer)
FMIN_HZ = 0.5           # below, friction dominates the response of a chirp experiment
MIN_PEAK_RATIO = 2.0    # a resonance: |H| f^2 at the peak over its level across the band
GAP_HZ = 1.0            # a gap this wide in the coherent bins ends the excited band
MIN_BINS = 8            # coherent bins needed around the mode for the fit
CONSISTENCY_Z = 3.0     # link and motor modes this many sigmas apart: one of them is biased
ZETA_MAX = 1.0          # a second-order pair of damping ratio 1 or more is two real poles
ANALYSIS_MIN_SAMPLES = 4096   # `analysis_log` leaves at least this many samples


@dataclass(frozen=True)
class FirstMode:
    """The first mode of an axis: `f1_hz` with its standard uncertainty `sigma_hz` [Hz],
    `method` (which response, how estimated), `found` (False: no resonance stands out, f1_hz
    is NaN) and `note` (how the value and its uncertainty were obtained, or why not found)."""

    f1_hz: float
    sigma_hz: float
    method: str
    found: bool
    note: str


def given_first_mode(f1_hz: float) -> FirstMode:
    """A first mode given by the user (`--f1`), without uncertainty."""
    return FirstMode(float(f1_hz), math.nan, "given", True, "f1 given by the user")


@dataclass(frozen=True)
class _Response:
    f: np.ndarray       # Hz
    G: np.ndarray       # -H (2 pi f)^2 exp(j w T / 2): flattened, ZOH half sample removed
    sd: np.ndarray      # standard deviation of log |G| (natural log) and of its phase [rad]
    ok: np.ndarray      # bins where the excitation is coherent with output and torque


def _response(spectra: Spectra, x: str, y: str, sl: slice, nperseg: int,
              noverlap: int | None, indirect: bool, same: bool = False) -> _Response:
    """The flattened response y / tau_m through the instrument x (log column names) on the
    samples `sl`, and the bins where it is measured. `same`: x is the torque array itself
    (H1 on the whole record), whose cross spectrum with the torque is its real Welch
    spectrum."""
    kw = dict(nperseg=nperseg, noverlap=noverlap, sl=sl)
    f = spectra.frequencies(nperseg)
    fs = spectra.hold_hz
    s_xy = spectra.csd(x, y, **kw)
    s_xt = spectra.welch(x, **kw) if same else spectra.csd(x, "tau_m", **kw)
    with np.errstate(divide="ignore", invalid="ignore"):   # constant signals: 0 / 0
        c_xy = spectra.coherence(x, y, **kw)
        c_xt = spectra.coherence(x, "tau_m", **kw) if indirect else np.ones_like(f)
    c_xy, c_xt = np.nan_to_num(c_xy), np.nan_to_num(c_xt)
    step = nperseg - (noverlap if noverlap is not None else nperseg // 2)
    n_avg = max(1, (len(spectra.log.t[sl]) - nperseg) // step + 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        # the torque is held over each period (ZOH): it acts half a sample late on average
        G = -(s_xy / s_xt) * (2 * np.pi * f) ** 2 * np.exp(1j * np.pi * f / fs)
        # relative variance of an FRF estimate: (1 - g^2) / (2 n g^2) per coherence
        # (Bendat & Piersol), for both spectra of the indirect ratio
        sd = np.sqrt(sum((1 - c) / (2 * n_avg * c) for c in (c_xy, c_xt)))
    ok = (c_xy >= COHERENCE_MIN) & (c_xt >= COHERENCE_MIN) & np.isfinite(G) & (f >= FMIN_HZ) \
        & (G != 0)
    return _Response(f, G, np.where(ok, sd, np.inf), ok)


def _nan(why: str) -> tuple[float, float, str]:
    return math.nan, math.nan, why


def _fit(resp: _Response, motor: bool, checks: bool = True) -> tuple[float, float, str]:
    """(f1, its fit standard deviation, '') or (nan, nan, why).

    The peak of |G| (above the antiresonance dip for the motor response) locates the mode
    coarsely; f1 is where the phase of G crosses -90 deg (link) or +90 deg (motor, the
    antiresonance zero having added 180 deg): a resonance's phase passes 90 deg at its
    undamped frequency whatever its damping (the arm's, from Coulomb friction, reaches
    zeta ~ 0.2, which puts the magnitude peak 4 % low). A weighted straight line through the
    phases within 40 deg of the target gives the crossing between bins. `checks` (off for
    the half-records `_measure` takes the spread from: the whole record has accepted the
    mode) rejects a link peak off the mass line (`_off_mass_line`) and an overdamped
    crossing (`_overdamped`)."""
    f, good = resp.f, np.flatnonzero(resp.ok)
    gaps = np.flatnonzero(np.diff(f[good]) > GAP_HZ)
    good = good[:gaps[0] + 1] if len(gaps) else good   # the excited band: no stray bins above
    if len(good) < MIN_BINS:
        return _nan("too few coherent frequency bins (too little excitation)")
    with np.errstate(divide="ignore"):
        mag = np.log10(np.abs(resp.G))
    level = float(np.median(mag[good]))
    search = good
    if motor:
        dip = good[np.argmin(mag[good])]
        search = good[good > dip]
        if len(search) == 0:
            return _nan("no peak above the antiresonance dip")
    k = search[np.argmax(mag[search])]
    if k == good[-1] or k == good[0]:
        return _nan(f"the largest |H| f^2 lies at the edge of the excited band ({f[k]:.3g} Hz): "
                    "no resonance inside it")
    ratio = 10 ** (mag[k] - (mag[dip] if motor else level))
    need = MIN_PEAK_RATIO ** 2 if motor else MIN_PEAK_RATIO
    if ratio < need:
        return _nan(f"no resonance stands out: the peak of |H| f^2 at {f[k]:.3g} Hz is "
                    f"{ratio:.2g} times its {'dip' if motor else 'median level'} (needs {need:g})")
    target = np.pi / 2 if motor else -np.pi / 2
    # friction adds the rigid body's phase lead atan(c / (w J)), ~1/f: measured on the flat
    # part well below the mode (or the antiresonance), carried to the peak and removed
    low = good[(f[good] >= 0.4 * f[dip if motor else k]) & (f[good] <= 0.6 * f[dip if motor else k])]
    if len(low) and not motor:   # below the dip the antiresonance's own phase dominates
        lead = np.angle(np.sum(resp.G[low] / np.abs(resp.G[low])))
        if checks and not abs(lead) < np.pi / 2:
            return _nan(_off_mass_line(f[k], lead))
        target += float(lead * np.mean(f[low]) / f[k])
    win = search[(f[search] >= 0.7 * f[k]) & (f[search] <= 1.4 * f[k])]
    phase = np.unwrap(np.angle(resp.G[win]))
    phase += 2 * np.pi * np.round((target - phase[np.argmin(abs(win - k))]) / (2 * np.pi))
    near = np.abs(phase - target) < np.radians(40)
    if near.sum() < 3 or not (phase.max() > target > phase.min()):
        sharp = _sharp_crossing(resp, k, target)
        if sharp is not None:
            return sharp, float(f[1] - f[0]), ""
        return _nan(f"the phase does not cross {np.degrees(target):+.0f} deg near the peak at "
                    f"{f[k]:.3g} Hz: no resonance")
    w = 1.0 / resp.sd[win][near]
    A = np.column_stack([np.ones(near.sum()), f[win][near] - f[k]])
    coef, *_ = np.linalg.lstsq(A * w[:, None], phase[near] * w, rcond=None)
    if not coef[1] < 0:
        return _nan(f"the phase rises through the peak at {f[k]:.3g} Hz: no resonance")
    f1 = float(f[k] + (target - coef[0]) / coef[1])
    span = f[win]   # the window the crossing was found in (phase.max() > target > phase.min())
    if not span.min() <= f1 <= span.max():
        return _nan(f"the phase line through the peak at {f[k]:.3g} Hz crosses "
                    f"{np.degrees(target):+.0f} deg at {f1:.3g} Hz, outside the window it was "
                    f"found in ({span.min():.3g}-{span.max():.3g} Hz): no resonance")
    why = _overdamped(f1, float(coef[1])) if checks else ""
    if why:
        return _nan(why)
    res = (phase[near] - A @ coef) * w
    cov = np.linalg.inv((A * w[:, None]).T @ (A * w[:, None])) * max(
        float(res @ res) / max(1, near.sum() - 2), 1.0)
    g = np.array([-1.0, -(target - coef[0]) / coef[1]]) / coef[1]   # d f1 / d coef
    return f1, float(np.sqrt(g @ cov @ g)), ""


def _off_mass_line(f_peak: float, lead: float) -> str:
    """Why a link peak whose flat band below is off the mass line is no first mode. Below the
    mode the flattened link response is the mass line 1 / (Jm + JL), real and positive,
    turned by the friction's lead atan(c / (w J)) (under 90 deg) or a delay's small lag: a
    phase of 90 deg or more there is another resonance below (a pendulum's gravity mode
    sqrt(MY g / (Jm + JL)), which a damped hardening pendulum can show well below its mode)."""
    return (f"the link response below its peak at {f_peak:.3g} Hz is off the mass line (phase "
            f"{np.degrees(lead):+.0f} deg at 0.4-0.6 times the peak; friction leads it by "
            "less than 90 deg): the peak is not the first mode (a resonance below it?)")


def _overdamped(f1: float, slope: float) -> str:
    """Why the phase crossing at `f1` [Hz], falling at `-slope` [rad/Hz], is no resonance, or
    "". A second-order pair's phase falls through its crossing at 1 / (zeta f1) rad/Hz; at a
    damping ratio zeta of ZETA_MAX (1) or more it is two real poles, no mode: such a shallow
    crossing is the slow turn of a response between two bands."""
    zeta = -1.0 / (f1 * slope)
    if zeta < ZETA_MAX:
        return ""
    return (f"the phase falls through the crossing at {f1:.3g} Hz at only {-slope:.2g} rad/Hz, "
            f"a damping ratio {zeta:.2g} (a mode has under {ZETA_MAX:g}): no resonance")


def _sharp_crossing(resp: _Response, k: int, target: float) -> float | None:
    """f1 of a lightly damped mode, or None: its phase falls through the target within a bin or
    two where the coherence drops (the chirp crosses the mode in a fraction of a segment), so
    the crossing is interpolated between the bins next to the peak whatever their coherence;
    its uncertainty is one bin."""
    f = resp.f
    idx = np.flatnonzero(np.isfinite(resp.G) & (resp.G != 0) & (f >= 0.8 * f[k])
                         & (f <= 1.25 * f[k]))
    if len(idx) < 3:
        return None
    phase = np.unwrap(np.angle(resp.G[idx]))
    phase += 2 * np.pi * np.round((target - phase[np.argmin(abs(idx - k))]) / (2 * np.pi))
    s = phase - target
    cross = np.flatnonzero((s[:-1] > 0) & (s[1:] <= 0))
    if not len(cross):
        return None
    i = int(cross[np.argmin(abs(f[idx[cross]] - f[k]))])
    return float(f[idx[i]] + s[i] / (s[i] - s[i + 1]) * (f[idx[i + 1]] - f[idx[i]]))


def measure_first_mode(log: Log) -> FirstMode:
    """The first mode of the axis of `log` from its measured frequency response (module
    docstring): the link's when `q` is logged, else the motor's. When the link response shows
    no resonance the motor response is tried (`_from_motor`). The uncertainty `sigma_hz`
    combines the fit's standard deviation, half the difference between the estimates on two
    interleaved sets of non-overlapping Welch segments (each set covers the whole record, so
    both see the chirp cross the mode) and the bin width / sqrt(12). `found` is False, with
    the reason in `note`, when no resonance stands out of the coherent band (a rigid axis, too
    little excitation). With `q`, a link mode is cross-checked against the motor response's
    (`_cross_checked`): when the two disagree, `sigma_hz` covers both."""
    work, spectra = analysis_log(log)
    mode = _measure(work, motor=log.q is None, spectra=spectra)
    if log.q is None:
        return _excitation_checked(work, mode, spectra)
    mode = _cross_checked(mode, _measure(work, motor=True, spectra=spectra)) if mode.found \
        else _from_motor(work, mode, spectra)
    return _excitation_checked(work, _with_link_mode(work, mode, spectra), spectra)


def analysis_log(log: Log) -> tuple[Log, Spectra]:
    """The record the responses are measured on, and its spectra: the log, or a copy
    decimated by the largest power of two D (`filtering.decimate`: the zero-phase anti-alias
    filter, every D-th sample) whose anti-alias cutoff 0.8 fs / (2 D) stays at or above the
    top of the band the responses are read in, 1.1 times the excitation's top
    (`link_mode.excitation_top_hz`, on the logged record), and which leaves at least
    ANALYSIS_MIN_SAMPLES samples (the filter's start-up at the ends stays a small share of
    the record). Segments of 1/D the samples at fs / D give the same bins; the anti-alias
    filter, common to every signal, leaves the responses (ratios of their spectra) and the
    coherences unchanged in that band; the torque's zero-order hold stays the logged rate's
    (`Spectra.hold_hz`). D times fewer samples to transform (a 60 s prototype log: D = 4)."""
    from jointbench.identification.filtering import decimate
    from jointbench.identification.link_mode import excitation_top_hz

    full = Spectra(log)
    top = excitation_top_hz(log, full)
    fs, D = log.sample_rate_hz, 1
    while np.isfinite(top) and 0.8 * fs / (2 * 2 * D) >= 1.1 * top \
            and len(log) // (2 * D) >= ANALYSIS_MIN_SAMPLES:
        D *= 2
    if D == 1:
        return log, full
    cols = {name: decimate(np.asarray(getattr(log, name), dtype=float), D)
            for name in ("q_m", "tau_m", "q", "q_ref") if getattr(log, name) is not None}
    work = replace(log, t=np.asarray(log.t)[::D], extra={},
                   meta={**log.meta, "sample_rate_hz": repr(fs / D)}, **cols)
    spectra = Spectra(work, hold_hz=fs, decimation=D)
    spectra.memo("link_mode.excitation_top_hz", lambda: top)
    return work, spectra


def _with_link_mode(log: Log, mode: FirstMode, spectra: Spectra | None = None) -> FirstMode:
    """`mode`, or the first mode from the link-over-motor response q / q_m
    (identification.link_mode) where that one decides: when the peak responses give none,
    when the link and motor peaks disagree (`_cross_checked`: one is biased and nothing else
    says which), when only the motor response has a peak (a motor side damped by a voltage
    drive's back-EMF or a stiff loop flattens the locked peak and moves it to its damped
    frequency, while q / q_m keeps the link mode sharp), when the link peak alone lies more
    than CONSISTENCY_Z sigmas of their difference from q / q_m's f1 (the peak of a closed
    loop's q / q_ref is that loop's; q / q_m, eq. (5) alone, holds no controller), or when
    the excitation stops under f1 (the locked peak outside it, the link mode below it). The
    note says which response decided and what the others gave."""
    from jointbench.identification.link_mode import excitation_top_hz, link_mode_first_mode

    disagree = "DISAGREES" in mode.note
    beyond = mode.found and excitation_top_hz(log, spectra) < mode.f1_hz
    alt = link_mode_first_mode(log, spectra)
    if alt is None:
        return mode
    f1, sigma, method, note = alt
    motor_only = mode.found and not mode.method.startswith("link q/tau_m")
    # a lone link peak that q / q_m contradicts: under a loop on q_m the link's closed-loop
    # peak is the loop's, not the axis's, while q / q_m holds the axis alone
    contradicted = (mode.found and not (disagree or beyond or motor_only)
                    and abs(mode.f1_hz - f1) > CONSISTENCY_Z * math.hypot(mode.sigma_hz, sigma))
    if mode.found and not (disagree or beyond or motor_only or contradicted):
        return mode
    why = ("the excitation stops under the peaks' f1" if beyond else
           "the link and motor peaks disagree" if disagree else
           "only the motor response has a peak" if motor_only else
           "the link peak contradicts the link over motor response" if contradicted else
           "the peak responses show no mode")
    other = (f"{mode.method} gave {mode.f1_hz:.4g} +- {mode.sigma_hz:.2g} Hz" if mode.found
             else f"{mode.method}: {mode.note}")
    return FirstMode(f1, sigma, f"{method} (decided: {why})", True, f"{note}; {other}")


def _excitation_checked(log: Log, mode: FirstMode, spectra: Spectra | None = None
                        ) -> FirstMode:
    """`mode` with a note when the excitation stops under EXCITATION_MARGIN times f1 (the
    band of section 3.2 reaches about 1.4 f1: its top then holds little excitation)."""
    from jointbench.identification.link_mode import EXCITATION_MARGIN, excitation_top_hz

    if not mode.found:
        return mode
    top = excitation_top_hz(log, spectra)
    if not top < EXCITATION_MARGIN * mode.f1_hz:
        return mode
    return replace(mode, note=f"{mode.note}; the excitation stops near f1: 99 % of its "
                   f"derivative's power lies under {top:.3g} Hz, {top / mode.f1_hz:.2g} f1 "
                   f"(under {EXCITATION_MARGIN:g} f1)")


def _cross_checked(link: FirstMode, motor: FirstMode) -> FirstMode:
    """`link` with its sigma widened when the motor response's mode `motor` (the same mode,
    seen through another output) lies more than CONSISTENCY_Z sigmas of their difference
    from it: one of the two is biased and nothing in the log says which, so the difference
    enters the sigma whole, sqrt(sigma^2 + d^2), which covers either being right. f1 stays
    the link's: the band is designed from it."""
    if not motor.found:
        return link
    d, sd = link.f1_hz - motor.f1_hz, math.hypot(link.sigma_hz, motor.sigma_hz)
    if not abs(d) > CONSISTENCY_Z * sd:
        return link
    sigma = math.hypot(link.sigma_hz, d)
    return replace(link, sigma_hz=sigma, note=(
        f"{link.note}; DISAGREES with the motor response q_m/tau_m ({motor.f1_hz:.4g} +- "
        f"{motor.sigma_hz:.2g} Hz, {abs(d) / sd:.1f} sigma apart): sigma widened to "
        f"{sigma:.2g} Hz to cover both"))


def _from_motor(log: Log, link: FirstMode, spectra: Spectra | None = None) -> FirstMode:
    """The motor response's first mode when the link's (`link`, not found) shows none: a
    mode damped by the friction flattens |q / tau_m| f^2 to a bump (the independent
    simulator without velocity feed-forward: 1.3-1.8 times its median level, the 2 it needs),
    while q_m / tau_m still has its antiresonance dip under it, whose depth the motor test
    measures. Not found by either: the
    link's reason and the motor's."""
    motor = _measure(log, motor=True, spectra=spectra)
    if not motor.found:
        return replace(link, note=f"{link.note}; the motor response: {motor.note}")
    return replace(motor, method=f"{motor.method} (the link response shows no resonance)",
                   note=f"{motor.note}; the link response q/tau_m: {link.note}")


def _measure(log: Log, motor: bool, spectra: Spectra | None = None) -> FirstMode:
    """`measure_first_mode` on one response: the motor's (`motor`) or the link's."""
    spectra = spectra or Spectra(log)
    fs = log.sample_rate_hz
    indirect = log.q_ref is not None
    out = "q_m" if motor else "q"
    x = "q_ref" if indirect else "tau_m"
    method = ("motor q_m/tau_m" if motor else "link q/tau_m") + \
        (", indirect via q_ref" if indirect else ", H1 (no q_ref)")
    n = len(log)
    nperseg = int(min(2 ** math.ceil(math.log2(SEGMENT_S * fs)), 2 ** math.floor(math.log2(n / 2))))
    if nperseg < 64:
        return FirstMode(math.nan, math.nan, method, False, f"{n} samples are too few")
    df = fs / nperseg
    f1, sd_fit, why = _fit(_response(spectra, x, out, slice(None), nperseg, None, indirect,
                                     same=not indirect), motor)
    if why:
        return FirstMode(math.nan, math.nan, method, False, why)
    half = nperseg // 2
    parts = [_fit(_response(spectra, x, out, sl, nperseg // 2, 0, indirect), motor, False)[0]
             for sl in (slice(0, n - half), slice(half, n))]
    spread = abs(parts[0] - parts[1]) / 2 if all(np.isfinite(parts)) else math.nan
    terms = [sd_fit, df / math.sqrt(12)] + ([spread] if np.isfinite(spread) else [])
    sigma = float(math.sqrt(sum(v ** 2 for v in terms if np.isfinite(v))))
    note = (f"phase crossing at the peak of |H| f^2 (ZOH half sample removed), Welch segments "
            f"of {nperseg * spectra.decimation} samples (bins {df:.3g} Hz), coherence >= "
            f"{COHERENCE_MIN:g}; "
            f"sigma {sigma:.3g} Hz from the fit ({sd_fit:.2g} Hz), the bin width "
            f"({df / math.sqrt(12):.2g} Hz) and "
            + (f"half the spread of two interleaved segment sets ({spread:.2g} Hz: "
               f"{parts[0]:.4g}, {parts[1]:.4g} Hz)" if np.isfinite(spread) else
               "no spread (a segment set found no resonance)"))
    return FirstMode(f1, sigma, method, True, note)
