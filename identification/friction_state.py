"""The Coulomb friction's state between samples, stick phases included.

A Coulomb column sign(v) assumes the friction is +-FS at every instant. At a reversal whose
drive cannot overcome FS the axis sticks instead: the friction then balances the drive,
anywhere in [-FS, FS], for as long as the drive stays inside that band. Without velocity
feed-forward, or near the antiresonance (the motor a node of the mode, the spring force
sweeping through the friction band within a sample), such stick phases recur at every
reversal, and a sign column, every reversal taken as slip-through, biases Jm (the whole
chain: tests/validation/test_indep_accuracy.py::test_joint_motor_without_noise).

`friction_integrals` integrates, within every sample interval independently, the one-mass
equation J v' = J (drive(t) - visc v) - FS s(t) with s the friction state (Karnopp: s =
sign(v) while moving; at rest, s = drive / rate while |drive| <= rate = FS / J, else the
axis breaks away), the drive linear in the interval (a held torque and a spring force
between their sample values), from the sample's velocity; the drive is then shifted by a
constant within each interval so that the integration ends on the next sample's velocity
where both move the same way (the drive is known only as well as the previous pass's
parameters; the velocities are measured). It returns the first and second integrals of s at the samples, which a stencil
turns into the regressor's column (`filtering.stencil_view`), as `filtering.sign_integrals`
does for sign(v).

Pure numpy.
"""

from __future__ import annotations

import numpy as np

SUBSTEPS = 32       # sub-steps a sample interval: a reversal placed to 1/32 of a sample
MATCH_PASSES = 2    # passes shifting the drive onto the next sample's velocity


