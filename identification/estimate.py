"""Least squares with the paper's statistics (section 3.1, section 4).

    X^ = argmin ||y - W X||,  sigma^2 = ||rho||^2 / (r - Np),  C = sigma^2 (W^T W)^-1,
    2 sigma_i and %sigma_ri = 100 sigma_i / |X^_i|.

Beside it, unchanged, `cov_corrected`: the heteroscedasticity-and-autocorrelation-consistent
sandwich of identification/uncertainty.py, since after filtering and decimation the residuals
are not white (the paper's sigma assumes they are).

Before solving, the columns are scaled to unit norm and the singular values checked: the
parameters the data cannot identify (structural or data rank deficiency) are named and left
out, never returned as numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointbench.identification.uncertainty import HACResult, hac_covariance

COND_LIMIT = 1e8  # scaled condition number beyond which a direction counts as unidentified


class NotIdentifiable(ValueError):
    """No parameter can be estimated from the data (no excitation at all)."""


@dataclass(frozen=True)
class LSResult:
    """Estimate, covariance and the paper's statistics; `unidentifiable` names the parameters
    dropped by the rank check (their entries in X, sigma are NaN). `cov_corrected` is the
    autocorrelation-consistent covariance (identification/uncertainty.py), `hac` how it was
    obtained; `sigma`, `cov` stay the paper's."""

    names: tuple[str, ...]
    X: np.ndarray
    sigma: np.ndarray
    cov: np.ndarray
    sigma2: float
    residual: np.ndarray
    r: int
    cond: float
    unidentifiable: tuple[str, ...]
    reasons: dict[str, str]
    cov_corrected: np.ndarray | None = None
    hac: HACResult | None = None
    instrumental: bool = False   # solved with instruments (X = (Z^T W)^-1 Z^T y)

    @property
    def sigma_corrected(self) -> np.ndarray:
        """Standard deviations from `cov_corrected` (NaN where not available)."""
        if self.cov_corrected is None:
            return np.full(len(self.names), np.nan)
        return np.sqrt(np.diag(self.cov_corrected))

    def std_corrected(self, name: str) -> float:
        return float(self.sigma_corrected[self.names.index(name)])

    @property
    def rel_sigma_pct(self) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return 100.0 * self.sigma / np.abs(self.X)

    def value(self, name: str) -> float:
        return float(self.X[self.names.index(name)])

    def std(self, name: str) -> float:
        return float(self.sigma[self.names.index(name)])

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residual ** 2)))


def _unidentified(Ws: np.ndarray, names: tuple[str, ...]) -> dict[str, str]:
    """Parameters to leave out, one per near-null direction of the column-scaled W: the one
    with the largest share of that direction; the reason names the others in it (only their
    combination is identifiable)."""
    reasons: dict[str, str] = {}
    live = list(range(len(names)))
    while live:
        # the singular values alone decide whether a direction is near-null; the vectors
        # (an n x p U besides) are computed only when one is
        sv = np.linalg.svd(Ws[:, live], compute_uv=False)
        if sv[0] != 0 and sv[-1] >= sv[0] / COND_LIMIT:
            break
        _, sv, Vt = np.linalg.svd(Ws[:, live], full_matrices=False)
        if sv[0] == 0:
            for i in live:
                reasons[names[i]] = "its column is zero: the data does not excite it"
            break
        if sv[-1] >= sv[0] / COND_LIMIT:
            break
        v = np.abs(Vt[-1])
        worst = int(np.argmax(v))
        others = [names[live[i]] for i in np.flatnonzero(v > 0.1 * v.max()) if i != worst]
        ratio = sv[-1] / sv[0]
        if others:
            reasons[names[live[worst]]] = (
                f"its column is (nearly) a combination of {', '.join(others)}: only their "
                f"combination is identifiable (singular value ratio {ratio:.1e})")
        else:
            reasons[names[live[worst]]] = ("its column is (nearly) zero: the data does not "
                                           f"excite it (singular value ratio {ratio:.1e})")
        live.pop(worst)
    return reasons


