"""Identification models: the sampled, filtered and decimated y = W X of eq. (21).

- `joint_motor`: eq. (13), both encoders, X = (Jm FVm FSm K JL MX MY FV FS).
- `motor_only`: eqs. (18)-(20), motor encoder only, X = (X1 ... X7). `corrected=True` adds
  the columns the printed eq. (18) drops: eq. (14) carries FSm sign(qm') into q, so q' and q''
  carry the band-limited derivatives s' and s'' of s = sign(qm'); substituting into eq. (5)
  gives X8 s'' + X9 s' with X8 = JL FSm / K = X1 X7 and X9 = FV FSm / K = X2 X7. It also
  keeps gravity, which the paper neglects: the columns g cos qm, g sin qm carry X10 = MX / c
  and X11 = MY / c, where c = 1 + G / K and G is the gravity stiffness (identification/physical.py
  derives it); neglecting it biases every X by G / K (2.6 % on the prototype).
- `rigid`: eq. (6) with q = qm plus an offset, X = (J FV FS offset) (docs/cli.md).

Every signal goes through the same zero-phase Butterworth before differentiation, so the
linear relation survives the filtering (section 3.2).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from jointbench.identification.filtering import (Drive, FilterSettings, as_acceleration_sees,
                                                 coulomb_integrals, decimate,
                                                 decimate_parallel, derivatives, held_missed,
                                                 kept_rows, kink_corrected, lowpass,
                                                 stencil_view, zoh_align)
from jointbench.identification.log import Log, LogError
from jointbench.identification.parameters import JOINT_MOTOR, MOTOR_ONLY, MOTOR_ONLY_CORRECTED, RIGID

MODELS = ("joint-motor", "motor-only", "rigid")


@dataclass(frozen=True)
class Regressor:
    """Rows of y = W X after filtering and decimation.

    `block` labels each row with its equation (0: motor eq. 6 or 20, 1: link eq. 5);
    `index` is the raw sample index of the row.
    """

    model: str
    names: tuple[str, ...]
    y: np.ndarray
    W: np.ndarray
    block: np.ndarray
    index: np.ndarray
    settings: FilterSettings


def _filtered(x: np.ndarray, s: FilterSettings, nd: int, lp: Callable = lowpass
              ) -> list[np.ndarray]:
    """[x, x', ..., x^(nd)] of the Butterworth-filtered x (`lp`: `lowpass`, or a
    `filtering.Lowpassed` that filters each array once)."""
    return derivatives(lp(x, s.wn, s.ts, s.m), s.ts, nd, s.stencil)


def _sign(x: np.ndarray, s: FilterSettings, rate: float = 0.0,
          held: np.ndarray | None = None, drive: Drive | None = None,
          inside: bool = True, missed: np.ndarray | None = None) -> np.ndarray:
    """sign(x) at the samples (the paper's chain), or as the 5-point stencil sees it (the
    `stencil_view` of `coulomb_integrals`: each reversal placed between samples, weighted as
    its acceleration).
    `rate` = FS / J > 0: the reversals of the velocity x moved back to where the friction's
    kink has them (`kink_corrected`, with the held drive `held` = tau / J when given) and
    placed between samples with that kink (`crossing_share`); with `drive`, the friction's
    state with its stick phases (`coulomb_integrals`) in place of sign(x). `inside` False:
    the reversals placed linearly between samples. `missed`: the held drive's share
    (`filtering.held_missed`) already made, in place of `held`."""
    if rate > 0:
        x = kink_corrected(x, rate, s, held=held, drive=drive, inside=inside, missed=missed)
    if s.stencil == 5:
        return stencil_view(coulomb_integrals(x, s.ts, rate if inside else 0.0, drive)[1],
                            s.ts, 5)
    out = np.sign(x)
    out[~np.isfinite(x)] = np.nan
    if drive is not None and rate > 0 and inside:
        # the stick phases as eq. (22)'s chain sees them: sign(x) takes every reversal as
        # slip-through, and without feed-forward the motor sticks at most of them, which
        # biases Jm. The view loses two more
        # samples than sign(x) at each end: those take the nearest state (a sign there would
        # be a step the decimation spreads over the first rows), so the passes keep their rows
        state = stencil_view(coulomb_integrals(x, s.ts, rate, drive)[1], s.ts, 3)
        ok, at = np.isfinite(state), np.arange(len(state))
        if ok.any():
            out = np.where(np.isfinite(out), np.interp(at, at[ok], state[ok]), np.nan)
    return out


def _torque(log: Log, s: FilterSettings, filtered: bool = True, lp: Callable = lowpass
            ) -> np.ndarray:
    """The torque paired with the positions: ZOH-aligned (`zoh_align`; exact with the 5-point
    chain, applied after the Butterworth since both are linear and the exact view leaves NaN
    at the ends) and Butterworth filtered when `filtered` (`lp` as `_filtered`'s)."""
    tau = np.asarray(log.tau_m, dtype=float)
    if s.zoh and s.stencil == 5:
        return zoh_align(lp(tau, s.wn, s.ts, s.m) if filtered else tau, exact=True, ts=s.ts)
    tau = zoh_align(tau) if s.zoh else tau
    return lowpass(tau, s.wn, s.ts, s.m) if filtered else tau


def joint_motor(log: Log, s: FilterSettings,
                friction: tuple[float, float] | Mapping[str, float] = (0.0, 0.0)
                ) -> Regressor:
    """Eq. (13): y = (tau_m, 0), rows of eq. (10); gravity g cos q, g sin q from the log's g.
    `friction` places the Coulomb reversals of the sign columns (`_sign`): the rates
    (FSm / Jm, FS / JL), or the parameters of an earlier estimate (names of eq. 13), which
    add the held torque's kinks and the stick phases (`_friction_models`); zero keeps the
    filtered velocity's. One call of `JointMotorChain`; build that once to fit the same log
    and filter again with other friction (the reversal passes)."""
    return JointMotorChain(log, s).regressor(friction)


class JointMotorChain:
    """Eq. (13)'s chain on one log at one filter setting, built once: the filtered and
    differentiated positions, the torque, the columns that do not depend on the friction and
    their decimation (per row span), so that each `regressor` call builds and decimates the
    two Coulomb columns alone. The numbers are `decimate_parallel`'s: the decimation filters
    every column on its own (with its own odd extension at the span's ends, so that eq. (13)
    holds between the decimated columns up to the record's ends: an anti-alias pass per
    signal, differentiated after it, would start the filter differently in each column and
    break it there); the spring column, in both equations, is decimated once. `lp`: the
    Butterworth (`lowpass`, or a `filtering.Lowpassed` shared with other chains of the
    log). `shared`: a `ChainColumns` that keeps the undecimated columns per log and filter
    setting, for another chain of the log at another decimation (the wide band's). `paired`
    False: the columns without the 5-point chain's pairing with the acceleration (`_as_seen`,
    a gain within 0.4 % of one in the band): instruments need only correlate with the
    regressor's columns, and the pairing is the chain's costliest transform."""

    MOTOR_SIGN, LINK_SIGN = 2, 8   # the sign columns of the motor and link blocks
    # the columns that do not depend on the friction, by block: (column, name in `_columns`);
    # the equations' other columns are zero, whose decimation is zero (the filter is linear)
    FIXED = (((0, "qm''"), (1, "qm'"), (3, "spring")),
             ((3, "-spring"), (4, "q''"), (5, "g cos q"), (6, "g sin q"), (7, "q'")))

    def __init__(self, log: Log, s: FilterSettings, lp: Callable = lowpass,
                 shared: ChainColumns | None = None, paired: bool = True):
        if log.q is None:
            raise LogError("the joint-motor model needs the link position column 'q'",
                           log.path, column="q")
        self.log, self.s = log, s
        made = (shared or ChainColumns()).columns(log, s, lp, paired)
        self.qm, self.q, self.tau, self.defl = made.qm, made.q, made.tau, made.defl
        self._columns, self._valid, self._made = made.columns, made.valid, made
        self._decimated: dict[tuple[str, int, int], np.ndarray] = {}

    def regressor(self, friction: tuple[float, float] | Mapping[str, float] = (0.0, 0.0)
                  ) -> Regressor:
        """`joint_motor(log, s, friction)` from the chain's columns."""
        s = self.s
        motor, link = _friction_models(self.log, friction, self.defl)
        if len(motor) == 3:   # the held torque tau / Jm: its missed share made once, scaled
            if self._made.held_missed is None:
                self._made.held_missed = held_missed(self.log.tau_m, s)
            rate, _, drive = motor
            m = _sign(self.qm[1], s, rate, drive=drive,
                      missed=self._made.held_missed / friction["Jm"])
        else:
            m = _sign(self.qm[1], s, *motor)
        y1, W1, i1 = self._decimate(0, m)
        y2, W2, i2 = self._decimate(1, _sign(self.q[1], s, *link))
        return Regressor("joint-motor", JOINT_MOTOR, np.concatenate([y1, y2]),
                         np.vstack([W1, W2]),
                         np.r_[np.zeros(len(y1), int), np.ones(len(y2), int)], np.r_[i1, i2], s)

    def _span(self, names: list[str], first: int, last: int) -> list[np.ndarray]:
        """The named columns decimated over the samples [first, last), each once per span
        (those not yet decimated in one call); "-spring" is the spring's negative."""
        s = self.s
        base = [n.lstrip("-") for n in names]
        todo = [n for n in dict.fromkeys(base) if (n, first, last) not in self._decimated]
        if todo:
            cols = np.column_stack([self._columns[n][first:last] for n in todo])
            dec = decimate(cols, s.Nd, axis=0) if s.Nd > 1 else cols
            for j, n in enumerate(todo):
                self._decimated[(n, first, last)] = dec[:, j]
        return [-self._decimated[(b, first, last)] if n.startswith("-")
                else self._decimated[(b, first, last)] for n, b in zip(names, base)]

    def _decimate(self, block: int, sign: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`decimate_parallel(y, W, s)` of `block` (0: motor, y = tau_m; 1: link, y = 0)
        with its Coulomb column `sign`: the rows from the first to the last sample where every
        column is defined, decimated, `edge` rows dropped at each end and any row with NaN.
        The other columns are decimated once per row span (`_span`; the equation's zero
        columns, and y = 0 of the link equation, not at all: their decimation is zero)."""
        s = self.s
        n = len(sign)
        valid = self._valid[block] & np.isfinite(sign)
        first, last = max(int(np.argmax(valid)), s.skip), n - int(np.argmax(valid[::-1]))
        fixed = self.FIXED[block]
        names = [name for _, name in fixed] + (["tau"] if block == 0 else [])
        dec = self._span(names, first, last)
        Wd = np.zeros((len(dec[0]), len(JOINT_MOTOR)))
        for (j, _), col in zip(fixed, dec):
            Wd[:, j] = col
        yd = dec[-1] if block == 0 else np.zeros(len(Wd))
        varying = self.MOTOR_SIGN if block == 0 else self.LINK_SIGN
        Wd[:, varying] = decimate(sign[first:last], s.Nd) if s.Nd > 1 else sign[first:last]
        return kept_rows(yd, Wd, first, s)


class _Columns:
    """`JointMotorChain`'s undecimated columns of one log at one filter setting (the
    Butterworth, the stencil and the torque's alignment: `ChainColumns.setting`), read-only
    once made, and `filtering.held_missed` of the torque, made when first needed."""

    def __init__(self, log: Log, s: FilterSettings, lp: Callable, paired: bool = True):
        self.qm = qm = _filtered(log.q_m, s, 2, lp)
        self.q = q = _filtered(log.q, s, 2, lp)
        self.tau = _torque(log, s, lp=lp)
        self.defl = defl = qm[0] - q[0]
        g = log.gravity
        # the spring is one column in both equations: filtered once; all five together
        seen = _as_seen(s) if paired else (lambda xs, orders: list(xs))
        spring, vm, gc, gs, v = seen(
            [defl, qm[1], g * np.cos(q[0]), g * np.sin(q[0]), q[1]], (0, 1, 0, 0, 1))
        self.columns = {"qm''": qm[2], "qm'": vm, "spring": spring, "q''": q[2],
                        "g cos q": gc, "g sin q": gs, "q'": v, "tau": self.tau}
        fine = {k: np.isfinite(c) for k, c in self.columns.items()}
        # where the block's columns that do not depend on the friction (and y) are defined
        self.valid = (fine["qm''"] & fine["qm'"] & fine["spring"] & fine["tau"],
                      fine["spring"] & fine["q''"] & fine["g cos q"] & fine["g sin q"]
                      & fine["q'"])
        for x in [*qm, *q, defl, *self.columns.values(), *self.valid]:
            x.setflags(write=False)   # shared by the chains of this setting
        self.held_missed: np.ndarray | None = None


class ChainColumns:
    """`JointMotorChain`'s undecimated columns, made once per log and filter setting while
    this object lives: the chooser's band and the wide one differ in the decimation alone
    when they share the Butterworth and the stencil, so their chains (of the log and of the
    instruments' log) filter, differentiate and weigh the same columns (`_as_seen`) once."""

    def __init__(self) -> None:
        self._kept: dict[tuple, tuple[Log, _Columns]] = {}

    @staticmethod
    def setting(s: FilterSettings) -> tuple:
        """What the undecimated columns depend on: the Butterworth, the sample period, the
        stencil and the torque's zero-order-hold alignment (not Nd, edge nor skip)."""
        return (float(s.wn), float(s.ts), int(s.m), int(s.stencil), bool(s.zoh))

    def columns(self, log: Log, s: FilterSettings, lp: Callable, paired: bool = True
                ) -> _Columns:
        """The columns of `log` at `s`, made once (`paired` False: without the 5-point
        chain's pairing with the acceleration, `JointMotorChain`'s)."""
        paired = paired or s.stencil != 5   # the pairing is the 5-point chain's alone
        key = (id(log), paired) + self.setting(s)
        hit = self._kept.get(key)
        if hit is not None and hit[0] is log:   # the log is held: its id is not reused
            return hit[1]
        made = _Columns(log, s, lp, paired)
        self._kept[key] = (log, made)
        return made


def _as_seen(s: FilterSettings):
    """The 5-point chain's pairing of the columns that are not second derivatives with the
    acceleration (`as_acceleration_sees`), or as they are with eq. (22)'s chain (the paper's,
    kept as printed): a function of the columns and their derivative orders."""
    if s.stencil != 5:
        return lambda xs, orders: list(xs)
    return lambda xs, orders: list(as_acceleration_sees(np.stack(xs), s.ts, orders, s.stencil))


def _friction_models(log: Log, friction: tuple[float, float] | Mapping[str, float],
                     defl: np.ndarray) -> tuple[tuple, tuple]:
    """`_sign`'s arguments after the velocity for the motor and the link columns, the same
    for every log (the plant's friction switches inside the sample interval, as a real axis'
    does): from rates (FSm / Jm, FS / JL), the reversals placed inside the sample interval
    with the friction's kink; from parameters p, the motor column also gets the held torque
    tau / Jm and its drive between samples, (tau[k] - K defl) / Jm at the interval's start and
    end with the viscous rate FVm / Jm, for its stick phases (`friction_state`), since the
    closed loop holds the motor at its reversals. The link, driven by the spring alone, keeps
    its reversals slip-through. Zero where a friction or inertia is missing or not
    positive."""
    rates = friction if not isinstance(friction, Mapping) else tuple(
        friction[f] / friction[j] if friction.get(j, 0) > 0 and friction.get(f, 0) > 0
        else 0.0 for f, j in (("FSm", "Jm"), ("FS", "JL")))
    p = friction if isinstance(friction, Mapping) else {}
    K, Jm = p.get("K", 0.0), p.get("Jm", 0.0)
    if not (rates[0] > 0 and K > 0):
        return (rates[0],), (rates[1],)
    tau = np.asarray(log.tau_m, dtype=float)
    nxt = np.r_[defl[1:], defl[-1:]]
    drive = ((tau - K * defl) / Jm, (tau - K * nxt) / Jm, max(p.get("FVm", 0.0), 0.0) / Jm)
    return (rates[0], tau / Jm, drive), (rates[1],)


def motor_only(log: Log, s: FilterSettings, corrected: bool = True,
               lp: Callable = lowpass) -> Regressor:
    """Eqs. (18)-(20): y = tau_m, D = (-tau'', -tau', qm'''', qm''', qm'', qm', sign(qm'))
    [+ (s'', s', g cos qm, g sin qm) when corrected]. `lp` as `_filtered`'s."""
    qm = _filtered(log.q_m, s, 4, lp)
    tau = derivatives(_torque(log, s, lp=lp), s.ts, 2, s.stencil)
    sgn = _sign(qm[1], s)
    cols = [-tau[2], -tau[1], qm[4], qm[3], qm[2], qm[1], sgn]
    names = MOTOR_ONLY
    if corrected:
        ds = _filtered(np.nan_to_num(sgn), s, 2)
        g = log.gravity
        cols += [ds[2], ds[1], g * np.cos(qm[0]), g * np.sin(qm[0])]
        names = MOTOR_ONLY_CORRECTED
    y, W, idx = decimate_parallel(tau[0], np.column_stack(cols), s)
    return Regressor("motor-only" if corrected else "motor-only-printed", names, y, W,
                     np.zeros(len(y), int), idx, s)


def rigid(log: Log, s: FilterSettings) -> Regressor:
    """tau_m = J qm'' + FV qm' + FS sign(qm') + offset (docs/cli.md).

    The torque is zero-order-hold aligned when `s.zoh` and Butterworth filtered when
    `s.filter_torque` (both by default); the EMPS reference chain uses neither (it pairs the
    raw force with the filtered positions and lets the decimation filter both in parallel).
    """
    qm = _filtered(log.q_m, s, 2)
    tau = _torque(log, s, filtered=s.filter_torque)
    W = np.column_stack([qm[2], qm[1], _sign(qm[1], s), np.ones(len(log.t))])
    y, W, idx = decimate_parallel(tau, W, s)
    return Regressor("rigid", RIGID, y, W, np.zeros(len(y), int), idx, s)
