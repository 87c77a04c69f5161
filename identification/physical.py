"""Physical parameters from the motor-only model's X (eq. 19, Table 3), with covariance.

Two inversions:
- `table3`: the paper's closed-form Table 3, as printed (no standard deviations).
- `invert_motor_only`: weighted nonlinear least squares of every identified X on the physical
  parameters, min (X^ - f(theta))^T C^-1 (X^ - f(theta)), whose covariance
  (J^T C^-1 J)^-1 gives the standard deviations the paper calls hard to get.

f(theta) is eq. (19) extended by the corrected model's terms. With gravity stiffness
G = g (MY cos qc - MX sin qc) (from eq. 7 around the mean angle qc) and c = 1 + G / K, eq. (5)
gives tau = Jm qm'' + FVm qm' + FSm s + (JL q'' + FV q' + Q(qm)) / c, hence
    X1 = JL/(K c)   X2 = FV/(K c)   X3 = Jm JL/(K c)   X4 = (Jm FV + JL FVm)/(K c)
    X5 = Jm + (JL + FV FVm / K)/c   X6 = FVm + FV/c   X7 = FSm
    X8 = JL FSm/(K c)   X9 = FV FSm/(K c)   X10 = MX/c   X11 = MY/c
and c = 1 without gravity columns (the paper's eq. 19).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from jointbench.identification.estimate import LSResult
from jointbench.identification.parameters import MOTOR_ONLY_PHYSICAL

PHYSICAL = MOTOR_ONLY_PHYSICAL


class InversionError(ValueError):
    """The X's cannot be inverted to physical parameters (for example X1 or X2 near zero)."""


@dataclass(frozen=True)
class PhysicalResult:
    names: tuple[str, ...]
    values: np.ndarray
    sigma: np.ndarray
    cov: np.ndarray
    chi2: float
    method: str

    def as_dict(self) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, self.values)}

    def value(self, name: str) -> float:
        return float(self.values[self.names.index(name)])

    def std(self, name: str) -> float:
        return float(self.sigma[self.names.index(name)])


def _x_of_theta(theta: dict[str, float], names: tuple[str, ...], g: float, qc: float) -> np.ndarray:
    Jm, K, JL, FVm, FV, FSm = (theta[k] for k in PHYSICAL)
    MX, MY = theta.get("MX", 0.0), theta.get("MY", 0.0)
    c = 1.0 + g * (MY * np.cos(qc) - MX * np.sin(qc)) / K
    full = {"X1": JL / (K * c), "X2": FV / (K * c), "X3": Jm * JL / (K * c),
            "X4": (Jm * FV + JL * FVm) / (K * c), "X5": Jm + (JL + FV * FVm / K) / c,
            "X6": FVm + FV / c, "X7": FSm, "X8": JL * FSm / (K * c), "X9": FV * FSm / (K * c),
            "X10": MX / c, "X11": MY / c}
    return np.array([full[n] for n in names])


def _near_zero(X: dict[str, float], sigma: dict[str, float] | None, name: str,
               why: str) -> None:
    """InversionError when X[name] is missing, zero, not finite, or (given `sigma`) within two
    standard deviations of zero; `why` says what needs it."""
    if name not in X:
        raise InversionError(f"{name} is not identified: {why}")
    value = X[name]
    s = None if sigma is None else sigma.get(name)
    if not np.isfinite(value) or value == 0:
        raise InversionError(f"{name} = {value:.3g}: {why}")
    if s is not None and np.isfinite(s) and abs(value) <= 2 * s:
        raise InversionError(f"{name} = {value:.3g} is not distinguishable from zero "
                             f"(2 sigma = {2 * s:.3g}): {why}")


