"""In-band visibility of a hidden effect, and the strength that gives a wanted visibility
(a battery whose strengths are not tuned to the detector).

The visibility of an effect on a case is what it changes in the noise-free command, in the
band the identification looks at:

    visibility = RMS(L[tau_effect - tau_clean]) / RMS(L[tau_clean])

with tau the logged command of the same experiment (same axis, gains, reference and seed,
torque noise off) without and with the effect, and L the zero-phase Butterworth low-pass
(identification.filtering.lowpass, order 4) at VISIBILITY_BAND f1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from jointbench.identification.filtering import lowpass
from jointbench.identification.output_values import rms

VISIBILITY_BAND = 1.4      # the low-pass corner in units of the first mode f1
SEARCH_TOLERANCE = 0.10    # relative: |visibility / target - 1| at which the search stops
SEARCH_EVALUATIONS = 6     # simulations at most per search
SLOPE_RANGE = (0.25, 4.0)  # d log(visibility) / d log(strength) is clipped to this range
# Below the target, a step of at least SATURATION_STEP in strength whose visibility grows
# with d log(visibility) / d log(strength) under SATURATION_SLOPE ends the search: the
# visibility has stopped growing (a spring damping that locks the link to the motor, a
# hardening that acts as a stop), and a target above it is out of reach.
SATURATION_SLOPE = 0.15
SATURATION_STEP = 1.5
# A saturated search keeps the smallest strength tried whose visibility is at least
# PLATEAU_SHARE of the largest reached: the start of the plateau, not the far end of it
# (a damping that welds the link to the motor, a backlash wider than any deflection, where
# the log degenerates and the effect shows no more).
PLATEAU_SHARE = 0.8
# One step beyond every strength tried changes it by at most this factor: the clipped slope
# would otherwise extrapolate a small growth by (target / visibility)^4, to strengths whose
# simulation (its step set by the stiffest term) takes many minutes, before the saturation
# shows.
MAX_STEP = 30.0


def visibility(tau_clean: np.ndarray, tau_effect: np.ndarray, f1_hz: float,
               rate_hz: float) -> float:
    """The in-band visibility (a ratio, not %) of the change tau_effect - tau_clean [N m]
    below VISIBILITY_BAND f1 [Hz]; the two commands are sampled at rate_hz on the same ticks.
    ValueError for commands of different lengths or a band at or above Nyquist."""
    a, b = np.asarray(tau_clean, float), np.asarray(tau_effect, float)
    if a.shape != b.shape:
        raise ValueError(f"commands of different lengths: {a.shape} and {b.shape}")
    corner = VISIBILITY_BAND * f1_hz
    if not 0 < corner < rate_hz / 2:
        raise ValueError(f"band {corner:g} Hz is not below Nyquist {rate_hz / 2:g} Hz")
    wn, ts = 2 * math.pi * corner, 1.0 / rate_hz
    return rms(lowpass(b - a, wn, ts)) / rms(lowpass(a, wn, ts))


@dataclass(frozen=True)
class Search:
    """A strength search's answer: the strength, its visibility and every (strength,
    visibility) tried, in order (visibility NaN where the simulation failed); `saturated`:
    the target is out of reach (the visibility stopped growing below it, or the largest
    strength stays below it), and `visibility` is the one reached."""

    strength: float
    visibility: float
    tried: tuple[tuple[float, float], ...]
    saturated: bool = False

    def hit(self, target: float, tolerance: float = SEARCH_TOLERANCE) -> bool:
        return abs(self.visibility / target - 1.0) <= tolerance


def strength_for(target: float, visibility_of: Callable[[float], float], start: float,
                 largest: float = math.inf, tolerance: float = SEARCH_TOLERANCE,
                 evaluations: int = SEARCH_EVALUATIONS) -> Search:
    """The strength whose visibility is `target` (a ratio), searched on the magnitude with
    the sign of `start` (a strength the effect typically has): secant steps on
    log(visibility) against log(strength), slope clipped to SLOPE_RANGE, at most MAX_STEP
    beyond the strengths tried, kept inside the bracket found so far and under |largest|;
    it stops where the visibility stops growing below the target (`stopped_growing`,
    Search.saturated). `visibility_of(strength)` runs the case (NaN
    or an exception: the strength is too strong for the simulation). Returns the tried
    strength nearest the target (in log ratio), or, saturated, the smallest whose
    visibility is PLATEAU_SHARE of the largest reached; ValueError when none ran."""
    if not (target > 0 and start != 0 and math.isfinite(start)):
        raise ValueError(f"need target > 0 and a finite start != 0, got {target}, {start}")
    sign, m = math.copysign(1.0, start), min(abs(start), abs(largest))
    tried: list[tuple[float, float]] = []
    good: list[tuple[float, float]] = []          # (magnitude, visibility) that ran
    failed = math.inf                             # smallest magnitude that did not run
    saturated = False
    for _ in range(evaluations):
        try:
            v = float(visibility_of(sign * m))
        except (ArithmeticError, ValueError, RuntimeError):
            v = math.nan
        tried.append((sign * m, v))
        if math.isfinite(v):
            good.append((m, v))
            if abs(v / target - 1.0) <= tolerance:
                break
            if stopped_growing(target, good):
                saturated = True
                break
        else:
            failed = min(failed, m)
        m = _next_magnitude(target, good, failed, abs(largest), m)
        if any(abs(m / g[0] - 1.0) < 1e-6 for g in good):
            # pinned at a bound already tried: at the largest strength with the visibility
            # still below the target, the target is out of reach
            saturated = all(p[1] < target for p in good)
            break
    if not good:
        raise ValueError(f"no strength near {start:g} ran: {tried}")
    best = min(good, key=lambda p: abs(math.log(max(p[1], 1e-300) / target)))
    if saturated:
        top = max(p[1] for p in good)
        best = min(p for p in good if p[1] >= PLATEAU_SHARE * top)
    return Search(sign * best[0], best[1], tuple(tried), saturated)


def stopped_growing(target: float, good: list[tuple[float, float]]) -> bool:
    """Whether the last (magnitude, visibility) of `good` shows the visibility saturating
    below `target`: it is the largest magnitude tried, under the target, and against the
    next smaller magnitude tried (at least SATURATION_STEP below it, with a visibility > 0)
    d log(visibility) / d log(strength) < SATURATION_SLOPE."""
    m, v = good[-1]
    if v >= target or v <= 0 or any(p[0] > m for p in good[:-1]):
        return False
    below = [p for p in good[:-1] if p[1] > 0 and p[0] * SATURATION_STEP <= m]
    if not below:
        return False
    m0, v0 = max(below)
    return math.log(v / v0) / math.log(m / m0) < SATURATION_SLOPE


def _next_magnitude(target: float, good: list[tuple[float, float]], failed: float,
                    largest: float, last: float) -> float:
    below = [p for p in good if p[1] < target]
    above = [p for p in good if p[1] >= target]
    lo = max(below)[0] if below else 0.0
    hi = min([p[0] for p in above] + [failed, largest])
    if not good:                                  # only failures so far: back off
        return last / 3.0
    ref = min(good, key=lambda p: abs(math.log(max(p[1], 1e-300) / target)))
    if ref[1] <= 0:
        m = ref[0] * 10.0
    else:
        others = [p for p in good if p is not ref and p[1] > 0 and p[0] != ref[0]]
        slope = 1.0
        if others:
            o = min(others, key=lambda p: abs(math.log(p[0] / ref[0])))
            slope = math.log(ref[1] / o[1]) / math.log(ref[0] / o[0])
            slope = min(max(slope, SLOPE_RANGE[0]), SLOPE_RANGE[1])
        m = ref[0] * (target / ref[1]) ** (1.0 / slope)
        tried = [p[0] for p in good]
        m = min(max(m, min(tried) / MAX_STEP), max(tried) * MAX_STEP)
    if m >= largest and not above and failed > largest:
        return 0.999 * largest                    # beyond the bound: try the bound itself
    if not lo < m < hi:                           # stay inside the bracket
        m = math.sqrt(lo * hi) if lo > 0 and math.isfinite(hi) else \
            0.5 * hi if math.isfinite(hi) else 2.0 * lo
    return min(m, 0.999 * largest) if math.isfinite(largest) else m
