"""Inverse view of the discrepancy analysis: which unmodelled effect (CONTRACT section 4) the
residual of the nominal model carries, ranked by what it explains and by BIC.

The nominal model is the linear two-mass axis the paper's eq. (13) describes, with two terms
moved out of it because they are candidate effects:

    motor (eq. 6):  tau_m = Jm qm'' + FVm qm' + FSm sign(qm') + K (qm - q)
    link  (eq. 5):  0     = JL q'' + FV q' - K (qm - q) + P g sin(q - qs)

Gravity is kept as the experiment assumes it, at rest at the start position qs (CONTRACT
section 2: an experiment starts at rest in equilibrium), P = m l [kg m]; the `gravity` effect
frees its phase (MX, MY of eq. 13). The link Coulomb friction FS of eq. 13 is the
`link_coulomb` effect. Logs without `q` use the motor-side equation only (rigid axis,
tau_m = J qm'' + FV qm' + FS sign(qm')) and test the effects observable there.

Every column, nominal or effect, is built at the raw rate from the same zero-phase Butterworth
signals and goes through the same decimation (section 3.2), so the band-limited equation stays
linear in the parameters. Rows are weighted by 1 / sigma of their block (nominal residual).
Nonlinear effect parameters (backlash width, hardening engagement, lag time constant, ripple
period) are found by a bounded scalar search (scipy.optimize) or a grid, the linear ones by
least squares at each trial.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy import optimize, signal, stats

from jointbench.identification.effects import EFFECTS, NONE
from jointbench.identification.filtering import FilterSettings, derivatives, lowpass, zoh_align
from jointbench.identification.log import Log, LogError

NOMINAL_TWO_MASS = ("Jm", "FVm", "FSm", "K", "JL", "FV", "P")
NOMINAL_RIGID = ("J", "FV", "FS")

BIC_MIN = 10.0          # "very strong" evidence on Kass and Raftery's scale
# Practical size: the effect must move its block's prediction by this much (% RMS) to be
# named. The link block is held to more because every real link has some Coulomb friction:
# on the bench models their own FS moves the link equation by 2.1 % (prototype, Table 1) to
# 4.2 % (arm axis6), and that is the nominal state of those axes, not a hidden effect.
SIZE_MIN_PCT = (3.0, 5.0)   # motor block, link block


@dataclass(frozen=True)
class Signals:
    """Band-limited raw-rate signals of one log (section 3.2), shared by every column."""

    ts: float
    g: float
    qm: np.ndarray
    qmd: np.ndarray
    qmdd: np.ndarray
    tau: np.ndarray          # measured torque, ZOH-aligned and low-passed
    tau_raw: np.ndarray      # measured torque, as logged
    q: np.ndarray | None
    qd: np.ndarray | None
    qdd: np.ndarray | None
    qs: float                # rest position assumed by the nominal gravity term
    settings: FilterSettings
    sl: slice                # raw samples that every derivative defines
    index: np.ndarray        # raw index of each decimated row

    @property
    def has_link(self) -> bool:
        return self.q is not None

    def lp(self, x: np.ndarray) -> np.ndarray:
        s = self.settings
        return lowpass(x, s.wn, s.ts, s.m)

    def dec(self, x: np.ndarray) -> np.ndarray:
        """The raw-rate column x on the decimated rows (scipy.signal.decimate, zero phase)."""
        s = self.settings
        x = np.asarray(x, dtype=float)[self.sl]
        xd = signal.decimate(x, s.Nd, zero_phase=True) if s.Nd > 1 else x
        e = s.edge
        return xd[e:len(xd) - e]


def signals(log: Log, settings: FilterSettings) -> Signals:
    """Filter and differentiate the log once (eq. 22 after the Butterworth of eq. 25)."""
    s = settings
    qm, qmd, qmdd = derivatives(lowpass(log.q_m, s.wn, s.ts, s.m), s.ts, 2, s.stencil)
    q = qd = qdd = None
    if log.q is not None:
        q, qd, qdd = derivatives(lowpass(log.q, s.wn, s.ts, s.m), s.ts, 2, s.stencil)
    n = len(log.t)
    if n < s.min_samples(2):
        raise LogError(f"{n} samples are too few for the diagnosis filter (Nd = {s.Nd}): at "
                       f"least {s.min_samples(2)} are needed", log.path)
    sl = slice(max(2, s.skip), n - 2)
    m = len(range(*sl.indices(n)))
    nd = (m + s.Nd - 1) // s.Nd if s.Nd > 1 else m
    index = sl.start + np.arange(nd) * s.Nd
    index = index[s.edge:nd - s.edge]
    head = max(1, min(n // 100, 20))
    qs = float(np.mean((log.q if log.q is not None else log.q_m)[:head]))
    tau_f = lowpass(zoh_align(log.tau_m), s.wn, s.ts, s.m)
    return Signals(ts=s.ts, g=log.gravity, qm=qm, qmd=qmd, qmdd=qmdd, tau=tau_f,
                   tau_raw=np.asarray(log.tau_m, float), q=q, qd=qd, qdd=qdd, qs=qs,
                   settings=s, sl=sl, index=index)


def _sign(x: np.ndarray) -> np.ndarray:
    return np.sign(np.nan_to_num(x))


def deadzone(d: np.ndarray, b: float) -> np.ndarray:
    """d - b sign(d) beyond +-b, 0 inside: the spring deflection of a transmission with
    backlash of half-width b (MuJoCo's two-valued tendon springlength)."""
    return np.sign(d) * np.maximum(np.abs(d) - b, 0.0)


def lagged(tau: np.ndarray, T: float, ts: float) -> np.ndarray:
    """A zero-order-hold command through a first-order lag of time constant T: the lag state
    at the start of each period, x[k] = a x[k-1] + (1 - a) u[k-1], a = exp(-ts / T), x[0] = u[0]
    (the experiment starts at rest). This is what MuJoCo's exact filter actuator applies over
    the period; the mean over the period instead overestimates T by 8-30 % on the bench."""
    tau = np.asarray(tau, float)
    if T <= 0:
        return tau
    a = np.exp(-ts / T)
    x = signal.lfilter([0.0, 1 - a], [1.0, -a], tau, zi=[a * tau[0]])[0]
    x[0] = tau[0]
    return x


@dataclass(frozen=True)
class Nominal:
    """Weighted stacked regression of the nominal model on the decimated rows."""

    names: tuple[str, ...]
    y: np.ndarray           # stacked (motor rows, then link rows)
    W: np.ndarray
    block: np.ndarray
    weights: np.ndarray
    X: np.ndarray
    rss: float              # weighted residual sum of squares
    reference_rms: tuple[float, ...]   # per block: RMS of what the block predicts
    sig: Signals

    @property
    def residual(self) -> np.ndarray:
        return self.y - self.W @ self.X

    def value(self, name: str) -> float:
        return float(self.X[self.names.index(name)])

    def block_rms(self, residual: np.ndarray, b: int) -> float:
        rows = self.block == b
        return float(np.sqrt(np.mean(residual[rows] ** 2))) if rows.any() else float("nan")

    def relative_error_pct(self, residual: np.ndarray, b: int) -> float:
        """100 ||residual|| / ||reference|| on block b: the inverse view's error metric."""
        return 100.0 * self.block_rms(residual, b) / self.reference_rms[b]


def _stack(sig: Signals, motor: np.ndarray | None, link: np.ndarray | None) -> np.ndarray:
    n = len(sig.index)
    m = sig.dec(motor) if motor is not None else np.zeros(n)
    if not sig.has_link:
        return m
    li = sig.dec(link) if link is not None else np.zeros(n)
    return np.concatenate([m, li])


def _nominal_columns(sig: Signals, tau: np.ndarray | None = None,
                     b: float = 0.0) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """y and the nominal columns; `tau` replaces the measured torque (torque lag), `b` the
    spring deflection by its dead-zone (backlash)."""
    tau = sig.tau if tau is None else tau
    if not sig.has_link:
        y = _stack(sig, tau, None)
        W = np.column_stack([_stack(sig, c, None)
                             for c in (sig.qmdd, sig.qmd, _sign(sig.qmd))])
        return y, W, NOMINAL_RIGID
    d = sig.qm - sig.q
    dk = deadzone(d, b) if b > 0 else d
    z = None
    y = _stack(sig, tau, z)
    cols = [_stack(sig, sig.qmdd, z), _stack(sig, sig.qmd, z), _stack(sig, _sign(sig.qmd), z),
            _stack(sig, dk, -dk), _stack(sig, z, sig.qdd), _stack(sig, z, sig.qd),
            _stack(sig, z, sig.g * np.sin(sig.q - sig.qs))]
    return y, np.column_stack(cols), NOMINAL_TWO_MASS


def _solve(W: np.ndarray, y: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float]:
    Ww, yw = W * w[:, None], y * w
    scale = np.linalg.norm(Ww, axis=0)
    scale[scale == 0] = 1.0
    X, *_ = np.linalg.lstsq(Ww / scale, yw, rcond=None)
    X = X / scale
    r = yw - Ww @ X
    return X, float(r @ r)


def nominal(log: Log, settings: FilterSettings) -> Nominal:
    """Identify the nominal model (block-weighted least squares, as for eq. 13)."""
    sig = signals(log, settings)
    y, W, names = _nominal_columns(sig)
    n = len(sig.index)
    block = np.r_[np.zeros(n, int), np.ones(n, int)] if sig.has_link else np.zeros(n, int)
    X, _ = _solve(W, y, np.ones(len(y)))
    w = np.ones(len(y))
    for bl in np.unique(block):
        rows = block == bl
        s = np.sqrt(np.mean((y[rows] - W[rows] @ X) ** 2))
        w[rows] = 1.0 / s if s > 0 else 1.0
    X, rss = _solve(W, y, w)
    ref = [float(np.sqrt(np.mean(y[block == 0] ** 2)))]
    if sig.has_link:
        K = X[names.index("K")]
        ref.append(float(np.sqrt(np.mean((K * W[block == 1, names.index("K")]) ** 2))))
    return Nominal(names=names, y=y, W=W, block=block, weights=w, X=X, rss=rss,
                   reference_rms=tuple(ref), sig=sig)


@dataclass(frozen=True)
class Candidate:
    """One effect evaluated against the nominal model."""

    effect: str
    testable: bool
    reason: str = ""
    parameters: dict[str, float] = field(default_factory=dict)
    k: int = 0                       # extra parameters, nonlinear ones included
    rss: float = float("nan")
    explained_pct: float = 0.0       # share of the nominal weighted RSS it removes
    delta_bic: float = 0.0           # BIC(nominal) - BIC(extended): > 0 favours the effect
    p_value: float = 1.0             # F-test of the added terms
    size_pct: float = 0.0            # RMS change of its block's prediction, % of the block
    before_pct: float = float("nan")  # inverse-view error metric of its block, nominal
    after_pct: float = float("nan")   # same with the effect
    block: int = 0
    X: tuple[float, ...] = ()
    names: tuple[str, ...] = ()
    unphysical: str = ""             # why the best fit is not a physical instance of it
    residual: np.ndarray | None = field(default=None, repr=False, compare=False)
    fixed: dict = field(default_factory=dict)   # values the effect's columns are built with

    @property
    def significant(self) -> bool:
        return (self.testable and not self.unphysical and self.delta_bic > BIC_MIN
                and self.p_value < 1e-3 and self.size_pct >= SIZE_MIN_PCT[self.block])

    @property
    def gain(self) -> float:
        return self.before_pct / self.after_pct if self.after_pct > 0 else float("inf")


# --- the effects' column builders: (y, W, names, block of the metric, params from X) ---

def _with(nom: Nominal, motor: np.ndarray | None, link: np.ndarray | None, name: str):
    col = _stack(nom.sig, motor, link)
    return nom.y, np.column_stack([nom.W, col]), nom.names + (name,)


def _fit(nom: Nominal, y: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, float]:
    return _solve(W, y, nom.weights)


def _search(nom: Nominal, build: Callable[[float], tuple[np.ndarray, np.ndarray, tuple]],
            grid: np.ndarray) -> float:
    """Grid then bounded refinement of a scalar nonlinear parameter by weighted RSS."""
    costs = [_fit(nom, *build(v)[:2])[1] for v in grid]
    i = int(np.argmin(costs))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    if hi <= lo:
        return float(grid[i])
    res = optimize.minimize_scalar(lambda v: _fit(nom, *build(v)[:2])[1], bounds=(lo, hi),
                                   method="bounded", options={"xatol": 1e-3 * (hi - lo)})
    return float(res.x) if res.fun <= costs[i] else float(grid[i])


def _evaluate(nom: Nominal, effect: str, y: np.ndarray, W: np.ndarray, names: tuple,
              k: int, block: int, params: Callable[[dict], dict],
              check: Callable[[dict], str] | None = None) -> Candidate:
    X, rss = _fit(nom, y, W)
    n = len(y)
    bic0 = n * np.log(nom.rss / n) + len(nom.names) * np.log(n)
    bic1 = n * np.log(max(rss, 1e-300) / n) + (len(nom.names) + k) * np.log(n)
    dof = n - len(nom.names) - k
    F = ((nom.rss - rss) / k) / (rss / dof) if rss > 0 and dof > 0 else np.inf
    p = float(stats.f.sf(F, k, dof)) if np.isfinite(F) else 0.0
    res_before = nom.residual
    res_after = y - W @ X
    rows = nom.block == block
    pred_change = (W @ X - nom.W @ nom.X)[rows]
    size = 100 * float(np.sqrt(np.mean(pred_change ** 2))) / nom.reference_rms[block]
    values = dict(zip(names, X))
    return Candidate(effect=effect, testable=True, parameters=params(values), k=k, rss=rss,
                     unphysical=check(values) if check else "", residual=res_after,
                     explained_pct=100 * (nom.rss - rss) / nom.rss, delta_bic=float(bic0 - bic1),
                     p_value=p, size_pct=size,
                     before_pct=nom.relative_error_pct(res_before, block),
                     after_pct=nom.relative_error_pct(res_after, block), block=block,
                     X=tuple(float(x) for x in X), names=tuple(names))


# --- designs: the extended regression of each effect at fixed nonlinear parameters ---
# `fixed` holds what the columns are built with (searched or carried over from another log);
# the linear parameters come from least squares on the columns.

def _asym_column(nom: Nominal, fixed: dict) -> np.ndarray:
    sig = nom.sig
    # Friction (1 + a s)(FV |qm'| + FS): the extra torque a (FV |qm'| + FS), motor side.
    return (fixed["FV_ref"] * np.abs(np.nan_to_num(sig.qmd))
            + fixed["FS_ref"] * np.abs(_sign(sig.qmd)))


def design(nom: Nominal, effect: str, fixed: dict) -> tuple[np.ndarray, np.ndarray, tuple]:
    """y, W and names of the nominal model extended by `effect` (CONTRACT section 4)."""
    sig = nom.sig
    n = len(sig.qm)
    if effect == "gravity":
        return _with(nom, None, sig.g * np.cos(sig.q - sig.qs), "Q")
    if effect == "link_coulomb":
        return _with(nom, None, _sign(sig.qd), "FS")
    if effect == "spring_damping":
        dd = sig.qmd - sig.qd
        return _with(nom, dd, -dd, "D")
    if effect == "offset":
        return _with(nom, np.ones(n), None, "offset")
    if effect == "asymmetric_friction":
        return _with(nom, _asym_column(nom, fixed), None, "a")
    if effect == "torque_ripple":
        ph = 2 * np.pi * sig.qm / fixed["ripple_period_rad"]
        y, W, names = _with(nom, np.sin(ph), None, "As")
        return y, np.column_stack([W, _stack(sig, np.cos(ph), None)]), names + ("Ac",)
    if effect == "torque_lag":
        tau = sig.lp(zoh_align(lagged(sig.tau_raw, fixed["lag_s"], sig.ts)))
        return _nominal_columns(sig, tau=tau)
    if effect == "backlash":
        return _nominal_columns(sig, b=fixed["backlash_rad"])
    if effect == "hardening":
        dz = deadzone(sig.qm - sig.q, fixed["deflection_rad"])
        return _with(nom, dz, -dz, "Kh")
    raise ValueError(f"unknown effect {effect!r}")


def _searched(nom: Nominal, effect: str, key: str, grid: np.ndarray,
              base: dict | None = None) -> dict:
    base = dict(base or {})
    v = _search(nom, lambda x: design(nom, effect, {**base, key: x}), grid)
    return {**base, key: v}


def _gravity_params(qs: float):
    def params(v):
        # P g sin(x) + Q g cos(x) vanishes at x = -atan(Q / P): the rest lies that far away.
        offset = float(np.arctan(v["Q"] / v["P"])) if v["P"] != 0 else 0.0
        phi = qs - offset
        return {"gravity_offset_rad": offset,
                "MX": -v["P"] * np.sin(phi) + v["Q"] * np.cos(phi),
                "MY": v["P"] * np.cos(phi) + v["Q"] * np.sin(phi), "rest_rad": phi}
    return params


def _test(nom: Nominal, effect: str) -> Candidate:
    """Search the effect's nonlinear parameters, then evaluate it (module docstring)."""
    sig = nom.sig
    fixed: dict = {}
    check = None
    if effect == "gravity":
        k, block, params = 1, 1, _gravity_params(sig.qs)
    elif effect == "link_coulomb":
        k, block, params = 1, 1, lambda v: {"FS": v["FS"]}
        check = lambda v: "" if v["FS"] > 0 else f"FS = {v['FS']:.4g} <= 0"  # noqa: E731
    elif effect == "spring_damping":
        k, block, params = 1, 1, lambda v: {"D": v["D"]}
        check = lambda v: "" if v["D"] > 0 else f"D = {v['D']:.4g} <= 0"  # noqa: E731
    elif effect == "offset":
        k, block, params = 1, 0, lambda v: {"offset": v["offset"]}
    elif effect == "asymmetric_friction":
        fixed = {"FV_ref": nom.value("FVm" if sig.has_link else "FV"),
                 "FS_ref": nom.value("FSm" if sig.has_link else "FS")}
        k, block, params = 1, 0, lambda v: {"asymmetry": v["a"]}
    elif effect == "torque_ripple":
        span = float(np.ptp(sig.qm[sig.sl]))
        # Periods from encoder-scale steps to the motion span (the column must vary).
        grid = np.geomspace(max(span / 2000, 1e-4), max(span, 2e-4), 160)
        fixed = _searched(nom, effect, "ripple_period_rad", grid)
        p = fixed["ripple_period_rad"]
        # The bench's ripple adds A sin(2 pi qm / p + phase) to the rotor torque: the logged
        # torque carries -A sin(...).
        k, block = 3, 0
        params = lambda v: {"ripple_amplitude": float(np.hypot(v["As"], v["Ac"])),  # noqa: E731
                            "ripple_period_rad": p,
                            "ripple_phase_rad": float(np.arctan2(-v["Ac"], -v["As"]))}
    elif effect == "torque_lag":
        grid = np.r_[0.0, np.geomspace(0.2 * sig.ts, 50 * sig.ts, 40)]
        fixed = _searched(nom, effect, "lag_s", grid)
        # No extra column: the lag replaces the torque. One extra parameter.
        k, block, params = 1, 0, lambda v: {"lag_s": fixed["lag_s"]}
    elif effect == "backlash":
        dmax = float(np.percentile(np.abs((sig.qm - sig.q)[sig.sl]), 95))
        fixed = _searched(nom, effect, "backlash_rad", np.linspace(0.0, 0.8 * dmax, 41))
        k, block = 1, 1
        params = lambda v: {"backlash_rad": fixed["backlash_rad"], "K": v["K"]}  # noqa: E731
        check = lambda v: "" if v["K"] > 0 else f"stiffness K = {v['K']:.4g} <= 0"  # noqa: E731
    elif effect == "hardening":
        dmax = float(np.percentile(np.abs((sig.qm - sig.q)[sig.sl]), 99))
        # Geometric grid: the engagement may sit near the encoder scale on a stiff joint.
        fixed = _searched(nom, effect, "deflection_rad",
                          np.geomspace(0.02 * dmax, 0.9 * dmax, 60))
        K0 = nom.value("K")
        k, block = 2, 1
        params = lambda v: {"hardening_ratio": v["Kh"] / v["K"],  # noqa: E731
                            "deflection_rad": fixed["deflection_rad"], "K": v["K"]}

        def check(v):
            # K -> 0 with a large Kh is a dead band: that is backlash, not hardening.
            if v["K"] < 0.25 * K0 or v["Kh"] <= 0:
                return (f"K = {v['K']:.4g} and Kh = {v['Kh']:.4g}: not a stiffness rising "
                        f"from the nominal K = {K0:.4g} (a dead band is backlash)")
            return ""
    else:
        raise ValueError(f"unknown effect {effect!r}")
    y, W, names = design(nom, effect, fixed)
    c = _evaluate(nom, effect, y, W, names, k, block, params, check)
    return dataclasses.replace(c, fixed=fixed)


def predict(nom: Nominal, c: Candidate | None) -> np.ndarray:
    """The residual on `nom`'s rows (possibly another log's) of the nominal model (c None,
    with nom.X) or of candidate c with its own parameters and fixed values: cross-validation."""
    if c is None:
        return nom.residual
    y, W, _ = design(nom, c.effect, c.fixed)
    return y - W @ np.asarray(c.X)


def with_parameters(nom: Nominal, X: np.ndarray) -> Nominal:
    """`nom`'s rows with another estimate X (same names): a model identified elsewhere."""
    return dataclasses.replace(nom, X=np.asarray(X, float))


RIGID_TESTS = ("offset", "asymmetric_friction", "torque_ripple", "torque_lag")
WHY_NOT_RIGID = ("it acts between the motor and the link or on the link: without the link "
                 "position q the rigid motor-side model cannot separate it")


@dataclass(frozen=True)
class InverseDiagnosis:
    nominal: Nominal
    candidates: tuple[Candidate, ...]   # ranked, best first; untestable ones last

    @property
    def named(self) -> Candidate | None:
        best = self.candidates[0] if self.candidates else None
        return best if best is not None and best.significant else None

    @property
    def named_cause(self) -> str:
        return self.named.effect if self.named else NONE


def diagnose_inverse(log: Log, settings: FilterSettings,
                     effects: tuple[str, ...] | None = None) -> InverseDiagnosis:
    """Evaluate every effect of CONTRACT section 4 against the nominal model of `log` and rank
    them: significant ones (BIC and F-test, and a practical size) first, by delta BIC; the
    first is named when it is significant."""
    nom = nominal(log, settings)
    out: list[Candidate] = []
    for name in effects or tuple(EFFECTS):
        if not nom.sig.has_link and name not in RIGID_TESTS:
            out.append(Candidate(effect=name, testable=False, reason=WHY_NOT_RIGID))
            continue
        out.append(_test(nom, name))
    # Significant effects first, by delta BIC; then the others. Ranking all by delta BIC alone
    # would let the link Coulomb friction every real link has (large delta BIC, small size)
    # hide a significant motor-side effect.
    out.sort(key=lambda c: (not c.testable, not c.significant, bool(c.unphysical),
                            -c.delta_bic))
    return InverseDiagnosis(nominal=nom, candidates=tuple(out))
