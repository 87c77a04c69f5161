"""Clipped torque: the samples of a log whose torque sits at a limit, and the regression rows
they spoil.

A logged torque at the drive's limit (metadata `tau_max`, docs/controller.md's clip) or on a
flat top (a current sensor or an ADC at the end of its range: the same extreme value on many
samples, in several separate runs) is not the torque the axis received, or no longer follows
the controller's law: every equation of eqs. (6), (13), (18)-(20) whose filtered window
touches it is biased (a third of the samples clipped gives K -94 %). `clipped_samples` finds
them, `exclude_clipped` drops the regression rows within reach of one (the Butterworth's and
the decimation filter's impulse responses), and a log with more than MAX_CLIPPED_SHARE of
its samples clipped is refused (`LogError`) by `identify`: what is left says nothing reliable
about the parameters. `diagnose` does not refuse it: the clip can be the symptom it looks for
(bench.analysis.diagnose.clipped).

Pure numerics (numpy), no I/O.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from jointbench.identification.log.schema import Log, LogError

CLIP_RELATIVE = 1e-6       # |tau| within this of the limit (relative) counts as at the limit
PLATEAU_RUNS = 3           # a flat top: the extreme value in at least this many separate runs
PLATEAU_MIN_SHARE = 0.002  # ... on at least this share of the samples (and 5 samples)
MAX_CLIPPED_SHARE = 1 / 3  # more clipped than this: refused
# Rows within REACH_PERIODS periods of the Butterworth frequency, plus REACH_DECIMATE
# decimation factors, of a clipped sample are dropped (the two filters' impulse responses).
REACH_PERIODS = 1.0
REACH_DECIMATE = 1


@dataclass(frozen=True)
class Clipping:
    """The clipped samples of a log: `mask` per sample, `how` (the limit and where it comes
    from) for the messages."""

    mask: np.ndarray
    how: str

    @property
    def count(self) -> int:
        return int(np.count_nonzero(self.mask))

    @property
    def share(self) -> float:
        return self.count / max(1, len(self.mask))

    def message(self, path: str | None) -> str:
        return (f"{path or '<log>'}: {self.count} of {len(self.mask)} torque samples "
                f"({100 * self.share:.3g} %) are clipped ({self.how})")


def _runs(mask: np.ndarray) -> int:
    """Separate runs of True in `mask`."""
    return int(np.count_nonzero(np.diff(np.r_[0, mask.astype(np.int8)]) == 1))


def at_limit(log: Log) -> np.ndarray:
    """The samples whose torque is at the metadata's `tau_max` (all False without it)."""
    tau = np.asarray(log.tau_m, dtype=float)
    tau_max = log.meta_float("tau_max")
    if tau_max is None:
        return np.zeros(len(tau), dtype=bool)
    return np.abs(tau) >= tau_max * (1 - CLIP_RELATIVE)


def clipped_samples(log: Log, limit_applied: bool = False) -> Clipping:
    """The samples at the metadata's `tau_max` and on flat tops of the torque (module
    docstring). `limit_applied`: the torque at `tau_max` is taken as the one the axis
    received (the controller's own clip, docs/controller.md, which the closed-loop replay
    applies too): only flat tops elsewhere count."""
    tau = np.asarray(log.tau_m, dtype=float)
    mask = np.zeros(len(tau), dtype=bool)
    hows = []
    tau_max = log.meta_float("tau_max")
    limit = at_limit(log)
    if limit.any() and not limit_applied:
        mask |= limit
        hows.append(f"at the metadata's tau_max = {tau_max:g}")
    for extreme in (float(np.max(tau)), float(np.min(tau))):
        at = np.abs(tau - extreme) <= CLIP_RELATIVE * abs(extreme)
        if extreme != 0 and _runs(at) >= PLATEAU_RUNS and \
                np.count_nonzero(at) >= max(5, PLATEAU_MIN_SHARE * len(tau)) and \
                not (limit[at].all() and limit.any()):
            mask |= at
            hows.append(f"a flat top at {extreme:g} in {_runs(at)} runs")
    return Clipping(mask=mask, how="; ".join(hows) or "none")


def check_clipping(log: Log) -> Clipping:
    """`clipped_samples`, refused (LogError) when more than MAX_CLIPPED_SHARE are clipped."""
    clip = clipped_samples(log)
    if clip.share > MAX_CLIPPED_SHARE:
        raise LogError(f"{clip.count} of {len(clip.mask)} torque samples "
                       f"({100 * clip.share:.3g} %) are clipped ({clip.how}): over "
                       f"{100 * MAX_CLIPPED_SHARE:.3g} %, what is left cannot be trusted; "
                       "record the experiment with a smaller amplitude or a wider torque "
                       "range", log.path, column="tau_m")
    return clip


def clipping_warnings(log: Log, excluded: bool = True, refuse: bool = True) -> list[str]:
    """The warning for a log with clipped torque samples ([] when none; LogError over
    MAX_CLIPPED_SHARE unless `refuse` is False): `excluded` says whether the analysis leaves
    their rows out. `refuse` False is for an analysis that states itself what the rows left
    can say (diagnose: a torque lag that drives the loop into its limit clips a third of the
    samples and more, and is what the log shows, not a reason to refuse it)."""
    clip = check_clipping(log) if refuse else clipped_samples(log)
    if not clip.count:
        return []
    return [clip.message(log.path) + (
        ": the regression rows within reach of them are left out of the fit" if excluded else
        ": they are NOT left out of this analysis, whose results they may bias")]


def reach(wn: float, ts: float, Nd: int) -> int:
    """Samples on each side of a clipped sample whose regression rows it spoils."""
    return int(math.ceil(REACH_PERIODS * 2 * math.pi / (wn * ts))) + REACH_DECIMATE * Nd


def exclude_clipped(reg, log: Log):
    """`reg` (identification.regressors.Regressor) without the rows within `reach` of a
    clipped sample of `log`; `reg` itself when none is clipped. LogError when over
    MAX_CLIPPED_SHARE of the samples are clipped."""
    clip = check_clipping(log)
    if not clip.count:
        return reg
    s = reg.settings
    h = reach(s.wn, s.ts, s.Nd)
    spoiled = np.convolve(clip.mask.astype(float), np.ones(2 * h + 1), mode="same") > 0.5
    keep = ~spoiled[reg.index]
    return dataclasses.replace(reg, y=reg.y[keep], W=reg.W[keep], block=reg.block[keep],
                               index=reg.index[keep])
