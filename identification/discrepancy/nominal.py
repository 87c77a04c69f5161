"""The nominal model of the inverse view (module docstring of identification.discrepancy):
its columns, its block-weighted least squares and the extended designs effects build on it."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from jointbench.identification.discrepancy.signals import Signals, signals, stack
from jointbench.identification.effects.base import Column, Design, hat, sign0
from jointbench.identification.filtering import FilterSettings, derivatives
from jointbench.identification.log import Log, LogError
from jointbench.identification.parameters import JOINT_MOTOR, RIGID

# Eq. (13) with MX, MY folded into P (gravity at rest at qs), link Coulomb friction FS included
# (Table 1 has it, every real link has it); without FS for a nominal that leaves it out (a
# user's model without link friction: then `link_coulomb` is a candidate).
NOMINAL_TWO_MASS = tuple(n for n in JOINT_MOTOR if n not in ("MX", "MY")) + ("P",)
NOMINAL_TWO_MASS_NO_FS = tuple(n for n in NOMINAL_TWO_MASS if n != "FS")
NOMINAL_RIGID = RIGID[:3]   # J FV FS: the offset is the `offset` effect
# The 3-point chain's own error in the link equation (eq. 22 at the sample period T): its
# second difference reads q'' + T^2 / 12 q(4) + ..., an error of 0.4 % of the spring torque at
# 12 Hz at the paper's rate. A free column q(4) carries it, so that no effect is credited with it:
# without it a dead band of a few tenths of a mrad "explains" half the residual of an exactly
# linear axis (tests/indep/simulator.py's wrist, frictionless, ideal sensors). The motor equation
# gets no such column: on a log with rows clipped out it trades with K. Numerics, not physics: never reported.
NUMERICS = ("d4q",)


def nominal_columns(sig: Signals, tau: np.ndarray | None = None,
                    deflection: np.ndarray | None = None, link_friction: bool = True,
                    v0: float = 0.0) -> Design:
    """y and the nominal columns; `tau` replaces the measured torque (torque lag),
    `deflection` the spring deflection qm - q (backlash's dead zone); `link_friction`: the
    link Coulomb friction FS s(q') is a nominal column (eq. 13), s the sign, or with `v0` > 0
    [rad/s] the smooth sign tanh(q' / v0) (link_law)."""
    tau = sig.tau if tau is None else tau
    if not sig.has_link:
        y = stack(sig, tau, None)
        W = np.column_stack([stack(sig, c, None)
                             for c in (sig.qmdd, sig.qmd, sign0(sig.qmd))])
        return y, W, NOMINAL_RIGID
    dk = hat(sig.qm - sig.q if deflection is None else deflection)
    z = None
    y = stack(sig, tau, z)
    cols = [stack(sig, sig.qmdd, z), stack(sig, sig.qmd, z), stack(sig, sign0(sig.qmd), z),
            stack(sig, dk, -dk), stack(sig, z, sig.qdd), stack(sig, z, sig.qd)]
    if link_friction:
        cols.append(stack(sig, z, smooth_sign(sig.qd, v0)))
    cols.append(stack(sig, z, sig.g * np.sin(sig.q - sig.qs)))
    # the chain's own error (NUMERICS): q(4) by the same 3-point differences
    cols += [stack(sig, z, _d4(sig, sig.qdd))]
    names = NOMINAL_TWO_MASS if link_friction else NOMINAL_TWO_MASS_NO_FS
    return y, np.column_stack(cols), names + NUMERICS


def smooth_sign(v: np.ndarray, v0: float) -> np.ndarray:
    """The Coulomb friction's law of the speed v: sign(v) (sign0) for v0 = 0, tanh(v / v0)
    for v0 > 0 (NaN counted as 0)."""
    return np.tanh(np.nan_to_num(v) / v0) if v0 > 0 else sign0(v)


# The smooth sign's speeds link_law tries: a geometric grid over this span of the link's
# largest speed (LAW_TOP percentile of |q'|), then a bounded refinement around the best; the
# sign itself (v0 = 0) besides.
LAW_SPAN = (1e-5, 0.3)
LAW_POINTS = 25
LAW_TOP = 99.0


def link_law(sig: Signals, y: np.ndarray, W: np.ndarray, names: tuple[str, ...],
             w: np.ndarray) -> float:
    """The link Coulomb friction's speed v0 of tanh(q' / v0) (0: the sign) that fits the
    nominal best: least weighted RSS at the block weights `w` over 0 and a geometric grid of
    LAW_SPAN times the link's largest speed, refined between the best point's neighbours.

    Near zero speed a real link's friction is no sign: it is smooth (a regularised contact,
    the independent simulator's tanh(q' / 1 mrad/s)) or holds the spring's torque while the
    link sticks, and the measured torque is low-passed besides. With the sign's full FS
    claimed at every creeping row, the link equation's misfit follows the spring's
    deflection while the link sticks, the homogeneous link equation shrinks as a whole (K
    and JL half their values), and a searched spring law (a hardening, a dead band) takes
    the misfit up as a cause: on a soft axis whose motor a torque ripple makes stick, the
    link residual is 0.49 N m with the sign and 0.04 with the simulator's own law, found
    here. The law is the nominal's, part of the reference every effect is tested against,
    never a cause; a log whose link friction is a sign keeps v0 = 0 or one under its
    resolution. Conversely, searched without a dead band the law takes part of the dead
    band's misfit up: an extended model that holds a backlash holds its own law, searched on
    its design (identification.discrepancy.candidates._own_law)."""
    j = names.index("FS")
    top = float(np.percentile(np.abs(np.nan_to_num(sig.qd[sig.sl])), LAW_TOP))
    if top <= 0:
        return 0.0
    A, b = _with_bias(sig, W) * w[:, None], y * w

    def cost(v0: float) -> float:
        # the weighted RSS by the normal equations of the column-scaled design, as
        # heldout.fitted_rss (an SVD per trial costs 40 times more on loaded cores)
        A[:, j] = stack(sig, None, smooth_sign(sig.qd, v0)) * w
        scale = np.linalg.norm(A, axis=0)
        scale[scale == 0] = 1.0
        As = A / scale
        G, c = As.T @ As, As.T @ b
        x = np.linalg.lstsq(G, c, rcond=None)[0]
        return float(b @ b - 2 * x @ c + x @ G @ x)

    grid = np.geomspace(LAW_SPAN[0] * top, LAW_SPAN[1] * top, LAW_POINTS)
    costs = [cost(v) for v in grid]
    i = int(np.argmin(costs))
    lo, hi = np.log(grid[max(i - 1, 0)]), np.log(grid[min(i + 1, len(grid) - 1)])
    best = optimize.minimize_scalar(lambda x: cost(float(np.exp(x))), bounds=(lo, hi),
                                    method="bounded", options={"xatol": 1e-2})
    v0, c = (float(np.exp(best.x)), float(best.fun)) if best.fun < costs[i] else (
        float(grid[i]), costs[i])
    return v0 if c < cost(0.0) else 0.0


def _led(sig: Signals, x: np.ndarray, lead: float) -> np.ndarray:
    """x + lead x' (3-point central difference at the raw rate; where it is undefined, at
    the ends which the decimation drops, x alone)."""
    if not lead:
        return x
    return x + lead * np.nan_to_num(derivatives(x, sig.ts, 1, 3)[1])


def _d4(sig: Signals, xdd: np.ndarray) -> np.ndarray:
    """The fourth derivative from the second by the same 3-point differences; 0 where
    undefined (the ends, which the decimation drops)."""
    return np.nan_to_num(derivatives(xdd, sig.ts, 2, 3)[2])


def solve(W: np.ndarray, y: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float]:
    """Row-weighted least squares with column scaling: X and the weighted RSS. A column that
    is zero (a term the data does not excite, such as gravity on a horizontal axis) is not
    identifiable: its parameter is exactly 0, not the rounding of a minimum-norm solution."""
    Ww, yw = W * w[:, None], y * w
    scale = np.linalg.norm(Ww, axis=0)
    live = scale > 0
    X = np.zeros(W.shape[1])
    if live.any():
        Xl, *_ = np.linalg.lstsq(Ww[:, live] / scale[live], yw, rcond=None)
        X[live] = Xl / scale[live]
    r = yw - Ww @ X
    return X, float(r @ r)


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
    link_friction: bool = True         # FS sign(q') among the columns (logs with q)
    bias: float = 0.0       # the motor equation's constant estimated beside X (_with_bias)
    link_v0: float = 0.0    # the link Coulomb friction's tanh(q' / v0) speed (0: sign; link_law)
    # What diagnose's searches reuse between trials on this very model (discrepancy.stacked):
    # not an input, not compared, and fresh in a dataclasses.replace copy (init=False).
    memo: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def residual(self) -> np.ndarray:
        return self.y - self.W @ self.X

    def value(self, name: str) -> float:
        return float(self.X[self.names.index(name)])

    def block_rms(self, residual: np.ndarray, b: int) -> float:
        rows = self.block == b
        return float(np.sqrt(np.mean(residual[rows] ** 2))) if rows.any() else float("nan")

    def relative_error_pct(self, residual: np.ndarray, b: int) -> float:
        """100 ||residual|| / ||reference|| on block b: the inverse view's error metric (NaN
        where the block predicts nothing: an axis whose spring the data cannot tell from rigid)."""
        ref = self.reference_rms[b]
        return 100.0 * self.block_rms(residual, b) / ref if ref > 0 else float("nan")

    def extend(self, *columns: Column,
               rated: tuple[np.ndarray | None, ...] | None = None) -> Design:
        """y, W and names with raw-rate (name, motor, link) columns added (an effect); the
        nominal leads none of them (`rated`: identification.effects.base.Rows.extend)."""
        cols = [stack(self.sig, motor, link) for _, motor, link in columns]
        return (self.y, np.column_stack([self.W, *cols]),
                self.names + tuple(name for name, _, _ in columns))

    def columns(self, tau: np.ndarray | None = None,
                deflection: np.ndarray | None = None, lead: float = 0.0) -> Design:
        """The nominal design rebuilt with another torque or spring deflection, or with the
        motor equation's torque led by `lead` [s] (only the columns they change: y, the
        stiffness column, the motor columns). `lead` = T: the command of a current loop that
        lags it by T, tau = (1 + T d/dt) (the motor equation's right-hand side), so that the
        residual stays in the measured torque whatever T (torque_lag)."""
        s = self.sig
        y, W = self.y, self.W
        if tau is not None or deflection is not None or lead:
            W = W.copy()
        if tau is not None:
            y = stack(s, tau, None)
        if (deflection is not None or lead) and s.has_link:
            if not lead:
                dk = hat(s.qm - s.q if deflection is None else deflection)
                W[:, self.names.index("K")] = stack(s, dk, -dk)
            else:
                dk, dk_d = self._led_parts("dk", deflection)
                W[:, self.names.index("K")] = np.concatenate([dk + lead * dk_d, -dk])
        if lead:
            names = ("J", "FV", "FS") if not s.has_link else ("Jm", "FVm", "FSm")
            acc, acc_d = self._led_parts("qmdd")
            sgn, sgn_d = self._led_parts("sign")
            vel = self._led_parts("qmd")[0]
            zero = np.zeros(len(s.index) if s.has_link else 0)
            for name, x in zip(names, (acc + lead * acc_d, vel + lead * acc, sgn + lead * sgn_d)):
                W[:, self.names.index(name)] = np.concatenate([x, zero])
        return y, W, self.names

    def _led_parts(self, which: str,
                   deflection: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The decimated motor rows of a column x and of its 3-point derivative x' (_led's):
        the decimation is linear, so a column led by T, x + T x', is dec(x) + T dec(x') for
        every T a lag's search tries, and x, x' are decimated once. `which`: "qmdd", "qmd",
        "sign" (sign0(qm')) or "dk" (the hat-paired spring deflection, qm - q or
        `deflection`). Kept on the memo; a deflection's by the very array."""
        kept = self.memo.setdefault("led", {})
        hit = kept.get(which)
        if hit is not None and hit[0] is deflection:
            return hit[1], hit[2]
        s = self.sig
        x = {"qmdd": lambda: s.qmdd, "qmd": lambda: s.qmd, "sign": lambda: sign0(s.qmd),
             "dk": lambda: hat(s.qm - s.q if deflection is None else deflection)}[which]()
        parts = (s.dec(x), s.dec(np.nan_to_num(derivatives(x, s.ts, 1, 3)[1])))
        kept[which] = (deflection, *parts)
        return parts

    def fit(self, y: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, float]:
        """Least squares of a design on these rows with the nominal's block weights."""
        return solve(W, y, self.weights)


# The spring of a two-mass axis carries the torque that moves the link: a share of the motor
# torque set by the inertias and frictions (a few % on a wrist, most of it on the prototype).
# Under a thousandth of it the nominal's link equation describes no link (a collapse).
COLLAPSED = 1e-3

# The scale test of the block weights (scale_shrunk): the held-out test's bar (heldout.ALPHA
# over heldout.SEGMENTS contiguous segments), here on a delete-one-segment jackknife of K.
SCALE_SEGMENTS = 40
SCALE_ALPHA = 1e-3
SCALE_STEPS = 12   # bisection halvings of scale_weights' exponent (to 2.4e-4)


def scale_shrunk(Wb: np.ndarray, y: np.ndarray, block: np.ndarray, w: np.ndarray,
                 k: int) -> bool:
    """Whether the block-weighted fit's spring stiffness K (column k of the stacked design
    Wb) lies below the equal-weight fit's by more than the latter's standard error allows:
    (K_eq - K_w) sign(K_eq) > t(SCALE_ALPHA, G - 1) se(K_eq), se by the delete-one-segment
    jackknife over G contiguous segments (the residual is low-passed: a row-wise standard
    error would understate it by the filter's correlation length).

    The link equation is homogeneous (0 = K (qm - q) - JL q'' - ...): its rows fix the
    ratios of its parameters, never their scale, which only K's motor column sets. Its
    weighted residual is that scale times the misfit of the ratios, so a weight on the link
    rows buys residual by shrinking the whole block, paid for only through the motor rows.
    Weights of 1 / (each block's residual spread) are an efficiency reweighting of one
    model when the residuals are noise, and then move K by a fraction of its standard
    error; when a motor-side misfit (a lag, a ripple) inflates the motor residual, the link
    equation gets a hundred times the weight and K shrinks by tens of standard errors: a
    degenerate reference, which the block weights must not set."""
    K_eq, bound = _shrink_bound(Wb, y, block, k)
    return bool((K_eq - solve(Wb, y, w)[0][k]) * np.sign(K_eq) > bound)


def _shrink_bound(Wb: np.ndarray, y: np.ndarray, block: np.ndarray,
                  k: int) -> tuple[float, float]:
    """scale_shrunk's equal-weight K and the shrink it allows, t(SCALE_ALPHA, G - 1) se."""
    n = int(np.sum(block == 0))
    G = min(SCALE_SEGMENTS, n)
    seg = np.minimum(np.arange(n) * G // n, G - 1)
    seg = np.r_[seg, seg]
    K_eq = solve(Wb, y, np.ones(len(y)))[0][k]
    # the replicates by the normal equations of the column-scaled design, the sums over
    # all segments less one segment's (as link_law's cost: a least squares per replicate
    # would cost as much as the rest of the nominal)
    scale = np.linalg.norm(Wb, axis=0)
    scale[scale == 0] = 1.0
    A = Wb / scale
    Gs = np.array([A[seg == g].T @ A[seg == g] for g in range(G)])
    cs = np.array([A[seg == g].T @ y[seg == g] for g in range(G)])
    G_all, c_all = Gs.sum(axis=0), cs.sum(axis=0)
    Kj = np.array([np.linalg.lstsq(G_all - Gs[g], c_all - cs[g], rcond=None)[0][k]
                   for g in range(G)]) / scale[k]
    se = np.sqrt((G - 1) / G * np.sum((Kj - Kj.mean()) ** 2))
    return float(K_eq), float(stats.t.isf(SCALE_ALPHA, G - 1) * se)


def scale_weights(Wb: np.ndarray, y: np.ndarray, block: np.ndarray, w: np.ndarray,
                  k: int) -> np.ndarray:
    """The block weights `w` (1 / each block's residual spread) taken only as far as they
    leave the link equation's scale alone: w^f with the largest f in [0, 1] whose fit K is
    not shrunk (scale_shrunk), by bisection to SCALE_STEPS halvings; f = 0 is equal weights.

    Equal weights alone would give the motor equation, whose residual a motor-side misfit
    (a ripple) inflates, the fit of a link-side effect beside it (a hardening, whose
    evidence is in the link rows); the weights as far as the scale allows keep the link
    rows' say without the degenerate shrink."""
    K_eq, bound = _shrink_bound(Wb, y, block, k)
    # w is one weight per block: each trial's fit by the blocks' normal equations of the
    # column-scaled design, w_b^(2 f) G_b summed (a least squares per trial would cost as
    # much as the rest of the nominal)
    scale = np.linalg.norm(Wb, axis=0)
    scale[scale == 0] = 1.0
    A = Wb / scale
    parts = [(float(w[block == b][0]), A[block == b].T @ A[block == b],
              A[block == b].T @ y[block == b]) for b in np.unique(block)]

    def K_at(f: float) -> float:
        Gf = sum(wb ** (2 * f) * Gb for wb, Gb, _ in parts)
        cf = sum(wb ** (2 * f) * cb for wb, _, cb in parts)
        return float(np.linalg.lstsq(Gf, cf, rcond=None)[0][k] / scale[k])

    lo, hi = 0.0, 1.0
    for _ in range(SCALE_STEPS):
        f = 0.5 * (lo + hi)
        if (K_eq - K_at(f)) * np.sign(K_eq) > bound:
            hi = f
        else:
            lo = f
    return w ** lo


def nominal(log: Log, settings: FilterSettings, link_friction: bool = True,
            limit_applied: bool = False) -> Nominal:
    """Identify the nominal model (block-weighted least squares, as for eq. 13);
    `link_friction` False leaves the link Coulomb friction FS out (then a candidate). Its
    parameters and block weights are estimated with a constant in the motor equation beside
    them (_with_bias), which the model itself leaves out. `limit_applied`: the rows at the
    metadata's tau_max are kept (signals)."""
    sig = signals(log, settings, limit_applied)
    link_friction = link_friction and sig.has_link
    y, W, names = nominal_columns(sig, link_friction=link_friction)
    n = len(sig.index)
    if n <= W.shape[1]:
        # the rows out of reach of a clipped torque cannot hold the fit (beside its constant)
        raise LogError(f"only {n} of the filtered rows are out of reach of the clipped torque "
                       f"samples, too few to fit the nominal model's {W.shape[1]} parameters; "
                       "record the experiment with a smaller amplitude or a wider torque range",
                       log.path, column="tau_m")
    block = np.r_[np.zeros(n, int), np.ones(n, int)] if sig.has_link else np.zeros(n, int)
    Wb = _with_bias(sig, W)
    X, _ = solve(Wb, y, np.ones(len(y)))
    w = np.ones(len(y))
    for bl in np.unique(block):
        rows = block == bl
        s = np.sqrt(np.mean((y[rows] - Wb[rows] @ X) ** 2))
        w[rows] = 1.0 / s if s > 0 else 1.0
    v0 = link_law(sig, y, W, names, w) if link_friction else 0.0
    if v0 > 0:
        y, W, names = nominal_columns(sig, link_friction=True, v0=v0)
        Wb = _with_bias(sig, W)
        X, _ = solve(Wb, y, np.ones(len(y)))
        for bl in np.unique(block):
            rows = block == bl
            s = np.sqrt(np.mean((y[rows] - Wb[rows] @ X) ** 2))
            w[rows] = 1.0 / s if s > 0 else 1.0
    X = solve(Wb, y, w)[0]
    ref = _reference_rms(y, W, X[:-1], block, names)
    if sig.has_link and (ref[1] < COLLAPSED * ref[0] or
                         scale_shrunk(Wb, y, block, w, names.index("K"))):
        # The link equation (homogeneous: 0 = ...) collapsed towards 0 = 0 (the spring
        # carries next to none of the motor torque, its residual's spread measures no noise,
        # and a weight of 1 / (that spread) pins every extended fit to the collapse): both
        # equations are in N m, equal weights. Or the weights shrank its scale beyond K's
        # standard error (scale_shrunk): the weights as far as the scale allows.
        w = np.ones(len(y)) if ref[1] < COLLAPSED * ref[0] else scale_weights(
            Wb, y, block, w, names.index("K"))
        X = solve(Wb, y, w)[0]
        ref = _reference_rms(y, W, X[:-1], block, names)
    X, bias = X[:-1], float(X[-1])
    r = (y - W @ X) * w
    return Nominal(names=names, y=y, W=W, block=block, weights=w, X=X, rss=float(r @ r),
                   reference_rms=tuple(ref), sig=sig, link_friction=link_friction, bias=bias,
                   link_v0=v0)


def _with_bias(sig: Signals, W: np.ndarray) -> np.ndarray:
    """W with a constant column in the motor equation's rows (eq. 6 with a constant torque),
    last: what the nominal's parameters and block weights are estimated with.

    A constant torque on the motor (a current sensor's offset, a constant load: the `offset`
    effect) is no part of the nominal, so it stays out of its design and `offset` is tested
    against it as any effect is. Left out of the estimate too, it would go into the motor
    rows' residual, and the block weights (1 / that residual's spread) would give the motor
    equation a fraction of its weight: the homogeneous link equation (0 = ...), whose scale
    only K's motor column sets, then shrinks as a whole; even with the right weights, the
    part of the offset that sign(qm') and the mean deflection take would move K. With the
    constant beside them the parameters and weights do not move with an offset
    (tests/sim/test_diagnose_offset_nominal.py)."""
    return np.column_stack([W, stack(sig, np.ones(len(sig.qm)), None)])


def _reference_rms(y: np.ndarray, W: np.ndarray, X: np.ndarray, block: np.ndarray,
                   names: tuple[str, ...]) -> list[float]:
    """Per block, the RMS of what it predicts: the measured torque; the transmitted torque
    (transmitted_rms: the spring torque K (qm - q) of the nominal)."""
    ref = [float(np.sqrt(np.mean(y[block == 0] ** 2)))]
    if (block == 1).any():
        ref.append(transmitted_rms(W, X, block))
    return ref


def transmitted_rms(W: np.ndarray, X: np.ndarray, block: np.ndarray) -> float:
    """RMS over the link rows of the torque the transmission carries from the motor to the
    link: the columns that act in both equations (action and reaction, eqs. 5-6), the spring
    K (qm - q) and what an effect adds to it (a spring damping D (qm' - q'), a hardening's
    second spring). The link equation is homogeneous (0 = ...), so its residual means
    something only against a torque of the same model: with a spring damping as large as
    the spring's stiffness times the mode, the damping carries most of that torque, and a
    residual over the spring part alone would call worse a model that removes most of the
    held-out residual."""
    motor, link = block == 0, block == 1
    both = np.any(W[motor] != 0, axis=0) & np.any(W[link] != 0, axis=0)
    return float(np.sqrt(np.mean((W[link][:, both] @ X[both]) ** 2)))


def with_link_law(nom: Nominal, design: Design) -> Nominal:
    """`nom` with its link friction's law near zero speed (link_law) searched again on
    `design` (the nominal extended by the causes named so far), its parameters refitted at
    its block weights; `nom` itself when the law is the same. Searched on the nominal alone
    the law also takes up what an unmodelled effect of the link's speed leaves (a spring
    damping D (qm' - q'): tanh(q' / v0) is a viscous friction below v0); once that cause is
    in the model, the law is the friction's again."""
    if not nom.link_friction:
        return nom
    y, W, names = design
    v0 = link_law(nom.sig, y, W, names, nom.weights)
    if v0 == nom.link_v0:
        return nom
    W0 = nom.W.copy()
    W0[:, nom.names.index("FS")] = stack(nom.sig, None, smooth_sign(nom.sig.qd, v0))
    Xb = solve(_with_bias(nom.sig, W0), nom.y, nom.weights)[0]
    r = (nom.y - W0 @ Xb[:-1]) * nom.weights
    return dataclasses.replace(nom, W=W0, X=Xb[:-1], bias=float(Xb[-1]), rss=float(r @ r),
                               link_v0=v0)


def with_parameters(nom: Nominal, X: np.ndarray) -> Nominal:
    """`nom`'s rows with another estimate X (same names): a model identified elsewhere."""
    return dataclasses.replace(nom, X=np.asarray(X, float))