def _interval(u: np.ndarray, d0: np.ndarray, d1: np.ndarray, visc: float, rate: float,
              ts: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One pass over every interval at once from velocities u: the first and second
    integrals of the friction state over the interval (from its start) and the end velocity.
    An interval that moves one way throughout has the state sign(u) at every sub-step: its
    velocity is stepped alone, the integrals are those of a constant sign (the same
    operations as `_slip_stick`'s, so the same numbers), and `_slip_stick` runs on the rest."""
    h = ts / SUBSTEPS
    sg = np.sign(u)
    free = u.copy()
    one_way = sg != 0
    slope, friction = d1 - d0, rate * sg
    d, acc, same = np.empty_like(u), np.empty_like(u), np.empty(len(u), dtype=bool)
    for j in range(SUBSTEPS):   # in place, the operations of `_slip_stick`'s free step
        np.multiply(slope, j + 0.5, out=d)
        np.divide(d, SUBSTEPS, out=d)
        np.add(d0, d, out=d)
        np.multiply(free, visc, out=acc)
        np.subtract(d, acc, out=acc)
        np.subtract(acc, friction, out=acc)
        np.multiply(acc, h, out=acc)
        np.add(free, acc, out=free)
        np.equal(np.sign(free, out=acc), sg, out=same)
        one_way &= same
    p1, p2 = _unit_integrals(ts)
    I1, I2, end = sg * p1, sg * p2, free
    rest = np.flatnonzero(~one_way)
    if len(rest):
        J1, J2, e = _slip_stick(u[rest], d0[rest], d1[rest], visc, rate, ts)
        I1[rest], I2[rest], end[rest] = J1, J2, e
    return I1, I2, end


def _unit_integrals(ts: float) -> tuple[float, float]:
    """The first and second integrals of a state of +1 over an interval, summed over its
    sub-steps as `_slip_stick` sums them (of -1: their negatives)."""
    h = ts / SUBSTEPS
    p1 = p2 = 0.0
    for _ in range(SUBSTEPS):
        p2 += p1 * h + 1.0 * h * h / 2
        p1 += 1.0 * h
    return p1, p2


def _surely_one_way(u: np.ndarray, d0: np.ndarray, d1: np.ndarray, visc: float, rate: float,
                    ts: float) -> np.ndarray:
    """Intervals that `_interval` finds moving one way throughout, known without stepping
    them: with w = sign(u) v, each free sub-step gives w' >= w (1 - h visc) - h (D + rate)
    (D the larger |drive| at the interval's ends, which bound it inside), so at every
    sub-step w >= |u| (1 - ts visc) - ts (D + rate) (Bernoulli: (1 - h visc)^j >= 1 - j h
    visc for h visc <= 1). Where that bound stays above 1 % of ts (D + rate) the velocity
    keeps its sign, rounding included (a few ulps over 32 sub-steps)."""
    k = min(1.0, 1.0 - ts * visc)
    reach = ts * (np.maximum(np.abs(d0), np.abs(d1)) + rate)
    return (u != 0) & (k > 0) & (np.abs(u) * k > 1.01 * reach)


def _integrals(u: np.ndarray, d0: np.ndarray, d1: np.ndarray, visc: float, rate: float,
               ts: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`_interval`'s integrals, stepping only the intervals `_surely_one_way` leaves in
    doubt (each interval is computed on its own: the same numbers); their end velocity is
    NaN where not stepped (a one-way interval never ends at rest)."""
    sure = _surely_one_way(u, d0, d1, visc, rate, ts)
    doubt = np.flatnonzero(~sure)
    if len(doubt) == len(u):
        return _interval(u, d0, d1, visc, rate, ts)
    p1, p2 = _unit_integrals(ts)
    sg = np.sign(u[sure])
    J1, J2, J3 = np.empty(len(u)), np.empty(len(u)), np.full(len(u), np.nan)
    J1[sure], J2[sure] = sg * p1, sg * p2
    if len(doubt):
        J1[doubt], J2[doubt], J3[doubt] = _interval(u[doubt], d0[doubt], d1[doubt], visc,
                                                    rate, ts)
    return J1, J2, J3


def _slip_stick(u: np.ndarray, d0: np.ndarray, d1: np.ndarray, visc: float, rate: float,
                ts: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`_interval` with the stick-slip law at every sub-step (reversals, rest, breakaway)."""
    h = ts / SUBSTEPS
    I1, I2 = np.zeros(len(u)), np.zeros(len(u))
    for j in range(SUBSTEPS):
        d = d0 + (d1 - d0) * (j + 0.5) / SUBSTEPS
        sg = np.sign(u)
        free = u + h * (d - visc * u - rate * sg)
        moving = sg != 0
        cross = moving & (np.sign(free) != sg)          # reaches rest within the sub-step
        at_rest = ~moving | cross
        stuck = at_rest & (np.abs(d) <= rate)            # the friction holds the drive
        away = at_rest & ~stuck                          # breaks away in the drive's direction
        with np.errstate(invalid="ignore", divide="ignore"):
            share = np.where(cross, np.clip(u / (u - free), 0.0, 1.0), 0.0)
        after = np.where(stuck, d / rate, np.sign(d))    # the state once at rest
        s = np.where(at_rest, sg * share + after * (1.0 - share), sg)
        new = h * (1.0 - share) * (d - rate * np.sign(d))
        new = np.where(away & (np.sign(new) == np.sign(d)), new, 0.0)
        u = np.where(at_rest, new, free)
        I2 += I1 * h + s * h * h / 2
        I1 += s * h
    return I1, I2, u


def friction_integrals(v: np.ndarray, drive0: np.ndarray, drive1: np.ndarray, visc: float,
                       rate: float, ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Samples of the first and second integrals of the friction state s(t) in [-1, 1]
    (module docstring), for velocity samples v [rad/s], the drive [rad/s^2] at the start
    (drive0[k]) and end (drive1[k]) of interval k, the viscous rate visc = FV / J [1/s] and
    rate = FS / J [rad/s^2] > 0. The second is NaN where v is."""
    v = np.asarray(v, dtype=float)
    u0, u1 = np.nan_to_num(v[:-1]), np.nan_to_num(v[1:])
    d0 = np.nan_to_num(np.asarray(drive0, dtype=float)[:-1])
    d1 = np.nan_to_num(np.asarray(drive1, dtype=float)[:-1])
    shift = np.zeros(len(u0))
    # the integrals of this first pass are not used: only where it ends at rest
    _, _, end = _integrals(u0, d0, d1, visc, rate, ts)
    # an axis that ended the last interval at rest with the drive still inside the band stays
    # at rest (Karnopp): the velocity measured there is creep or the reconstruction's error,
    # and starting from it would slip for part of the interval, which biases Jm
    held = np.r_[False, end[:-1] == 0] & (np.abs(d0) <= rate)
    u0 = np.where(held, 0.0, u0)
    I1, I2, end = _interval(u0, d0, d1, visc, rate, ts)
    for i in range(MATCH_PASSES):
        # only where the axis ends the interval moving as measured: an interval that ends at
        # rest says nothing of the drive (any drive inside the band holds it), and shifting it
        # onto a creeping or noisy velocity would invent a breakaway
        moving = (np.sign(end) == np.sign(u1)) & (end != 0)
        shift = shift + np.where(moving, (u1 - end) / ts, 0.0)
        # the last pass's end velocity is not used
        step = _integrals if i == MATCH_PASSES - 1 else _interval
        I1, I2, end = step(u0, d0 + shift, d1 + shift, visc, rate, ts)
    S1 = np.concatenate([[0.0], np.cumsum(I1)])
    S2 = np.concatenate([[0.0], np.cumsum(S1[:-1] * ts + I2)])
    S2[~np.isfinite(v)] = np.nan
    return S1, S2
