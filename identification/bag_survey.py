"""The joints a survey bag moved, and when (docs/log-format.md section 1.7).

A survey moves each joint in turn while the others are held. A joint's motion is measured on
its motor position q_m by the rolling standard deviation r_k of the second difference
q_m[k+1] - 2 q_m[k] + q_m[k-1] over MOTION_WINDOW_S: a chirp's acceleration keeps its size up
to its top frequency, where the position's shrinks as 1 / f^2. A joint moved when the peak of
r exceeds MOVED_RATIO times its held level (the 10th percentile of r, or the encoder's step
when larger: a held joint flickering by one count did not move); its window is the span of
the samples where r exceeds ACTIVE_FRACTION of the peak and HELD_MARGIN times the held level.
Two windows that overlap are refused: a survey moves one joint at a time.

Pure numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointbench.identification.bag_import import MOTOR_SUFFIX, Bag, BagSpec, Source, TimeGrid
from jointbench.identification.log.schema import LogError

MOTION_WINDOW_S = 0.25  # the rolling window of the motion measure [s]
MOVED_RATIO = 100.0     # moved: peak over 100 x the held level
ACTIVE_FRACTION = 1e-3  # the window: above 0.1 % of the peak ...
HELD_MARGIN = 3.0       # ... and 3 x the held level


def rolling_sd(x: np.ndarray, w: int) -> np.ndarray:
    """Standard deviation of x over the centred window of w samples (shorter at the ends)."""
    n = len(x)
    x = x - x.mean()
    c1 = np.concatenate([[0.0], np.cumsum(x)])
    c2 = np.concatenate([[0.0], np.cumsum(x * x)])
    i = np.arange(n)
    lo, hi = np.clip(i - w // 2, 0, n), np.clip(i + w - w // 2, 0, n)
    m = hi - lo
    mean = (c1[hi] - c1[lo]) / m
    return np.sqrt(np.maximum((c2[hi] - c2[lo]) / m - mean ** 2, 0.0))


@dataclass(frozen=True)
class Motion:
    """A joint's motion in a survey bag: `moved`, its sample window [start, stop), the peak
    rolling sd and the held level it is compared with."""

    joint: str
    moved: bool
    start: int
    stop: int
    peak: float
    held: float


def motion(joint: str, q_m: np.ndarray, rate_hz: float) -> Motion:
    """Whether and when `joint` moved, from its motor position sampled at `rate_hz` (module
    docstring)."""
    w = max(3, int(round(MOTION_WINDOW_S * rate_hz)))
    r = rolling_sd(np.concatenate([[0.0], np.diff(q_m, 2), [0.0]]), w)
    steps = np.abs(np.diff(q_m))
    steps = steps[steps > 0]
    held = max(float(np.percentile(r, 10)), float(steps.min()) if steps.size else 0.0)
    peak = float(r.max())
    moved = peak > 0 and peak > MOVED_RATIO * held
    if not moved:
        return Motion(joint, False, 0, 0, peak, held)
    active = np.flatnonzero(r > max(ACTIVE_FRACTION * peak, HELD_MARGIN * held))
    return Motion(joint, True, int(active[0]), int(active[-1]) + 1, peak, held)


def survey_joints(names: tuple[str, ...]) -> list[str]:
    """The axes of a JointState: names X with a name X_motor beside them."""
    return [n for n in names if n + MOTOR_SUFFIX in names]


def moved_windows(bag: Bag, spec: BagSpec, grid: TimeGrid) -> tuple[list[Motion], list[str]]:
    """Every axis of the main topic with its Motion, and the moved ones' names in time order.
    LogError when no axis is found, none moved, or two moved at the same time."""
    data = bag.topic(spec.topic)
    joints = survey_joints(data.names)
    if not joints:
        raise LogError(f"topic {spec.topic}: no axis (a joint NAME with a joint "
                       f"NAME{MOTOR_SUFFIX}; names: {', '.join(data.names)})", bag.path)
    motions = [motion(j, data.column(Source(spec.topic, j + MOTOR_SUFFIX, "position"),
                                     bag.path), grid.rate_hz) for j in joints]
    moved = sorted((m for m in motions if m.moved), key=lambda m: m.start)
    if not moved:
        raise LogError(f"topic {spec.topic}: no joint moved (axes {', '.join(joints)})",
                       bag.path)
    for a, b in zip(moved, moved[1:]):
        if b.start < a.stop:
            raise LogError(f"joints {a.joint} and {b.joint} move at the same time (from "
                           f"{b.start * grid.period:.3f} s): a survey bag moves one joint at a "
                           "time", bag.path)
    return motions, [m.joint for m in moved]


def held_config(bag: Bag, spec: BagSpec, motions: list[Motion], m: Motion) -> str:
    """`locked_config` of the log of `m`: the other axes' median link angle in its window."""
    data = bag.topic(spec.topic)
    parts = []
    for other in motions:
        if other.joint == m.joint:
            continue
        q = data.column(Source(spec.topic, other.joint, "position"), bag.path)
        parts.append(f"{other.joint}={float(np.median(q[m.start:m.stop])):.6g}")
    return " ".join(parts)
