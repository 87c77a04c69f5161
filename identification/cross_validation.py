"""Cross-validation of an identification on another log (`identify --validate OTHER.csv`).

The identified X predicts the other log's torque in the inverse view: the other log goes
through the same model's regressor (eq. 13, eqs. 18-20 or the rigid eq. 6) with its own
filter, designed from that log (`defaults.settings_for`, the chain options of the fit kept),
and 100 ||y - W X|| / ||y|| over its motor-torque rows is set beside the fit's own direct
validation (the paper's Figure 2, on the data of the fit). Pure numerics: no MuJoCo.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from jointbench.identification import regressors
from jointbench.identification.band_choice import band_for
from jointbench.identification.filter_choice import settings_for
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.identify import Identification
from jointbench.identification.log import Log, LogError
from jointbench.identification.output_values import finite_json, rms

# each model's rows on another log, given the identified physical parameters p (the
# joint-motor model's Coulomb reversals are placed by them, as identify places them)
REGRESSORS = {
    "joint-motor": lambda log, s, p: regressors.joint_motor(log, s, p),
    "motor-only": lambda log, s, p: regressors.motor_only(log, s, corrected=True),
    "motor-only-printed": lambda log, s, p: regressors.motor_only(log, s, corrected=False),
    "rigid": lambda log, s, p: regressors.rigid(log, s)}


@dataclass(frozen=True)
class Validation:
    """The identified model on another log: relative error [%] and residual RMS [N m, N
    prismatic] of the predicted motor torque on the other log (`relative_error_pct`,
    `residual_rms`) and on the fit's own (`fit_*`), the other log's filter (`settings`,
    `note` when it is a generic one), the rows compared and the arrays `t`, `y`, `y_pred`."""

    path: str | None
    model: str
    settings: FilterSettings
    rows: int
    relative_error_pct: float
    residual_rms: float
    fit_relative_error_pct: float
    fit_residual_rms: float
    t: np.ndarray
    y: np.ndarray
    y_pred: np.ndarray
    note: str | None = None

    @property
    def ratio(self) -> float:
        """Cross error over the fit's own (1: the model predicts new data as well as its own)."""
        return self.relative_error_pct / self.fit_relative_error_pct

    def to_json(self) -> dict:
        """The `validation` object of `identify --json` (docs/cli.md)."""
        s = self.settings
        return finite_json({
            "file": self.path, "model": self.model, "view": "inverse", "rows": self.rows,
            "relative_error_pct": self.relative_error_pct, "residual_rms": self.residual_rms,
            "fit_relative_error_pct": self.fit_relative_error_pct,
            "fit_residual_rms": self.fit_residual_rms, "ratio": self.ratio,
            "filter": {"wn_rad_s": s.wn, "order": s.m, "decimate": s.Nd},
            "note": self.note})

    def text(self, unit: str = "N m") -> str:
        """Two lines for the `identify` report."""
        s = self.settings
        lines = [f"validation on {self.path} (inverse view: the identified {self.model} model "
                 f"predicts that log's motor torque): relative error "
                 f"{self.relative_error_pct:.3g} % against {self.fit_relative_error_pct:.3g} % "
                 f"on the fit's own log (ratio {self.ratio:.3g}); motor-torque residual rms "
                 f"{self.residual_rms:.4g} {unit} against {self.fit_residual_rms:.4g} {unit}; "
                 f"{self.rows} equations, that log's filter wn = {s.wn:.4g} rad/s, Nd = {s.Nd}"]
        if self.note:
            lines.append(f"validation filter: {self.note}")
        return "\n".join(lines)


def validate_on(result: Identification, other: Log, f1_hz: float | None = None) -> Validation:
    """Predict `other`'s motor torque with the identified X of `result` (inverse view).

    The filter is `settings_for(other, f1_hz)` (its own rate and band; its wide band,
    `band_choice.band_for`, when the fit took the wide one), with the chain options
    of the fit (ZOH alignment, torque filter, skip, stencil). Raises LogError when the other
    log lacks what the model needs (q for joint-motor) or is too short for the filter.
    """
    base, note = settings_for(other, f1_hz)
    base = band_for(other, base, result.band)   # the fit's band rule: wide there, wide here
    s = result.settings
    settings = replace(base, zoh=s.zoh, filter_torque=s.filter_torque, skip=s.skip,
                       stencil=s.stencil)
    nd = 4 if result.model.startswith("motor-only") else 2
    if len(other) < settings.min_samples(nd):
        raise LogError(f"{len(other)} samples are too few to validate with this filter "
                       f"(Nd = {settings.Nd})", other.path)
    reg = REGRESSORS[result.model](other, settings, result.physical)
    ls = result.ls
    keep = [i for i, n in enumerate(ls.names) if n not in ls.unidentifiable]
    y_pred = reg.W[:, keep] @ ls.X[keep]
    rows = reg.block == 0
    own = result.block == 0
    y, pred = reg.y[rows], y_pred[rows]
    return Validation(
        path=other.path, model=result.model, settings=settings, rows=int(rows.sum()),
        relative_error_pct=float(100 * np.linalg.norm(y - pred) / np.linalg.norm(y)),
        residual_rms=rms(y - pred), fit_relative_error_pct=result.relative_error_pct,
        fit_residual_rms=rms(result.y[own] - result.y_pred[own]),
        t=other.t[reg.index[rows]], y=y, y_pred=pred, note=note)