def table3(X: dict[str, float], sigma: dict[str, float] | None = None) -> dict[str, float]:
    """The paper's Table 3: Jm = X3/X1, FVm = (X4 - Jm X2)/X1, FV = X6 - FVm, K = FV/X2,
    JL = X1 K, FSm = X7. Raises InversionError when X1 or X2 is zero, not finite, or (given
    their standard deviations `sigma`) within two standard deviations of zero, where the
    divisions turn noise into any value."""
    _near_zero(X, sigma, "X1", "Table 3 divides by it (Jm = X3/X1, FVm = (X4 - Jm X2)/X1)")
    _near_zero(X, sigma, "X2", "Table 3 divides by it (K = FV/X2)")
    Jm = X["X3"] / X["X1"]
    FVm = (X["X4"] - Jm * X["X2"]) / X["X1"]
    FV = X["X6"] - FVm
    K = FV / X["X2"]
    return {"Jm": Jm, "K": K, "JL": X["X1"] * K, "FVm": FVm, "FV": FV, "FSm": X["X7"]}


def _start(X: dict[str, float]) -> dict[str, float]:
    """A starting point that avoids Table 3's ill-conditioned K = FV / X2: K from X5
    (X5 = Jm + X1 K + X2 FVm), then FV from X2."""
    Jm = X["X3"] / X["X1"]
    FVm = max((X["X4"] - Jm * X["X2"]) / X["X1"], 0.0)
    K = (X["X5"] - Jm - X["X2"] * FVm) / X["X1"]
    if not K > 0:
        raise InversionError(f"the X's give a non-positive stiffness (K = {K:.4g}): "
                             "the data does not identify the joint mode")
    FV = max(X["X2"] * K, 0.0)
    theta = {"Jm": Jm, "K": K, "JL": X["X1"] * K, "FVm": FVm, "FV": FV, "FSm": X["X7"]}
    if "X10" in X:
        theta["MX"], theta["MY"] = X["X10"], X["X11"]
    return theta


def invert_motor_only(ls: LSResult, g: float = 9.81, qc: float = 0.0) -> PhysicalResult:
    """Physical parameters with standard deviations from the motor-only X's (weighted
    nonlinear least squares, covariance propagated). Raises InversionError when an X its
    start reads (X1..X5, X7) is not identified, or X1 or X3 is nearly zero."""
    names = tuple(n for n in ls.names if n not in ls.unidentifiable)
    for need in ("X1", "X2", "X3", "X4", "X5", "X7"):
        if need not in names:
            raise InversionError(f"{need} is not identified ({ls.reasons.get(need, '')}): "
                                 "the physical parameters cannot be computed")
    X = {n: ls.value(n) for n in names}
    sigma = {n: ls.std(n) for n in names}
    _near_zero(X, sigma, "X1", "the motor-only inversion divides by it (Jm = X3/X1, "
                               "K = (X5 - Jm - X2 FVm)/X1)")
    _near_zero(X, sigma, "X3", "the motor-only inversion needs X3 = Jm JL/K to separate Jm "
                               "from JL")
    idx = [ls.names.index(n) for n in names]
    C = ls.cov[np.ix_(idx, idx)]
    L = np.linalg.cholesky(C)
    xhat = np.array([X[n] for n in names])
    theta0 = _start(X)
    keys = tuple(theta0)
    scale = np.array([abs(v) if v != 0 else 1.0 for v in theta0.values()])

    def residual(p: np.ndarray) -> np.ndarray:
        theta = dict(zip(keys, p * scale))
        return np.linalg.solve(L, xhat - _x_of_theta(theta, names, g, qc))

    sol = optimize.least_squares(residual, np.ones(len(keys)), method="lm", x_scale="jac")
    J = sol.jac / scale  # d residual / d theta
    dof = max(len(names) - len(keys), 1)
    chi2 = float(sol.fun @ sol.fun)
    cov = np.linalg.pinv(J.T @ J) * max(1.0, chi2 / dof)
    values = sol.x * scale
    return PhysicalResult(names=keys, values=values, sigma=np.sqrt(np.diag(cov)), cov=cov,
                          chi2=chi2, method="weighted nonlinear least squares on all X")
