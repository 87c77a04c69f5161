"""Can a log tell a parameter's error within POINTS? And if not, how long a log would.

`diagnose --model` reports each parameter's error e = 100 (model - data) / scale with the sigma
the data's value carries into it, s (points of %, `against_model.error_sigma`). The error is
known within POINTS at CONFIDENCE when z s <= POINTS, z the two-sided normal quantile (1.96
for 95 %). Where it is not, the experiment must be longer. The same experiment run T instead
of T0 seconds gives T / T0 times the equations of eq. (13): the information matrix W^T W grows
as T, so the covariance shrinks as 1 / T and

    s(T) = s(T0) sqrt(T0 / T)   =>   T >= T0 (z s(T0) / POINTS)^2.

The paper's (white) sigma follows this law closely; the autocorrelation-corrected one, itself
estimated from the residual, less closely. The duration is therefore an estimate, good for
FVm, the parameter 60 s logs leave coarse. Nothing here is tuned: POINTS is the bar asked
of `diagnose --model`, CONFIDENCE the usual 95 %.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import NormalDist
from typing import Mapping, Protocol

from jointbench.bench.analysis.diagnose.model_edit import GRAVITY

POINTS = 2.0        # the bar: an error known within this many points of %
CONFIDENCE = 0.95   # two-sided
Z = NormalDist().inv_cdf(0.5 + CONFIDENCE / 2)


class _Error(Protocol):
    data: float
    sigma: float
    error_sigma_pct: float


@dataclass(frozen=True)
class Coarse:
    """A parameter whose error the log cannot tell within POINTS: its sigma [points] and the
    length [s] of the same experiment that would."""

    name: str
    error_sigma_pct: float
    duration_s: float

    def to_json(self) -> dict:
        return {"error_sigma_pct": self.error_sigma_pct, "duration_s": self.duration_s}


def needed_duration(error_sigma_pct: float, duration_s: float,
                    points: float = POINTS) -> float:
    """T0 (z s / points)^2 [s]: the length of the experiment at which the error's sigma s
    [points], measured on a log of T0 = duration_s, is points / z (module docstring)."""
    return duration_s * (Z * error_sigma_pct / points) ** 2


def told_from_zero(errors: Mapping[str, _Error], name: str, sigmas: float) -> bool:
    """Whether the log tells the reference of `name`'s error % from zero: |data| > `sigmas`
    sigma (MX, MY: the gravity moment, sqrt(MX^2 + MY^2) against sqrt(sigma_MX^2 +
    sigma_MY^2)). Where it does not (MX, MY of a vertical axis), there is no relative error
    to tell, at any duration."""
    keys = GRAVITY if name in GRAVITY else (name,)
    if not all(k in errors for k in keys):
        return False
    value = math.hypot(*(errors[k].data for k in keys))
    return value > sigmas * math.hypot(*(errors[k].sigma for k in keys))


def coarse(errors: Mapping[str, _Error], duration_s: float, sigmas: float,
           points: float = POINTS) -> dict[str, Coarse]:
    """The parameters of `errors` whose error is not known within `points` at CONFIDENCE
    (z sigma > points), each with the experiment length that would know it; left out: a
    sigma that is not finite (not identified), an error without a reference
    (`told_from_zero` at `sigmas`)."""
    out = {}
    for name, e in errors.items():
        s = e.error_sigma_pct
        if math.isfinite(s) and Z * s > points and told_from_zero(errors, name, sigmas):
            out[name] = Coarse(name, s, needed_duration(s, duration_s, points))
    return out


def describe(found: Mapping[str, Coarse], points: float = POINTS) -> str:
    """One line for the report: which errors are too coarse, and the duration that would do."""
    if not found:
        return (f"precision: every error known within {points:g} points "
                f"({100 * CONFIDENCE:g} %)")
    items = [f"{c.name} +- {c.error_sigma_pct:.1f} points ({c.duration_s:.0f} s)"
             for c in found.values()]
    return (f"precision: errors not known within {points:g} points ({100 * CONFIDENCE:g} %, "
            f"{Z:.2f} sigma): {', '.join(items)}; in brackets the length of this experiment "
            "that would tell them (sigma ~ 1/sqrt(duration))")
