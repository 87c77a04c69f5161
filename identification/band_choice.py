"""The band of the joint-motor fit chosen by the log's own precision.

Two candidates: the chooser's band (`defaults.choose_filter`: decimated cutoff about 1.4 f1)
and a wide one, the chooser's Butterworth with the decimation lowered until the decimated
cutoff 0.8 Fs / (2 Nd) reaches the top of what the log can give (`wide_settings`: the
excitation's top measured on the log, capped where the 5-point stencil or the zero-phase
Butterworth would distort the band by more than defaults.STENCIL_DISTORTION_MAX, the 1 %
the chooser's stencil rule allows). The chooser's band throws away the excitation between
1.4 f1 and the sweep's top, which carries most of what the motor inertia is seen by.

The rule (`choose_band`): both are fitted; the one whose largest relative corrected sigma
of K, Jm, JL (the fit's own autocorrelation-consistent covariance) is the smaller is kept,
unless, when the wide one is the more precise, the two estimates lie more than 3 sigmas of
their difference apart on any of K, Jm, JL (`CONSISTENCY_Z`; Hausman's test: both fit the
same log, so the difference of two unbiased estimates has the variance |sigma_a^2 -
sigma_b^2|): one of them is then biased, which no precision can settle alone, and the
chooser's band stays with a warning, unless the measured first mode settles it
(`mode_gap`): the chooser's band was designed for the mode the frequency response measured
(the fits' arbiter, independent of both), and a chooser's fit whose two-mass model puts the
mode more than MODE_DISAGREEMENT from it, while the wide fit's holds it within that, has
missed its own design; the wide band is then kept, still with the warning. The
difference's variance is Hausman's, not a root-sum-square bound, which is too lenient: it
lets the wide band win near-ties whose K differs from the chooser's. No threshold is tuned
on test cases:
the 1 % budgets are the chooser's, the 3 sigma the suite's. Pure numerics; the caller fits
both bands (`wide_settings` gives the wide one) and hands both fits to `choose_band`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable, TypeVar

import numpy as np
from scipy import signal
from scipy.optimize import brentq

from jointbench.identification.filter_choice import STENCIL_DISTORTION_MAX, stencil_for
from jointbench.identification.filtering import FilterSettings, stencil_gain
from jointbench.identification.log import Log

PRECISION_PARAMS = ("K", "Jm", "JL")
# Two estimates of one parameter from the same log farther apart than this many standard
# deviations of their difference (`disagreement`) are not both unbiased: the usual 3 sigma
# of the test suite.
CONSISTENCY_Z = 3.0
MODE_DISAGREEMENT = 0.2   # relative gap between the two f1 estimates that voids the band
WELCH_SEGMENT_S = 8.0   # Welch segments for the excitation's spectrum (0.125 Hz), as first_mode

Fit = TypeVar("Fit")


@dataclass(frozen=True)
class BandChoice:
    """What `choose_band` did: `used` ("chooser" or "wide"), the alternative's settings and
    its largest relative corrected sigma of K, Jm, JL (`alt_rel_sigma`, NaN when not fitted),
    the used band's (`rel_sigma`), the excitation's top [Hz] and the one-line reason."""

    used: str
    rel_sigma: float
    alternative: FilterSettings | None
    alt_rel_sigma: float
    excitation_top_hz: float
    reason: str
    warning: str = ""

    def to_json(self) -> dict:
        """The JSON object `identify --json` prints under "band" (NaN as None)."""
        alt = self.alternative
        return {"used": self.used, "reason": self.reason,
                "max_rel_sigma_corrected_pct": _pct(self.rel_sigma),
                "excitation_top_hz": self.excitation_top_hz
                if math.isfinite(self.excitation_top_hz) else None,
                "alternative": None if alt is None else {
                    "decimate": alt.Nd, "stencil": alt.stencil, "wn_rad_s": alt.wn,
                    "decimated_cutoff_hz": alt.decimated_cutoff_hz,
                    "max_rel_sigma_corrected_pct": _pct(self.alt_rel_sigma)}}


def _pct(x: float) -> float | None:
    return 100 * x if math.isfinite(x) else None


def excitation_top_hz(log: Log) -> tuple[float, str]:
    """The excitation's top [Hz] and its source: the highest frequency where the Welch
    spectrum of the reference's acceleration (q_ref's second difference; the motor torque
    without q_ref) stands above the geometric mean of its peak and its floor (the median over
    the top quarter of the band, 0.75-1 Nyquist), that is half-way between them in decibels.
    A sweep's spectrum falls by decades at its top, so the level only has to sit between the
    two; the Blackman-Harris window keeps its sidelobes (-92 dB) from carrying the peak past
    the top. NaN when the spectrum has no floor below its peak."""
    x, what = ((np.diff(log.q_ref, 2), "the reference's acceleration") if log.q_ref is not None
               else (log.tau_m, "the motor torque"))
    fs = log.sample_rate_hz
    nper = min(len(x), int(WELCH_SEGMENT_S * fs))
    f, p = signal.welch(x - np.mean(x), fs, window="blackmanharris", nperseg=nper)
    floor, peak = float(np.median(p[f >= 0.75 * fs / 2])), float(np.max(p))
    if not (floor > 0 and peak > floor):
        return math.nan, what
    return float(f[np.nonzero(p > math.sqrt(floor * peak))[0][-1]]), what


def stencil_top_hz(rate_hz: float, stencil: int = 5, nd: int = 2) -> float:
    """The highest frequency [Hz] where the stencil's distortion 1 - gain^nd (nd = 2, the
    joint-motor model's highest derivative) stays within defaults.STENCIL_DISTORTION_MAX,
    the rule `defaults.stencil_for` applies at the decimated cutoff (eq. 29's idea)."""
    x = brentq(lambda x: 1 - stencil_gain(x, stencil) ** nd - STENCIL_DISTORTION_MAX,
               1e-6, math.pi / 2)
    return x * rate_hz / (2 * math.pi)


def butterworth_flat_top_hz(s: FilterSettings) -> float:
    """The highest frequency [Hz] where the zero-phase Butterworth of `s` (gain
    1 / (1 + (w / wn)^2m), forward and back) passes the band within
    defaults.STENCIL_DISTORTION_MAX: there every column, the Coulomb ones built from the
    filtered velocity included, sees the signal the equation holds for. For m = 4: 0.56 wn."""
    eps = STENCIL_DISTORTION_MAX
    return s.wn / (2 * math.pi) * (eps / (1 - eps)) ** (1 / (2 * s.m))


def wide_settings(log: Log, base: FilterSettings) -> tuple[FilterSettings | None, float, str]:
    """The wide candidate, the excitation's top [Hz] and how the band's top was set:
    `base`'s Butterworth and chain, Nd = ceil(0.8 Fs / (2 top)) (the smallest decimation whose
    cutoff stays at or under top), top = the least of the excitation's top
    (`excitation_top_hz`), the 5-point stencil's (`stencil_top_hz`) and the Butterworth's
    flat band (`butterworth_flat_top_hz`), and the stencil `stencil_for` gives that band.
    The candidate is None when that Nd is not below base's (the chooser's band reaches the
    top already) or no excitation top is found."""
    exc, what = excitation_top_hz(log)
    rate = log.sample_rate_hz
    caps = {"the 5-point stencil's": stencil_top_hz(rate),
            "the Butterworth's flat band": butterworth_flat_top_hz(base)}
    if not math.isfinite(exc):
        return None, exc, f"no excitation top found in {what}"
    top = min(exc, *caps.values())
    why = f"the excitation's top {exc:.3g} Hz ({what})" + "".join(
        f", capped at {name} {f:.3g} Hz" for name, f in caps.items() if f == top < exc)
    nd = max(1, math.ceil(0.8 * rate / (2 * top) - 1e-9))
    if nd >= base.Nd:
        return None, exc, (f"the chooser's band (cutoff {base.decimated_cutoff_hz:.3g} Hz) "
                           f"already reaches {why}")
    wide = replace(base, Nd=nd)
    return replace(wide, stencil=stencil_for(wide)[0]), exc, why


def excitation_capped(log: Log, base: FilterSettings) -> tuple[FilterSettings, str]:
    """`base` with its decimated cutoff brought down to the excitation's top
    (`excitation_top_hz`) when it lies above it: Nd = ceil(0.8 Fs / (2 top)), the smallest
    decimation whose cutoff stays at or under the top (as `wide_settings`), the Butterworth
    and chain kept; and how, or "" when `base` already stays under the top or none is found.
    For a band chosen without a resonance (a generic band): above the excitation's top the
    log holds no motion the reference drives, only the encoders' quantisation (and what a
    disturbance of the axis itself moves), which the led columns amplify by w Ts per
    difference (the motor acceleration's by (w Ts)^2): in a band reaching twice the top,
    that noise outweighs what an effect changes in it."""
    exc, what = excitation_top_hz(log)
    if not (math.isfinite(exc) and exc > 0):
        return base, ""
    nd = max(1, math.ceil(0.8 * log.sample_rate_hz / (2 * exc) - 1e-9))
    if nd <= base.Nd:
        return base, ""
    capped = replace(base, Nd=nd)
    return capped, (f"capped at the excitation's top {exc:.3g} Hz ({what}): Nd = {nd}, "
                    f"decimated cutoff {capped.decimated_cutoff_hz:.3g} Hz")


def band_for(log: Log, base: FilterSettings, band: BandChoice | None) -> FilterSettings:
    """The band a fit's `band` choice gives another log whose chooser's settings are `base`:
    its own wide candidate (`wide_settings`) when the fit took the wide band and the log has
    one, else `base` (`identify --validate` compares like with like)."""
    if band is None or band.used != "wide":
        return base
    return wide_settings(log, base)[0] or base


def max_rel_sigma(physical: dict[str, float], sigma: dict[str, float]) -> float:
    """max over K, Jm, JL of sigma / |value| (inf when one is missing or not finite)."""
    out = 0.0
    for p in PRECISION_PARAMS:
        v, s = physical.get(p, math.nan), sigma.get(p, math.nan)
        if not (math.isfinite(v) and v != 0 and math.isfinite(s)):
            return math.inf
        out = max(out, s / abs(v))
    return out


def disagreement(a: tuple[dict, dict], b: tuple[dict, dict]) -> tuple[str, float]:
    """The parameter of K, Jm, JL whose two estimates (physical, corrected sigma) lie
    farthest apart, in sigmas of their difference, and that distance. Both bands fit the same
    log, so the two estimates are correlated: when both are unbiased the difference has the
    variance |sigma_a^2 - sigma_b^2| (Hausman's specification test: the more precise one
    efficient), far below the root sum of squares when the two sigmas are close."""
    z = {}
    for p in PRECISION_PARAMS:
        d, var = abs(a[0][p] - b[0][p]), abs(a[1][p] ** 2 - b[1][p] ** 2)
        z[p] = d / math.sqrt(var) if var > 0 else (math.inf if d > 0 else 0.0)
    name = max(z, key=z.get)
    return name, z[name]


def mode_gap(physical: dict[str, float], f1_hz: float | None) -> float:
    """|f1_hz / f - 1| for the two-mass model's first mode f = sqrt(K (1/Jm + 1/JL)) / 2 pi
    of `physical`; inf when f1_hz is not given or K, Jm, JL are not all positive."""
    K, Jm, JL = (physical.get(n, math.nan) for n in PRECISION_PARAMS)
    if f1_hz is None or not (K > 0 and Jm > 0 and JL > 0):
        return math.inf
    return abs(f1_hz / (math.sqrt(K * (1 / Jm + 1 / JL)) / (2 * math.pi)) - 1)


def choose_band(chosen: Fit, other: Fit | Exception | None,
                wide: tuple[FilterSettings | None, float, str],
                estimate: Callable[[Fit], tuple[dict, dict] | None],
                f1_hz: float | None = None) -> tuple[Fit, BandChoice]:
    """The rule, between the chooser's fit `chosen` and `other`, the same model fitted in
    the wide band (`wide`: what `wide_settings` gave for the chooser's settings; `other` the
    error the wide fit raised, or None when there is no wide band): keep the fit whose
    largest relative corrected sigma of K, Jm, JL (`max_rel_sigma`
    of `estimate(fit)`: (physical, corrected sigma), None when not a joint-motor fit) is the
    smaller, unless, when that is the wide one, the two estimates lie more than CONSISTENCY_Z
    sigmas of their difference apart on any of K, Jm, JL (`disagreement`): then the
    chooser's, and a warning; the wide one, and the warning, when the chooser's model puts
    the first mode more than MODE_DISAGREEMENT from the measured `f1_hz` [Hz] and the wide
    one's within it (`mode_gap`). The chooser's fit also
    stays when there is no wider band or its fit failed."""
    base_est = estimate(chosen)
    settings = chosen.settings
    rel = max_rel_sigma(*base_est) if base_est else math.inf
    wide, top, why = wide
    keep = BandChoice("chooser", rel, wide, math.nan, top, "")
    if wide is None or other is None:
        return chosen, replace(keep, reason=f"chooser's band: {why}")
    label = (f"Nd {wide.Nd}, cutoff {wide.decimated_cutoff_hz:.3g} Hz, {wide.stencil} points; "
             f"{why}")
    if isinstance(other, Exception):
        return chosen, replace(keep, reason=f"chooser's band: the wide band ({label}) "
                                            f"failed: {other}")
    other_est = estimate(other)
    alt = max_rel_sigma(*other_est) if other_est else math.inf
    keep = replace(keep, alt_rel_sigma=alt)
    if not (base_est and other_est and math.isfinite(rel) and math.isfinite(alt)):
        return chosen, replace(keep, reason=f"chooser's band: no corrected sigma to compare "
                                            f"with the wide band ({label})")
    if not alt < rel:
        return chosen, replace(keep, reason=(
            f"chooser's band: largest relative corrected sigma {100 * rel:.2g} % against "
            f"{100 * alt:.2g} % in the wide band ({label})"))
    name, z = disagreement(base_est, other_est)
    if z > CONSISTENCY_Z:
        text = (f"the wide band ({label}) puts {name} at {other_est[0][name]:.4g} against "
                f"{base_est[0][name]:.4g} in the chooser's band, {z:.1f} sigma of their "
                f"difference apart: one of them is biased; ")
        gaps = [mode_gap(e[0], f1_hz) for e in (base_est, other_est)]
        if not gaps[0] > MODE_DISAGREEMENT >= gaps[1]:
            text += "the chooser's band kept"
            return chosen, replace(keep, reason="chooser's band: " + text, warning=text)
        text += (f"the wide band kept: its model puts the first mode {100 * gaps[1]:.2g} % "
                 f"from the measured {f1_hz:.4g} Hz, the chooser's {100 * gaps[0]:.2g} %")
        return other, BandChoice("wide", alt, settings, rel, top, "wide band: " + text, text)
    return other, BandChoice(
        "wide", alt, settings, rel, top,
        f"wide band ({label}): largest relative corrected sigma of K, Jm, JL "
        f"{100 * alt:.2g} % against {100 * rel:.2g} % in the chooser's band "
        f"(Nd {settings.Nd}); the two agree within {z:.1f} sigma of their difference")
