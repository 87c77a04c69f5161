"""The filter of a log: the paper's constants and the one chooser of the bandpass filter.

The paper's values (section 4: 350.87 Hz, wn = 176 rad/s, Nd = 26, f1 = 3.9 Hz) are the
prototype's, and a default for the prototype only; every other log gets its filter from its
own first mode (eqs. 28-29). Every command that needs a filter asks `settings_for` or
`default_settings`, here and nowhere else; `identify` then widens a joint-motor fit's band
when the log's own precision says so (identification/band_choice.py), and the commands that
identify read the band used from the result (`Identification.settings`, `.band`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

# The filter modules import scipy (0.6 s); a virtual experiment (bench.sim) imports only the
# constants below and must not pay for them (README "Speed"; the literal rate lives here
# alone, so no lighter module can hold it): the functions import them where they are used.
if TYPE_CHECKING:
    from jointbench.identification.filtering import FilterSettings
    from jointbench.identification.first_mode import FirstMode
    from jointbench.identification.log import Log

PAPER_RATE = 350.87    # Hz, the prototype's acquisition rate (section 4)
PAPER_WN = 176.0       # rad/s, the Butterworth frequency used in section 4
PAPER_ND = 26          # decimation factor used in section 4
PAPER_F1 = 3.9          # Hz, the loaded prototype's first mode quoted in section 4
RATE_MARGIN = 2.0       # design_rate_hz: sample rate over eq. (29)'s


def default_settings(rate_hz: float, f1_hz: float | None = None, m: int = 4) -> FilterSettings:
    """The filter for a log at `rate_hz` whose first mode is `f1_hz`.

    At the paper's rate 350.87 Hz, with no f1 or one within 20 % of the paper's 3.9 Hz: the
    paper's wn = 176 rad/s, Nd = 26 (section 4). Otherwise from f1: wn from eq. (28)
    (nd = 2, wc = 6 w1, Ac = sqrt(2)/2, capped at 0.8 of the Nyquist frequency) and Nd placing
    the decimated cutoff 0.8 Fs / (2 Nd) at 5.4 / 3.9 f1, the paper's ratio (so that the band
    holds the mode). The paper's Nd = 26 at 350.87 Hz would cut at 5.4 Hz, below a 15-19 Hz
    mode of the six-axis arm. Raises ValueError without f1 at another rate."""
    from jointbench.identification.filtering import FilterSettings

    ts = 1.0 / rate_hz
    paper_rate = abs(rate_hz / PAPER_RATE - 1.0) < 0.01
    if paper_rate and (f1_hz is None or abs(f1_hz / PAPER_F1 - 1.0) <= 0.2):
        s = FilterSettings(wn=PAPER_WN, m=m, Nd=PAPER_ND, ts=ts)
    elif f1_hz is None:
        raise ValueError("at a sample rate other than 350.87 Hz the filter is derived from the "
                         "first mode: give f1 (Hz) or explicit wn and Nd")
    else:
        s = FilterSettings(wn=wn_from_f1(rate_hz, f1_hz, m), m=m, Nd=nd_from_f1(rate_hz, f1_hz),
                           ts=ts)
    return replace(s, stencil=stencil_for(s)[0])


STENCIL_DISTORTION_MAX = 0.01   # 1 - sinc(w T)^4 at the decimated cutoff, eq. (22) kept below


def stencil_for(s: FilterSettings, nd: int = 4) -> tuple[int, str]:
    """The central-difference stencil for the band of `s`, and why: eq. (22) (3 points) while
    its distortion 1 - (sin(wT) / wT)^nd (eq. 24, the D share of eq. 26) at the decimated
    cutoff stays under 1 %, else the 5-point stencil (distortion (wT)^4 / 30 per derivative).
    nd = 4, the highest derivative any model takes (motor-only). Why 1 %: the distortion grows
    as w^2, so at the mode (the cutoff is about 1.385 f1) it is about half of it, 0.5 %; the
    sinc distortion at f1 biases K and Jm by about 0.4 times itself (0.2 % for 0.47 %, see
    design_rate_hz), so 1 % at the cutoff keeps that bias near 0.2 %, inside the 0.5 % the
    joint-motor model is asked for. The prototype at 350.87 Hz (cutoff 5.4 Hz) has 0.62 %."""
    x = 2 * np.pi * s.decimated_cutoff_hz * s.ts
    dist = 1 - float(np.sinc(x / np.pi)) ** nd
    if dist <= STENCIL_DISTORTION_MAX:
        return 3, (f"eq. (22): 3 points, distortion (sin wT / wT)^{nd} at the decimated cutoff "
                   f"{100 * dist:.2g} % <= {100 * STENCIL_DISTORTION_MAX:g} %")
    return 5, (f"5 points: eq. (22)'s distortion (sin wT / wT)^{nd} at the decimated cutoff "
               f"would be {100 * dist:.2g} % > {100 * STENCIL_DISTORTION_MAX:g} %")


def wn_from_f1(rate_hz: float, f1_hz: float, m: int = 4) -> float:
    """Butterworth frequency [rad/s] from the first mode: eq. (28) with nd = 2, wc = 6 w1,
    Ac = sqrt(2)/2, rc = 1, capped at 0.8 of the Nyquist frequency."""
    from jointbench.identification.design import design_bandpass

    return min(design_bandpass(f1_hz, nd=2, m=m).wn_rad_s, 0.8 * np.pi * rate_hz)


def nd_from_f1(rate_hz: float, f1_hz: float) -> int:
    """Decimation factor placing the decimated cutoff 0.8 Fs / (2 Nd) at 5.4 / 3.9 f1, the
    paper's ratio of cutoff to first mode (section 4: 0.8 x 350.87 / (2 x 5.4) = 25.99 gives
    its Nd = 26), so that the band holds the mode; rounded down instead when rounding would
    put the cutoff under MIN_CUTOFF_OVER_F1 f1 (few decimation steps: 2.4 rounds down to 2 at 1.66 f1)."""
    from jointbench.identification.checks.band import MIN_CUTOFF_OVER_F1

    x = 0.8 * rate_hz / (2 * f1_hz * 5.4 / 3.9)
    nd = max(1, int(round(x)))
    if 0.8 * rate_hz / (2 * nd) < MIN_CUTOFF_OVER_F1 * f1_hz:
        nd = max(1, int(math.floor(x)))
    return nd


def design_rate_hz(f1_hz: float, m: int = 4, margin: float = RATE_MARGIN) -> float:
    """An acquisition rate for an axis whose first mode is f1: `margin` times the Fs of
    eq. (29) (nd = 2, wc = 6 w1, Ac = sqrt(2)/2, rc = 1), that is about 105 f1 for m = 4.

    Eq. (29) bounds the central-difference distortion sinc(w Ts)^2 at wc; at f1 it leaves
    (w1 Ts)^2 / 3 = 0.47 %, which biases K by about -0.2 % and Jm by +0.2 % (measured on the
    arm without friction, joint-motor model). Twice the rate quarters it (0.12 %, K and Jm
    within 0.05 %). For the arm's 14.7-19.5 Hz modes: 1.5-2.1 kHz."""
    from jointbench.identification.design import design_bandpass

    if not margin >= 1.0:
        raise ValueError(f"margin must be >= 1 (a rate below eq. (29)'s), got {margin!r}")
    return margin * design_bandpass(f1_hz, nd=2, m=m).fs_hz


