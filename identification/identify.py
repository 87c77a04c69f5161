"""The whole chain on one log: filter settings, regressor, least squares, physical parameters,
direct validation (Figure 2). Pure numerics: no I/O, no MuJoCo."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from identification import models as regressors
from identification.estimate import LSResult, block_weighted, least_squares
from identification.filtering import FilterSettings, default_settings
from identification.log import Log, LogError
from identification.physical import InversionError, PhysicalResult, invert_motor_only, table3

MODEL_CHOICES = ("joint-motor", "motor-only", "motor-only-printed", "rigid", "auto")


@dataclass(frozen=True)
class Identification:
    """Everything `identify` found: the model, its LS estimate, the physical parameters (with
    standard deviations where available), the filter, and the direct validation arrays."""

    model: str
    ls: LSResult
    physical: dict[str, float]
    physical_sigma: dict[str, float]
    settings: FilterSettings
    y: np.ndarray
    y_pred: np.ndarray
    t: np.ndarray
    block: np.ndarray
    notes: tuple[str, ...] = ()
    table3: dict[str, float] = field(default_factory=dict)

    @property
    def relative_error_pct(self) -> float:
        """Direct validation: 100 ||y - W X^|| / ||y|| over the torque rows."""
        rows = self.block == 0
        return float(100 * np.linalg.norm(self.y[rows] - self.y_pred[rows])
                     / np.linalg.norm(self.y[rows]))


def _check_length(log: Log, settings: FilterSettings, nd: int) -> None:
    need = settings.min_samples(nd)
    if len(log) < need:
        raise LogError(f"{len(log)} samples are too few for this filter and decimation "
                       f"(Nd = {settings.Nd}, derivatives to order {nd}): at least {need} "
                       "are needed", log.path)


def identify(log: Log, model: str = "auto", settings: FilterSettings | None = None,
             f1_hz: float | None = None) -> Identification:
    """Identify the axis of `log` with `model` (CONTRACT section 3 names, plus
    `motor-only-printed`, the paper's eq. 18 as printed). `auto` takes joint-motor when `q`
    is logged, else motor-only, and falls back to rigid when the data does not identify a
    stiffness. Raises LogError for unusable logs and NotIdentifiable when nothing is excited.
    """
    if model not in MODEL_CHOICES:
        raise ValueError(f"unknown model {model!r} (choices: {', '.join(MODEL_CHOICES)})")
    settings = settings or default_settings(log.sample_rate_hz, f1_hz)
    notes: list[str] = []
    if model == "auto":
        if log.q is not None:
            model = "joint-motor"
        else:
            try:
                result = identify(log, "motor-only", settings)
            except InversionError as err:
                notes.append(f"auto: motor-only model rejected ({err}); rigid model used")
                model = "rigid"
            else:
                if result.physical.get("K", 0) > 0 and all(
                        result.physical_sigma.get(k, np.inf) < 0.5 * abs(result.physical[k])
                        for k in ("K", "JL")):
                    return result
                notes.append("auto: the data does not identify a stiffness in the band "
                             "(K or JL has a relative standard deviation over 50 %); "
                             "rigid model used")
                model = "rigid"
    nd = 4 if model.startswith("motor-only") else 2
    _check_length(log, settings, nd)
    if model == "joint-motor":
        reg = regressors.joint_motor(log, settings)
        ls = block_weighted(reg.W, reg.y, reg.names, reg.block)
    elif model == "motor-only":
        reg = regressors.motor_only(log, settings, corrected=True)
        ls = least_squares(reg.W, reg.y, reg.names)
    elif model == "motor-only-printed":
        reg = regressors.motor_only(log, settings, corrected=False)
        ls = least_squares(reg.W, reg.y, reg.names)
    else:
        reg = regressors.rigid(log, settings)
        ls = least_squares(reg.W, reg.y, reg.names)
    physical: dict[str, float] = {}
    sigma: dict[str, float] = {}
    t3: dict[str, float] = {}
    if model.startswith("motor-only"):
        X = {n: ls.value(n) for n in ls.names if n not in ls.unidentifiable}
        try:
            t3 = table3(X)
        except (InversionError, KeyError):
            t3 = {}
        phys = invert_motor_only(ls, g=log.gravity, qc=float(np.mean(log.q_m)))
        physical, sigma = phys.as_dict(), {n: phys.std(n) for n in phys.names}
    else:
        for n in ls.names:
            if n not in ls.unidentifiable:
                physical[n] = ls.value(n)
                sigma[n] = ls.std(n)
    y_pred = reg.W[:, [i for i, n in enumerate(ls.names) if n not in ls.unidentifiable]] @ \
        ls.X[[i for i, n in enumerate(ls.names) if n not in ls.unidentifiable]]
    for n in ls.unidentifiable:
        notes.append(f"{n} not identifiable: {ls.reasons[n]}")
    for n, v in physical.items():
        if n in ("K", "Jm", "JL", "J", "FVm", "FSm", "FV", "FS") and v < 0:
            notes.append(f"{n} = {v:.4g} is unphysical (negative)")
    return Identification(model=reg.model, ls=ls, physical=physical, physical_sigma=sigma,
                          settings=settings, y=reg.y, y_pred=y_pred, t=log.t[reg.index],
                          block=reg.block, notes=tuple(notes), table3=t3)