def least_squares(W: np.ndarray, y: np.ndarray, names: tuple[str, ...],
                  weights: np.ndarray | None = None, time: np.ndarray | None = None,
                  corrected: bool = True, instruments: np.ndarray | None = None) -> LSResult:
    """Solve eq. (21) for X with the paper's statistics and the corrected covariance.
    `weights` scales each row (weighted least squares, for example 1/sigma per equation
    block); `time` labels each row's sampling instant (rows of stacked equation blocks taken
    at the same instant share a label; default: every row its own instant, in order);
    `corrected=False` skips the corrected covariance (`cov_corrected` None).

    `instruments` Z (the shape of W): the instrumental-variable estimate
    X^ = (Z^T W)^-1 Z^T y, with C = sigma^2 (Z^T W)^-1 Z^T Z (W^T Z)^-1 and the sandwich on
    the scores Z_i rho_i. In closed loop the torque noise reaches the positions, so W is
    correlated with the equation error and least squares is biased; instruments built from
    the reference alone (identification/instruments.py) are not.
    Raises NotIdentifiable when no parameter is excited, ValueError on shape mismatch."""
    W = np.asarray(W, dtype=float)
    y = np.asarray(y, dtype=float)
    if W.ndim != 2 or W.shape[0] != len(y) or W.shape[1] != len(names):
        raise ValueError(f"W is {W.shape}, y has {len(y)} rows and there are {len(names)} names")
    if instruments is not None and np.shape(instruments) != W.shape:
        raise ValueError(f"instruments are {np.shape(instruments)}, W is {W.shape}")
    Ww, yw = (W, y) if weights is None else (W * weights[:, None], y * weights)
    Zw = None if instruments is None else (
        np.asarray(instruments, dtype=float) * (1.0 if weights is None else weights[:, None]))
    norms = np.linalg.norm(Ww, axis=0)
    live = norms > 0
    reasons = {names[i]: "its column is zero: the data does not excite it"
               for i in np.flatnonzero(~live)}
    sv = None   # the singular values of the scaled live columns, when all are kept
    if live.any():
        Ws = Ww[:, live] / norms[live]
        live_names = tuple(n for n, ok in zip(names, live) if ok)
        sv = np.linalg.svd(Ws, compute_uv=False)   # `_unidentified`'s first test, made here
        if not (sv[0] != 0 and sv[-1] >= sv[0] / COND_LIMIT):
            reasons.update(_unidentified(Ws, live_names))
            sv = None
    keep = np.array([n not in reasons for n in names])
    if not keep.any():
        raise NotIdentifiable("no parameter is identifiable from this data: "
                              + "; ".join(f"{n}: {why}" for n, why in reasons.items()))
    r, Np = W.shape[0], int(keep.sum())
    if r <= Np:
        raise NotIdentifiable(f"{r} equations for {Np} parameters: too few samples")
    Wk = Ww[:, keep]
    scale = np.linalg.norm(Wk, axis=0)
    Ws = Wk / scale
    Zs = None
    if Zw is None:
        Xs, *_ = np.linalg.lstsq(Ws, yw, rcond=None)
    else:
        Zk = Zw[:, keep]
        Zs = Zk / np.where(np.linalg.norm(Zk, axis=0) > 0, np.linalg.norm(Zk, axis=0), 1.0)
        Xs = np.linalg.solve(Zs.T @ Ws, Zs.T @ yw)
    Xk = Xs / scale
    rho = yw - Wk @ Xk
    sigma2 = float(rho @ rho) / (r - Np)
    if Zs is None:
        cov_s = sigma2 * np.linalg.inv(Ws.T @ Ws)
    else:
        B = np.linalg.inv(Zs.T @ Ws)
        cov_s = sigma2 * B @ (Zs.T @ Zs) @ B.T
    cov_k = cov_s / np.outer(scale, scale)
    X = np.full(len(names), np.nan)
    X[keep] = Xk
    cov = np.full((len(names), len(names)), np.nan)
    cov[np.ix_(keep, keep)] = cov_k
    if sv is None or not np.array_equal(keep, live):
        sv = np.linalg.svd(Ws, compute_uv=False)
    residual = y - np.nan_to_num(W[:, keep] @ Xk) if weights is not None else rho
    hac, cov_corr = None, None
    if corrected:
        hac = hac_covariance(Wk, rho, time=time, cov_paper=cov_k,
                             instruments=None if Zw is None else Zw[:, keep])
        cov_corr = np.full((len(names), len(names)), np.nan)
        cov_corr[np.ix_(keep, keep)] = hac.cov
    return LSResult(names=tuple(names), X=X, sigma=np.sqrt(np.diag(cov)), cov=cov, sigma2=sigma2,
                    residual=residual, r=r, cond=float(sv[0] / sv[-1]),
                    unidentifiable=tuple(n for n in names if n in reasons), reasons=reasons,
                    cov_corrected=cov_corr, hac=hac, instrumental=Zw is not None)


def block_weighted(W: np.ndarray, y: np.ndarray, names: tuple[str, ...],
                   block: np.ndarray, time: np.ndarray | None = None,
                   instruments: np.ndarray | None = None, corrected: bool = True) -> LSResult:
    """Weighted least squares over equation blocks (motor and link equations of eq. 13): an
    ordinary solution gives each block's residual sigma, then every row is weighted by
    1 / sigma of its block, so that torque (N m) and link (N m, from encoder noise) residuals
    count by their own noise level.

    `time` labels each row's sampling instant (for example the raw sample index); the
    corrected covariance adds the weighted scores of the blocks' rows at one instant, so the
    covariance between blocks is counted at every lag. Without it the k-th row of every
    block is taken as the k-th instant. `corrected` as `least_squares`'."""
    block = np.asarray(block)
    if time is None:
        time = np.empty(len(block), dtype=int)
        for b in np.unique(block):
            rows = block == b
            time[rows] = np.arange(int(rows.sum()))
    first = least_squares(W, y, names, corrected=False, instruments=instruments)
    weights = np.ones(len(y))
    for b in np.unique(block):
        rows = block == b
        s = np.sqrt(np.mean(first.residual[rows] ** 2))
        weights[rows] = 1.0 / s if s > 0 else 1.0
    return least_squares(W, y, names, weights=weights, time=time, corrected=corrected,
                         instruments=instruments)