GENERIC_WN_RATIO = 0.1   # Butterworth cutoff / sample rate when no first mode is known
GENERIC_ND = 10          # decimation factor when no first mode is known


def generic_settings(rate_hz: float, m: int = 4) -> FilterSettings:
    """Settings for a log whose first mode is unknown (no f1), at any rate: the Butterworth at
    a tenth of the sample rate and Nd = 10 (decimated cutoff 0.04 Fs). These are the ratios of
    the EMPS reference identification (1 kHz, 100 Hz, Nd = 10; Janot, Gautier, Brunot 2019)
    and they keep the rigid-body band (tens of Hz at 1 kHz) while rejecting the noise the
    double differentiation amplifies."""
    from jointbench.identification.filtering import FilterSettings

    return FilterSettings(wn=2 * np.pi * GENERIC_WN_RATIO * rate_hz, m=m, Nd=GENERIC_ND,
                          ts=1.0 / rate_hz)


@dataclass(frozen=True)
class FilterChoice:
    """The chooser's answer: the settings, the first mode they come from (None: the caller
    gave neither f1 nor a log to measure), why this stencil, notes and warnings."""

    settings: FilterSettings
    first_mode: FirstMode | None
    stencil_reason: str
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()


def choose_filter(log: Log, f1_hz: float | None = None) -> FilterChoice:
    """The default filter for `log`: with `f1_hz` from it (as `default_settings`); without,
    from the first mode measured on the log (`measure_first_mode`), at every rate, 350.87 Hz
    included (the paper's filter stays for a measured f1 within 20 % of 3.9 Hz at that rate).
    When no resonance is found: `generic_settings` and a warning saying so."""
    from jointbench.identification.first_mode import given_first_mode, measure_first_mode

    rate = log.sample_rate_hz
    mode = given_first_mode(f1_hz) if f1_hz is not None else measure_first_mode(log)
    if mode.found:
        s = default_settings(rate, mode.f1_hz)
        return FilterChoice(s, mode, stencil_for(s)[1])
    s = generic_settings(rate)
    s = replace(s, stencil=stencil_for(s)[0])
    text = (f"no resonance found ({mode.note}): generic band wn = {s.wn:.4g} rad/s "
            f"({s.wn / (2 * np.pi):.4g} Hz, a tenth of the rate), Nd = {s.Nd}, decimated cutoff "
            f"{s.decimated_cutoff_hz:.3g} Hz; give --f1 if the axis has a mode")
    return FilterChoice(s, mode, "generic band: " + stencil_for(s)[1], (), (text,))


def settings_for(log: Log, f1_hz: float | None = None) -> tuple[FilterSettings, str | None]:
    """`choose_filter`'s settings and its notes and warnings as one text (None if none)."""
    c = choose_filter(log, f1_hz)
    return c.settings, "; ".join(c.notes + c.warnings) or None


PAPER_SOURCE = "model prototype_axis.xml"   # the bench's `source` metadata for the prototype


def is_paper_prototype(log: Log) -> bool:
    """A log of the paper's prototype axis, from the metadata the bench writes (`source`:
    "jointbench virtual experiment, model prototype_axis.xml"), never from numbers."""
    return log.meta.get("source", "").strip().endswith(PAPER_SOURCE)
