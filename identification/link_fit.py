"""The motor-only model solved with the link reconstructed from the motor angle.

Eqs. (18)-(20) eliminate q through eq. (14), which puts the torque's own derivatives tau'' and
tau' in the regressor. In closed loop those carry the current loop's torque noise, which the
controller answers: the columns are correlated with the equation error, and least squares is
biased by a factor growing with JL / Jm (the noise term X1 w'' is JL / Jm + 1 times the noise at
the first mode; heavy link, JL / Jm = 10: K -16 %, JL -46 %). The paper's assumption that the
link Coulomb friction FS is not excited leaves it out as well (JL +2.7 % on a soft axis).

Here q is not eliminated but computed from the motor angle through the link's own equation (5)
(identification/link_sim.py): with a = K / JL, b = FV / JL, the deflection qm - q is
    d = H (qm'' + b qm' + c phi + gx cos q + gy sin q),   H = 1 / (s^2 + b s + a),
phi the link friction (stick-slip) and c, gx, gy as in link_sim. The motor equation (6),
    tau = Jm qm'' + FVm qm' + FSm sign(qm') + K d,
is linear in X = (Jm, FVm, FSm, K, K c, K MX / JL, K MY / JL) once a and b are fixed, and every
column is a filtered motor position (no torque), as in the joint-motor model. a and b are found
by variable projection on the same rows (trust region on log a, log b; their columns
dm/da = -H^2 U, dm/db = K H qm' - s H^2 U, U the input of d times K), from the eqs. (18)-(20)
estimate; the link friction phi, the gravity terms and the motor reversals (placed as the
joint-motor model places them, with the motor's stick phases: `regressors._friction_models`
with the drive (tau - K d) / Jm, d = qm - q on the reconstructed link) come from the previous
round. The reference's instruments
(identification/instruments.py) then replace least squares for the last passes. A gravity the
data cannot tell from zero is left out (it trades with K). JL = K / a, FV = b JL, FS = c JL.
The link's friction switches inside the sample interval (`simulate_link`), as a real axis'
does.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy import optimize, stats

from jointbench.identification import regressors
from jointbench.identification.estimate import LSResult, least_squares
from jointbench.identification.filtering import (FilterSettings, antialias_gain, decimate,
                                                 held_missed, kept_rows, lowpass, zoh_align)
from jointbench.identification.instruments import instrument_log
from jointbench.identification.link_sim import inverse, inverse_at, simulate_link, spectra
from jointbench.identification.log import Log
from jointbench.identification.saturation import exclude_clipped

NAMES = ("Jm", "FVm", "FSm", "K", "Kc", "Kgx", "Kgy", "a", "b")
LINEAR = 7            # the first seven enter linearly
ROUNDS = 3            # profile updates (link friction, gravity, reversals), each with (a, b)
ROUNDS_AGAIN = 1      # the same after the gravity is left out (from the converged point)
GRAVITY_Z = 3.0       # MX or MY this many corrected sigma from zero keeps the gravity columns
IV_PASSES = 2         # then passes with instruments
IV_SETTLED = 0.99     # the last pass's step must lie inside this confidence region
B_FLOOR = 1e-6        # FV / JL kept positive (the link's response needs some damping)
GAIN_FLOOR = 1e-15    # the decimation's gain below which a bin is left out (`_Rows._responses`)


@dataclass(frozen=True)
class LinkFit:
    """The estimate: physical parameters with standard deviations (paper's and corrected),
    the linearised LS result on NAMES, the rows (y, prediction, sample index) and notes."""

    physical: dict[str, float]
    sigma: dict[str, float]
    sigma_corrected: dict[str, float]
    ls: LSResult
    y: np.ndarray
    y_pred: np.ndarray
    index: np.ndarray
    notes: tuple[str, ...]
    warnings: tuple[str, ...] = ()


class _Rows:
    """The motor rows of one log for given (a, b) and given profiles (phi, gravity, reversal
    rate): the filtered motor derivatives and their spectra are computed once, the decimated
    torque, qm'', qm' and sign once per profile.

    Decimation is linear, and so is the link's response in its inputs: the Jacobian's columns
    dm/da and dm/db (`derivatives`) are summed in the frequency domain and decimated as the two
    columns they are, not as the nine responses they sum (the same numbers to rounding)."""

    def __init__(self, log: Log, s: FilterSettings, lp: Callable = lowpass, stick: bool = True):
        self.log, self.s, self.stick = log, s, stick
        self.qm = regressors._filtered(log.q_m, s, 2, lp)
        self.tau = regressors._torque(log, s, lp=lp)
        self.g = log.gravity
        self.bad = ~np.isfinite(self.qm[2])
        self.gravity = self.g != 0    # False: the gravity columns are zero (not identified)
        # the spectra are kept on the bins the decimation passes (`_responses`)
        spec = spectra([self.qm[2], self.qm[1]], s.ts)
        self._fft = 2 * (len(spec[0]) - 1)
        gain = antialias_gain(s.Nd, self._fft) if s.Nd > 1 else None
        self._bins = None if gain is None else int(np.flatnonzero(gain >= GAIN_FLOOR)[-1]) + 1
        self._gain = None if gain is None else gain[:self._bins]
        self.motor_spectra = self._cut(spec)   # of qm'', qm'
        self._key: tuple | None = None
        # decimate_parallel's valid rows before the sign's: the torque, qm'', qm'
        self.finite = np.isfinite(self.tau) & np.isfinite(self.qm[1]) & ~self.bad
        self._span: tuple[int, int] | None = None
        self._H: tuple | None = None
        self._s2 = self.motor_spectra[0] * self.motor_spectra[0]    # s^2 on the bins
        self._missed: np.ndarray | None = None      # `filtering.held_missed` of the torque

    def profiles(self, p: dict[str, float]) -> None:
        """The link friction phi and gravity (link_sim with p's a, b, c, gx, gy) and the motor
        reversals (placed with p's FSm / Jm), kept until the next call (kept as they are
        when those are the same). With `stick`, the motor's Coulomb column is its friction
        state with the stick phases (`friction_state`), driven by (tau - K d) / Jm with the
        reconstructed deflection d = qm - q, as the joint-motor model's is by the measured
        one: without torque noise or feed-forward the closed loop can hold the motor at rest
        for long stretches (a heavy link on a small motor), where the friction balances the
        drive instead of giving +-FSm, and a sign column biases Jm and FVm."""
        a, b, K = p["a"], p["b"], p["K"]
        # the columns are H(g cos q), H(g sin q): Kgx = K MX / JL, so g MX / JL = g Kgx / K
        c = max(p["Kc"] / K, 0.0) if K > 0 else 0.0
        gx, gy = ((self.g * p["Kgx"] / K, self.g * p["Kgy"] / K) if K > 0 and self.gravity
                  else (0.0, 0.0))
        rate = p["FSm"] / p["Jm"] if p["Jm"] > 0 and p["FSm"] > 0 else 0.0
        stick = self.stick and rate > 0 and K > 0
        friction = ({n: p[n] for n in ("Jm", "FVm", "FSm", "K")} if stick else (rate, 0.0))
        key = (a, b, c, gx, gy, rate, self.gravity) + ((p["Jm"], p["FVm"], K) if stick else ())
        if key == self._key:
            return
        q, phi = simulate_link(self.log.q_m, self.s.ts, a, b, c, gx, gy)
        self.phi = zoh_align(phi)            # the step means at the samples
        g = self.g if self.gravity else 0.0
        self.cos, self.sin = g * np.cos(q), g * np.sin(q)
        s, U, u0 = self._cut(spectra([self.phi, self.cos, self.sin], self.s.ts))
        self.spectra = (s, np.vstack([self.motor_spectra[1], U]),
                        np.r_[self.motor_spectra[2], u0])
        # the link inputs (`_link`): the first row, qm'' + b qm', is made for each b
        self._ins = np.vstack([U[:1], U])
        self._i0 = np.r_[0.0, u0]
        self._live = np.r_[False, np.any(U != 0, axis=1) | (u0 != 0)]
        # the reversals placed as the joint-motor chain places them; the held torque's share
        # the chain misses is linear in the torque: made once, scaled by 1 / Jm
        motor, _ = regressors._friction_models(self.log, friction, self.log.q_m - q)
        if len(motor) == 3:
            if self._missed is None:
                self._missed = held_missed(self.log.tau_m, self.s)
            self.sign = regressors._sign(self.qm[1], self.s, motor[0], drive=motor[2],
                                         missed=self._missed / p["Jm"])
        else:
            self.sign = regressors._sign(self.qm[1], self.s, *motor)
        self._rows(self.sign)
        self._key, self._H = key, None

    def _cut(self, spec: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
        """`link_sim.spectra`'s (s, U, u0) on the bins `_responses` uses."""
        s, U, u0 = spec
        return (s, U, u0) if self._bins is None else (s[:self._bins], U[:, :self._bins], u0)

    def _rows(self, sign: np.ndarray) -> None:
        """The rows `decimate_parallel` keeps for the torque and the columns (qm'', qm', the
        motor's `sign` and the link's responses, NaN where qm'' is), less those near a clipped
        torque (`exclude_clipped`, as for every model); the decimated torque and motor columns
        on them (the torque, qm'' and qm' decimated once per span), and the span the
        decimation filters."""
        sign = np.where(self.bad, np.nan, sign)
        valid = self.finite & np.isfinite(sign)
        self.first = max(int(np.argmax(valid)), self.s.skip)
        self.last = len(valid) - int(np.argmax(valid[::-1]))
        span = (self.first, self.last)
        if self._span != span:
            self._span = span
            self._motor = self._decimate_span(np.column_stack([self.tau, self.qm[2],
                                                               self.qm[1]]))
        D = np.column_stack([self._motor, self._decimate_span(sign[:, None])])
        yd, Wd, index = kept_rows(D[:, 0], D[:, 1:], self.first, self.s)
        reg = exclude_clipped(regressors.Regressor("motor-only", NAMES[:3], yd, Wd,
                                                   np.zeros(len(yd), int), index, self.s),
                              self.log)
        self.y, self.motor, self.index = reg.y, reg.W, reg.index

    def _decimate_span(self, X: np.ndarray) -> np.ndarray:
        """The columns X decimated by Nd over the span of `_rows` (filtering.decimate, as in
        `decimate_parallel`), one column at a time: the same numbers as the columns filtered
        together, in about two thirds of the time (each pass of the filter runs over one
        contiguous array)."""
        X = X[self.first:self.last]
        if self.s.Nd == 1:
            return X.copy()
        return np.column_stack([decimate(x, self.s.Nd) for x in X.T])

    def _link(self, a: float, b: float) -> tuple[np.ndarray, ...]:
        """s, H = 1 / (s^2 + b s + a), the spectra of the link inputs u = (qm'' + b qm', phi,
        g cos q, g sin q), their first samples, and which of them are not zero (no gravity:
        the last two are), for the last (a, b) asked for."""
        if self._H is None or self._H[0] != (a, b):
            s, U, u0 = self.spectra     # of qm'', qm', phi, g cos q, g sin q
            ins, i0, live = self._ins, self._i0, self._live
            np.add(U[0], b * U[1], out=ins[0])
            i0[0] = u0[0] + b * u0[1]
            live[0] = np.any(ins[0] != 0) or i0[0] != 0
            self._H = ((a, b), s, 1.0 / (self._s2 + b * s + a), ins, i0, live)
        return self._H[1:]

    def _responses(self, spec: np.ndarray, const: np.ndarray) -> np.ndarray:
        """The decimated columns of the signals whose spectra (less their first sample) are
        the rows of `spec` and whose first samples are `const`, on the rows of `_rows`. The
        anti-alias pass is applied where the responses are made, in the frequency domain
        (`filtering.antialias_gain`: the same zero-phase filter, a gain on the bins; a
        constant passes with the gain at 0), and the inverse transform is read at the kept
        rows alone (`link_sim.inverse_at`), on the bins where that gain is at least
        GAIN_FLOOR (the Chebyshev's stopband falls monotonically: past them, less than that
        share of any input is left): no pass over the record per column. It differs from
        `decimate`'s only within the filter's transient of the record's end, where the
        response continues as the link's own instead of oddly (the first rows: the link
        starts from rest)."""
        if self._gain is None:     # no decimation
            x = inverse(spec, self.spectra[0], len(self.tau))
            return (x[:, self.index] + const[:, None]).T
        k = (self.index - self.first) // self.s.Nd
        x = inverse_at(spec * self._gain, self._fft, self.first, self.s.Nd, int(k[-1]) + 1)
        return (x[:, k] + (const * self._gain[0])[:, None]).T

    def linear(self, p: dict[str, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The decimated rows (y, the LINEAR columns qm'', qm', sign, H u_i, raw sample
        index) for p's a, b; a zero input's column is zero."""
        a = p["a"]
        s, H, ins, i0, live = self._link(a, p["b"])
        resp = np.zeros((len(self.index), len(ins)))
        resp[:, live] = self._responses(H * ins[live], i0[live] / a)
        return self.y, np.column_stack([self.motor, resp]), self.index

    def derivatives(self, p: dict[str, float]) -> np.ndarray:
        """The decimated columns dm/da = -sum beta_i H^2 u_i and dm/db = K H qm' - sum
        beta_i s H^2 u_i at p (beta = K, Kc, Kgx, Kgy), on the rows of `linear`."""
        a, K = p["a"], p["K"]
        s, H, ins, i0, live = self._link(a, p["b"])
        beta = np.array([K, p["Kc"], p["Kgx"], p["Kgy"]])[live]
        HH = H * H
        bu = beta @ ins[live]
        spec = np.vstack([-HH * bu, K * H * self.spectra[1][1] - s * HH * bu])
        return self._responses(spec, np.array([-(beta @ i0[live]) / a ** 2,
                                               K * self.spectra[2][1] / a]))

    def design(self, p: dict[str, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(y, the Jacobian J = (the LINEAR columns, dm/da, dm/db) at p, index): m = Jm qm''
        + FVm qm' + FSm sign + sum beta_i H u_i, linear in the first LINEAR parameters."""
        y, L, idx = self.linear(p)
        return y, np.column_stack([L, self.derivatives(p)]), idx


def _model(W: np.ndarray, p: dict[str, float]) -> np.ndarray:
    return W[:, :LINEAR] @ np.array([p[n] for n in NAMES[:LINEAR]])


def _solve(rows: _Rows, log: Log, p: dict[str, float], Z: tuple | None = None,
           corrected: bool = False):
    """One Gauss-Newton pass: the linearised rows y - m(p) + J p = J X solved for X, with the
    instruments `Z` = (instrument rows, their index) when given and covering the rows."""
    y, J, idx = rows.design(p)
    ylin = y - _model(J, p) + J @ np.array([p[n] for n in NAMES])
    inst = None
    if Z is not None:
        where = {k: i for i, k in enumerate(Z[1].tolist())}
        pick = [where.get(k) for k in idx.tolist()]
        inst = None if any(i is None for i in pick) else Z[0][pick]
    ls = least_squares(J, ylin, NAMES, time=idx, corrected=corrected, instruments=inst)
    return ls, y, J, idx


def _orthonormal(W: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """QR of the nonzero columns of W scaled to unit norm: (Q, R, the columns' norms with 0
    for the zero columns: no gravity, no link friction)."""
    norms = np.linalg.norm(W, axis=0)
    live = norms > 0
    Q, R = np.linalg.qr(W[:, live] / norms[live])
    return Q, R, norms


def _linear(rows: _Rows, log: Log, p: dict[str, float]
            ) -> tuple[dict[str, float], np.ndarray, Callable[[], np.ndarray]]:
    """The linear parameters for the (a, b) of `p` by least squares on the first LINEAR
    columns (profiles as they are), the residual, and a function giving its Jacobian with
    respect to (log a, log b) at those linear parameters projected off the linear columns
    (variable projection, Kaufman's form; made when the trust region asks for it: at the
    points it steps to, not at the trial points it rejects)."""
    y, L, _ = rows.linear(p)
    Q, R, norms = _orthonormal(L)
    x = np.zeros(LINEAR)
    x[norms > 0] = np.linalg.solve(R, Q.T @ y) / norms[norms > 0]
    new = dict(p)
    new.update({n: float(v) for n, v in zip(NAMES, x)})
    r = y - _model(L, new)

    def jacobian() -> np.ndarray:
        Jab = rows.derivatives(new) * np.array([new["a"], new["b"]])
        return -(Jab - Q @ (Q.T @ Jab))

    return new, r, jacobian


def _converge(rows: _Rows, log: Log, p: dict[str, float], rounds: int) -> dict[str, float]:
    """`rounds` of: profiles from `p`, then (a, b) by variable projection (trust region on
    log a, log b; the linear parameters solved at every point)."""
    for _ in range(rounds):
        rows.profiles(p)      # friction, gravity and reversals of the previous round
        cache: dict[tuple[float, float], tuple] = {}

        def evaluate(x: np.ndarray) -> tuple:
            key = (float(x[0]), float(x[1]))
            if key not in cache:
                cache.clear()
                cache[key] = _linear(rows, log, {**p, "a": np.exp(x[0]), "b": np.exp(x[1])})
            return cache[key]

        sol = optimize.least_squares(lambda x: evaluate(x)[1], np.log([p["a"], p["b"]]),
                                     jac=lambda x: evaluate(x)[2](), method="trf",
                                     x_scale=1.0)
        p = evaluate(sol.x)[0]
    return p


def _final(rows: _Rows, log: Log, p: dict[str, float], Z) -> tuple[tuple, dict | None, set]:
    """IV_PASSES Gauss-Newton passes with the instruments `Z` (a function of the parameters,
    or None: none), then the last linearised solve with the corrected covariance at the point
    p returned; the point the last pass started from (None without instruments): the steps
    X - p and p - that point say whether the passes converge (`_unsettled`); and the
    parameters some pass put outside the physical region (`_unphysical`; the next pass
    starts from the point with FV / JL floored at B_FLOOR)."""
    before, stray = None, set()
    if Z is not None:
        for _ in range(IV_PASSES):
            rows.profiles(p)
            ls, *_ = _solve(rows, log, p, Z=Z(p))
            stray.update(_unphysical(ls))
            before = p
            p = {n: float(v) if np.isfinite(v) else 0.0 for n, v in zip(NAMES, ls.X)}
            p["b"] = max(p["b"], B_FLOOR)
    rows.profiles(p)
    ls, y, J, idx = _solve(rows, log, p, Z=None if Z is None else Z(p), corrected=True)
    return (p, ls, y, J, idx), before, stray


def _unsettled(ls: LSResult, p: dict[str, float], before: dict[str, float]
               ) -> tuple[float, float, float] | None:
    """Whether the instrumental Gauss-Newton passes failed to converge: the last step
    d = X - p and the one before it, p - `before`, each measured against the estimate's own
    covariance C (corrected, the paper's where that is missing) as d^T C^+ d on the
    parameters it covers. A converging iteration either steps by less than the estimate's
    uncertainty (inside the confidence region IV_SETTLED: the chi-square quantile with as many
    degrees of freedom; X = p at its fixed point) or still shrinks its steps; a last step
    outside that region and no shorter than the one before means the passes oscillate or
    diverge (a weak instrument), and where they stop is set by rounding. Returns (last step,
    step before, the quantile) then, None otherwise."""
    C = ls.cov_corrected if ls.cov_corrected is not None else ls.cov
    if C is None:
        return None
    x = np.array([p[n] for n in NAMES])
    d, e = ls.X - x, x - np.array([before[n] for n in NAMES])
    live = np.isfinite(d) & np.isfinite(e) & (np.nan_to_num(np.diag(C)) > 0)  # NaN: no column
    C = C[np.ix_(live, live)]
    if not live.any() or not np.all(np.isfinite(C)):
        return None
    P = np.linalg.pinv(C)
    last, prev = float(d[live] @ P @ d[live]), float(e[live] @ P @ e[live])
    bound = float(stats.chi2.ppf(IV_SETTLED, int(live.sum())))
    return (last, prev, bound) if last > bound and last >= prev else None


def _unphysical(ls: LSResult) -> list[str]:
    """The physical parameters of the linearised result that no axis can have: Jm, K,
    JL = K / a not positive; FVm, FV = b JL negative by more than GRAVITY_Z corrected sigma
    (a frictionless axis puts them at zero within their noise)."""
    x = {n: ls.value(n) for n in NAMES}

    def below(n: str) -> bool:
        sd = ls.std_corrected(n)
        sd = sd if np.isfinite(sd) and sd > 0 else ls.std(n)
        return not x[n] > -GRAVITY_Z * (sd if np.isfinite(sd) else 0.0)

    bad = {"Jm": not x["Jm"] > 0, "K": not x["K"] > 0, "JL": not x["a"] > 0,
           "FVm": below("FVm"), "FV": below("b")}
    return [n for n, b in bad.items() if b]


def _final_checked(rows: _Rows, log: Log, p: dict[str, float], Z) -> tuple[tuple, str]:
    """`_final` with the instruments `Z`; when those give an unphysical estimate (a
    negative inertia or viscous friction) from the physical least-squares point `p`, or pass
    through one, or when their passes have not converged (`_unsettled`), `_final` without
    them, and a warning
    naming the cause ('' otherwise). The instruments are the columns rebuilt from the
    reference's predicted motion; the link Coulomb column (the reconstructed link's friction
    switching) is the weakest of them, and on a link whose friction FS is zero it is hardly
    correlated with its instrument at all: without torque noise to average over the
    switching, the instrumental passes can then oscillate or leave the physical region, while
    least squares is unbiased there (no noise to be correlated with)."""
    out, before, stray = _final(rows, log, p, Z)
    if Z is None or not all(p[n] > 0 for n in ("Jm", "K", "a")):
        return out, ""
    ls = out[1]
    bad, step = _unphysical(ls), _unsettled(ls, out[0], before)
    if not bad and step is None and not stray:
        return out, ""
    if bad:
        got = (f"gave an unphysical {', '.join(bad)} (Jm = {ls.value('Jm'):.4g}, K = "
               f"{ls.value('K'):.4g}, FVm = {ls.value('FVm'):.4g})")
    elif stray:
        got = (f"passed through an unphysical {', '.join(sorted(stray))} on the way (ending "
               f"at Jm = {ls.value('Jm'):.4g}, K = {ls.value('K'):.4g})")
    else:
        got = (f"did not converge (the last pass moved the estimate by {step[0]:.3g} in "
               f"chi-square against its own covariance, beyond the {IV_SETTLED:.0%} region's "
               f"{step[2]:.3g} and no less than the pass before, {step[1]:.3g}; Jm = "
               f"{ls.value('Jm'):.4g}, K = {ls.value('K'):.4g})")
    warning = (f"motor-only: the instrumental-variable passes of the link reconstruction "
               f"{got}: the instrument of the link "
               f"Coulomb friction column is weak (the link's friction switching is not in the "
               f"reference's predicted motion: a link without Coulomb friction, FS = "
               f"{p['Kc'] / p['a']:.3g} by least squares), so the least-squares link "
               f"reconstruction is kept; it is unbiased only without closed-loop torque noise")
    return _final(rows, log, p, None)[0], warning


def fit(log: Log, s: FilterSettings, start: dict[str, float], f1_hz: float | None = None,
        lp: Callable = lowpass, stick: bool = True) -> LinkFit:
    """The motor-only estimate from a starting point `start` (physical names: K, JL, Jm, FV,
    FVm, FSm and optionally FS, MX, MY); `lp`: the Butterworth (`lowpass`, or a
    `filtering.Lowpassed` shared with the eqs. (18)-(20) fit); `stick`: the motor's Coulomb
    column with its stick phases (`_Rows.profiles`), else its reversals alone. Raises ValueError when the
    start has no positive K and JL."""
    K, JL = start.get("K", 0.0), start.get("JL", 0.0)
    if not (K > 0 and JL > 0):
        raise ValueError(f"the link reconstruction needs a positive K and JL to start from "
                         f"(K = {K:.4g}, JL = {JL:.4g})")
    g = log.gravity
    a = K / JL
    p = {"Jm": start.get("Jm", 0.0), "FVm": start.get("FVm", 0.0),
         "FSm": start.get("FSm", 0.0), "K": K, "Kc": a * start.get("FS", 0.0),
         "Kgx": a * start.get("MX", 0.0), "Kgy": a * start.get("MY", 0.0), "a": a,
         "b": max(start.get("FV", 0.0) / JL, B_FLOOR)}
    rows = _Rows(log, s, lp, stick)
    p = _converge(rows, log, p, ROUNDS)
    Z, why = _instruments(log, s, f1_hz, stick)
    (p, ls, y, J, idx), warning = _final_checked(rows, log, p, Z)
    notes = [f"motor-only: link reconstructed from q_m through eq. (5) (stick-slip link "
             f"friction), variable projection from the eqs. (18)-(20) estimate, {ROUNDS} "
             f"rounds; {why}; the link's friction switching inside the sample interval"]
    left_out = None
    if rows.gravity and not _significant(ls, ("Kgx", "Kgy")):
        # a gravity stiffness the data cannot tell from zero still trades with K (both stiffen
        # the link's response): left out, the estimate of K keeps its variance; MX = MY = 0
        # are reported with the standard deviations the data gave them
        left_out = _physical(ls, g)
        rows.gravity = False
        p = _converge(rows, log, {**p, "Kgx": 0.0, "Kgy": 0.0}, ROUNDS_AGAIN)
        (p, ls, y, J, idx), warning = _final_checked(rows, log, p, Z)
        notes.append(f"the link's gravity (MX, MY) is within {GRAVITY_Z:g} sigma of zero: left "
                     "out of the model (a horizontal axis, or one at rest near its balance) "
                     "and reported as 0 with the standard deviation it had")
    physical, sigma, sigma_c = _physical(ls, g)
    if left_out is not None:
        for k in ("MX", "MY"):
            if k in left_out[0]:
                physical[k], sigma[k] = 0.0, left_out[1][k]
                if k in left_out[2]:
                    sigma_c[k] = left_out[2][k]
    return LinkFit(physical, sigma, sigma_c, ls, y, _model(J, p), idx, tuple(notes),
                   (warning,) if warning else ())


START_POINTS = 12     # antiresonances tried by `start_from_band`
START_SPAN = 30.0     # from the decimated cutoff down to this fraction of it


def start_from_band(log: Log, s: FilterSettings) -> dict[str, float]:
    """A starting point when eqs. (18)-(20) give none: the link's antiresonance sqrt(a) / 2 pi
    tried on START_POINTS geometric steps from the decimated cutoff / START_SPAN up to the
    cutoff (damping ratio 0.05), the linear parameters by least squares for each; the one of
    least residual with K > 0. Raises ValueError when none has."""
    rows = _Rows(log, s)
    top = 2 * np.pi * s.decimated_cutoff_hz
    best: tuple[float, dict[str, float]] | None = None
    for w in np.geomspace(top / START_SPAN, top, START_POINTS):
        p = {n: 0.0 for n in NAMES}
        p.update(a=w * w, b=0.1 * w)
        rows.profiles(p)
        p, r, _ = _linear(rows, log, p)
        rss = float(r @ r)
        if p["K"] > 0 and (best is None or rss < best[0]):
            best = (rss, p)
    if best is None:
        raise ValueError("no link antiresonance in the band gives a positive stiffness")
    p = best[1]
    JL = p["K"] / p["a"]
    return {"Jm": p["Jm"], "K": p["K"], "JL": JL, "FVm": p["FVm"], "FSm": max(p["FSm"], 0.0),
            "FV": p["b"] * JL}


def _instruments(log: Log, s: FilterSettings, f1_hz: float | None, stick: bool = True):
    """A function of the parameters giving the instruments (the same columns from the
    reference's predicted motor angle), or None; and a note. The link angle q, which the
    columns do not hold, is not predicted."""
    inst = instrument_log(replace(log, q=None), f1_hz)
    if inst is None:
        return None, "least squares (no instruments: no q_ref, or the log is too short)"
    rows = _Rows(inst, s, stick=stick)

    def Z(p: dict[str, float]) -> np.ndarray:
        rows.profiles(p)
        _, J, idx = rows.design(p)
        return J, idx

    return Z, "instrumental variables from q_ref's predictions for the last passes"


def _significant(ls: LSResult, names: tuple[str, ...]) -> bool:
    """Any of `names` farther than GRAVITY_Z corrected sigma from zero (the paper's sigma when
    the corrected one is missing)."""
    for n in names:
        x, sd = ls.value(n), ls.std_corrected(n)
        sd = sd if np.isfinite(sd) and sd > 0 else ls.std(n)
        if np.isfinite(x) and np.isfinite(sd) and abs(x) > GRAVITY_Z * sd:
            return True
    return False


def _physical(ls: LSResult, g: float) -> tuple[dict[str, float], ...]:
    """(JL = K / a, FV = b JL, FS = Kc / a, MX = Kgx / a, MY = Kgy / a) and the rest,
    with standard deviations by the delta method from the paper's and the corrected
    covariances."""
    x = {n: ls.value(n) for n in NAMES}
    a, b, K = x["a"], x["b"], x["K"]
    values = {"Jm": x["Jm"], "K": K, "JL": K / a, "FVm": x["FVm"], "FSm": x["FSm"],
              "FV": b * K / a, "FS": x["Kc"] / a, "MX": x["Kgx"] / a,
              "MY": x["Kgy"] / a}
    n = len(NAMES)
    G = {k: np.zeros(n) for k in values}
    i = {k: NAMES.index(k) for k in NAMES}
    for k in ("Jm", "FVm", "FSm", "K"):
        G[k][i[k]] = 1.0
    G["JL"][i["K"]], G["JL"][i["a"]] = 1 / a, -K / a ** 2
    G["FV"][i["K"]], G["FV"][i["b"]], G["FV"][i["a"]] = b / a, K / a, -b * K / a ** 2
    for name, col in (("FS", "Kc"), ("MX", "Kgx"), ("MY", "Kgy")):
        G[name][i[col]], G[name][i["a"]] = 1 / a, -x[col] / a ** 2

    def sd(cov: np.ndarray | None) -> dict[str, float]:
        if cov is None:
            return {}
        C = np.nan_to_num(cov)
        return {k: float(np.sqrt(max(G[k] @ C @ G[k], 0.0))) for k in values}

    for k in ("MX", "MY"):
        if g == 0 or not np.isfinite(values[k]):
            values.pop(k)
    return values, {k: v for k, v in sd(ls.cov).items() if k in values}, \
        {k: v for k, v in sd(ls.cov_corrected).items() if k in values}
