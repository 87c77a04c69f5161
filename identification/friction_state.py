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

The law is stepped SUBSTEPS times an interval (`_slip_stick`, the definition). An interval
that moves one way is a linear recurrence with a drive linear in the sub-step, whose end
has a closed form (`_powers`), so only the intervals that may leave their sign (reversals,
stick phases: a few % of a log with feed-forward) are followed, phase by phase between
their events (`_phases`), and only those, with the ones after them, go through the passes
(`_one_way_every_pass`); the numbers are the sub-steps' to rounding (tests/unit/
test_friction_state.py).

Numpy; the phases, interval by interval, compiled by numba when it is installed (the optional
extra "fast"; the same numbers as the array passes).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from jointbench.identification.compiled import compiled as compiled_kernel

SUBSTEPS = 32       # sub-steps a sample interval: a reversal placed to 1/32 of a sample
MATCH_PASSES = 2    # passes shifting the drive onto the next sample's velocity


@lru_cache(maxsize=64)
def _powers(visc: float, ts: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(P, G0, G1) over m = 0 ... SUBSTEPS for the free sub-step u' = a u + h e_j (h = ts /
    SUBSTEPS, a = 1 - h visc, e_j the drive less the friction at sub-step j): P[m] = a^m,
    G0[m] = sum_{l<m} a^(m-1-l), G1[m] = sum_{l<m} a^(m-1-l) l, so that m free sub-steps from
    sub-step j0 with e_j = alpha + beta j end at a^m u + h ((alpha + beta j0) G0[m] + beta G1[m])
    (a linear recurrence with a drive linear in the sub-step: geometric sums). Made once per
    (visc, ts)."""
    a = 1.0 - ts / SUBSTEPS * visc
    P, G0, G1 = np.ones(SUBSTEPS + 1), np.zeros(SUBSTEPS + 1), np.zeros(SUBSTEPS + 1)
    for m in range(SUBSTEPS):
        P[m + 1], G0[m + 1], G1[m + 1] = P[m] * a, G0[m] * a + 1.0, G1[m] * a + m
    for x in (P, G0, G1):
        x.setflags(write=False)   # cached: shared by every call with these rates
    return P, G0, G1


@lru_cache(maxsize=64)
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
    """Intervals that `_slip_stick` finds moving one way throughout, known without stepping
    them: with w = sign(u) v, each free sub-step gives w' = a w + h (sign(u) d - rate) >= a w -
    h E, where E = max(0, rate - min(sign(u) d0, sign(u) d1)) is how far the friction can
    exceed the drive along the motion (the drive lies between its values at the interval's
    ends), so at every sub-step w >= |u| (1 - ts visc) - ts E (Bernoulli: a^j >= 1 - j h visc
    for h visc <= 1). Where that bound stays above 1 % of ts (D + rate) (D the larger |drive|
    at the ends) the velocity keeps its sign, rounding included (a few ulps over 32
    sub-steps)."""
    k = min(1.0, 1.0 - ts * visc)
    sg = np.sign(u)
    excess = np.maximum(rate - np.minimum(sg * d0, sg * d1), 0.0)
    reach = ts * (np.maximum(np.abs(d0), np.abs(d1)) + rate)
    return (u != 0) & (k > 0) & (np.abs(u) * k - ts * excess > 0.01 * reach)


def _interval(u: np.ndarray, d0: np.ndarray, d1: np.ndarray, visc: float, rate: float,
              ts: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`_slip_stick`'s first and second integrals of the friction state over every interval
    (from its start) and its end velocity, from velocities u, each interval on its own. An
    interval `_surely_one_way` has the state sign(u) at every sub-step: its integrals are
    those of a constant sign (the same numbers as the sub-steps'), its end velocity the free
    recurrence's closed form (`_powers`); the others go through `_phases`."""
    h = ts / SUBSTEPS
    P, G0, G1 = _powers(visc, ts)
    if not P[1] > 0:   # h visc >= 1: no closed form worth its name, every sub-step stepped
        return _slip_stick(u, d0, d1, visc, rate, ts)
    sg = np.sign(u)
    p1, p2 = _unit_integrals(ts)
    slope = (d1 - d0) / SUBSTEPS
    alpha = d0 + (d1 - d0) * 0.5 / SUBSTEPS - rate * sg
    I1, I2 = sg * p1, sg * p2
    end = P[-1] * u + h * (alpha * G0[-1] + slope * G1[-1])
    doubt = np.flatnonzero(~_surely_one_way(u, d0, d1, visc, rate, ts))
    if len(doubt):
        I1[doubt], I2[doubt], end[doubt] = _phases(u[doubt], d0[doubt], d1[doubt], visc, rate,
                                                   ts)
    return I1, I2, end


def _event(u: np.ndarray, free: np.ndarray, d: np.ndarray, rate: float, h: float
           ) -> tuple[np.ndarray, np.ndarray]:
    """`_slip_stick`'s sub-step for an axis at rest or reaching rest within it (u moving to
    `free` of the other sign, or u = 0) under the drive d: its state s and the velocity
    after it."""
    sg = np.sign(u)
    cross = sg != 0
    share = np.zeros(len(u))
    share[cross] = np.clip(u[cross] / (u[cross] - free[cross]), 0.0, 1.0)
    stuck = np.abs(d) <= rate
    after = np.where(stuck, d / rate, np.sign(d))
    s = sg * share + after * (1.0 - share)
    new = h * (1.0 - share) * (d - rate * np.sign(d))
    return s, np.where(~stuck & (np.sign(new) == np.sign(d)), new, 0.0)


def _phases(u: np.ndarray, d0: np.ndarray, d1: np.ndarray, visc: float, rate: float,
            ts: float, compiled: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`_slip_stick` phase by phase instead of sub-step by sub-step, for every interval at
    once: a moving phase follows the free recurrence in closed form (`_powers`) to the first
    sub-step whose free step changes the velocity's sign (a reversal: `_event`); a phase at
    rest holds s = drive / rate up to the first sub-step where |drive| > rate (a breakaway:
    `_event`; none where the drive is inside the band at the phase's first and last
    sub-steps, the drive being linear). Each phase ends in an event or at the interval's end,
    so the loop runs once per event of the busiest interval. The decisions are
    `_slip_stick`'s on the same drive; the velocities agree with its sub-steps to rounding,
    and so do the integrals, I1 = h sum_j s_j and I2 = h^2 sum_j s_j (SUBSTEPS - j - 1/2)
    (an interval that never leaves its sign: a constant sign's, as `_slip_stick` sums
    them). `compiled`: interval by interval (`_steps`, the same operations in the same order,
    so the same numbers) compiled by numba when it is installed (the optional extra "fast"),
    else these array passes."""
    n, N, h = len(u), SUBSTEPS, ts / SUBSTEPS
    free, weight, ahead, mid, mid_w = _tables(visc, ts)
    steps = compiled_kernel(_steps) if compiled else None
    if steps is not None:
        I1, I2, end = np.zeros(n), np.zeros(n), np.zeros(n)
        one_way = np.zeros(n, dtype=np.bool_)
        steps(np.asarray(u, dtype=float), d0, d1, rate, h, free, weight, ahead, mid, mid_w,
              I1, I2, end, one_way)
        p1, p2 = _unit_integrals(ts)
        sg = np.sign(u[one_way])
        I1[one_way], I2[one_way] = sg * p1, sg * p2
        return I1, I2, end
    j = np.arange(N)
    diff = d1 - d0
    slope = diff / N
    start = d0 + diff * 0.5 / N                         # the drive at sub-step 0
    I1, I2, end = np.zeros(n), np.zeros(n), np.zeros(n)
    at, v = np.zeros(n, dtype=int), u.astype(float)     # each interval's phase: start, velocity
    active, one_way = np.ones(n, dtype=bool), np.zeros(n, dtype=bool)
    while True:
        rows = np.flatnonzero(active & (v != 0))        # moving phases
        if len(rows):
            sg, a0 = np.sign(v[rows]), at[rows]
            # the velocity at the start of sub-step a0 + m, m = 0 ... SUBSTEPS
            c = start[rows] - rate * sg + slope[rows] * a0
            U = v[rows, None] * free[0] + c[:, None] * free[1] + slope[rows, None] * free[2]
            flip = U[:, 1:] * sg[:, None] <= 0          # the free step leaves the sign
            later = a0.any()
            if later:
                flip &= j < (N - a0)[:, None]           # sub-steps inside the interval
            r = np.argmax(flip, axis=1)
            hit = flip[np.arange(len(rows)), r]
            stop = np.where(hit, a0 + r, N)
            I1[rows] += sg * (h * (stop - a0))
            I2[rows] += sg * (ahead[stop] - ahead[a0])
            through = ~hit
            end[rows[through]] = U[through, N - a0[through]]
            one_way[rows[through]] = a0[through] == 0
            active[rows[through]] = False
            rh, k = np.flatnonzero(hit), r[hit]
            _step(rows[hit], stop[hit], U[rh, k], U[rh, k + 1], d0, d1, rate, h, weight,
                  I1, I2, at, v, end, active)
        rows = np.flatnonzero(active & (v == 0))        # phases at rest
        if len(rows):
            a0 = at[rows]
            first = d0[rows] + diff[rows] * (a0 + 0.5) / N
            last = d0[rows] + diff[rows] * (N - 0.5) / N
            held = (np.abs(first) <= rate) & (np.abs(last) <= rate)
            done, a = rows[held], a0[held]
            # s = drive / rate to the end: sums of the linear drive over sub-steps a ... N - 1
            I1[done] += h / rate * (d0[done] * (N - a) + slope[done] * mid[a])
            I2[done] += (d0[done] * (ahead[N] - ahead[a]) + slope[done] * mid_w[a]) / rate
            active[done] = False
            rows, a0 = rows[~held], a0[~held]
        if len(rows):
            drive = d0[rows, None] + diff[rows, None] * (j + 0.5) / N
            after = j >= a0[:, None]
            away = after & (np.abs(drive) > rate)
            hit = away.any(axis=1)
            stop = np.where(hit, np.argmax(away, axis=1), N)
            state = np.where(after & (j < stop[:, None]), drive / rate, 0.0)
            I1[rows] += h * np.cumsum(state, axis=1)[:, -1]     # summed in order (`_steps`)
            I2[rows] += np.cumsum(state * weight, axis=1)[:, -1]
            active[rows[~hit]] = False                  # at rest to the end
            rows, stop = rows[hit], stop[hit]
            zero = np.zeros(len(rows))
            _step(rows, stop, zero, zero, d0, d1, rate, h, weight, I1, I2, at, v, end, active)
        if not active.any():
            break
    p1, p2 = _unit_integrals(ts)
    sg = np.sign(u[one_way])
    I1[one_way], I2[one_way] = sg * p1, sg * p2
    return I1, I2, end


def _steps(u: np.ndarray, d0: np.ndarray, d1: np.ndarray, rate: float, h: float,
           free: np.ndarray, weight: np.ndarray, ahead: np.ndarray, mid: np.ndarray,
           mid_w: np.ndarray, I1: np.ndarray, I2: np.ndarray, end: np.ndarray,
           one_way: np.ndarray) -> None:
    """`_phases` interval by interval as plain scalar code (numba compiles it,
    `compiled_kernel`): each interval's phases in the order `_phases` takes them (a moving
    phase, then a phase at rest, each ending in an event (`_step`) or at the interval's end),
    each value with `_phases`' operations in the same order, so the same numbers; a moving
    phase stops at the first sub-step whose free step leaves the sign. Writes I1, I2, end and
    one_way (the intervals that moved one way from their start to their end) in place."""
    N = len(weight)
    for i in range(len(u)):
        diff = d1[i] - d0[i]
        slope = diff / N
        start = d0[i] + diff * 0.5 / N
        at, v, active = 0, u[i], True
        while active:
            for phase in range(2):
                event, eu, ef = -1, 0.0, 0.0
                if phase == 0 and v != 0:            # moving
                    sg, a0 = (1.0 if v > 0 else -1.0), at
                    c = start - rate * sg + slope * a0
                    now = v * free[0, 0] + c * free[1, 0] + slope * free[2, 0]
                    nxt = now
                    stop = N
                    for m in range(N - a0):
                        nxt = v * free[0, m + 1] + c * free[1, m + 1] + slope * free[2, m + 1]
                        if nxt * sg <= 0:
                            stop = a0 + m
                            break
                        now = nxt
                    I1[i] += sg * (h * (stop - a0))
                    I2[i] += sg * (ahead[stop] - ahead[a0])
                    if stop == N:
                        end[i] = nxt
                        one_way[i] = a0 == 0
                        active = False
                    else:
                        event, eu, ef = stop, now, nxt
                elif phase == 1 and active and v == 0:   # at rest
                    a0 = at
                    first = d0[i] + diff * (a0 + 0.5) / N
                    last = d0[i] + diff * (N - 0.5) / N
                    if abs(first) <= rate and abs(last) <= rate:
                        I1[i] += h / rate * (d0[i] * (N - a0) + slope * mid[a0])
                        I2[i] += (d0[i] * (ahead[N] - ahead[a0]) + slope * mid_w[a0]) / rate
                        active = False
                    else:
                        stop = N
                        for j in range(a0, N):
                            if abs(d0[i] + diff * (j + 0.5) / N) > rate:
                                stop = j
                                break
                        s1 = s2 = 0.0
                        for j in range(N):
                            state = ((d0[i] + diff * (j + 0.5) / N) / rate if a0 <= j < stop
                                     else 0.0)
                            if j == 0:
                                s1, s2 = state, state * weight[j]
                            else:
                                s1, s2 = s1 + state, s2 + state * weight[j]
                        I1[i] += h * s1
                        I2[i] += s2
                        if stop == N:
                            active = False
                        else:
                            event = stop
                if event >= 0:                           # `_step`, `_event`
                    d = d0[i] + (d1[i] - d0[i]) * (event + 0.5) / N
                    sd = 1.0 if d > 0 else (-1.0 if d < 0 else 0.0)
                    su = 1.0 if eu > 0 else (-1.0 if eu < 0 else 0.0)
                    share = min(max(eu / (eu - ef), 0.0), 1.0) if su != 0 else 0.0
                    stuck = abs(d) <= rate
                    after = d / rate if stuck else sd
                    state = su * share + after * (1.0 - share)
                    new = h * (1.0 - share) * (d - rate * sd)
                    sn = 1.0 if new > 0 else (-1.0 if new < 0 else 0.0)
                    if stuck or sn != sd:
                        new = 0.0
                    I1[i] += state * h
                    I2[i] += state * weight[event]
                    at, v = event + 1, new
                    if at == N:
                        end[i] = v
                        active = False


def _one_way_steps(u0: np.ndarray, u1: np.ndarray, d0: np.ndarray, d1: np.ndarray,
                   rate: float, ts: float, k: float, h: float, PN: float, G0N: float,
                   G1N: float, N: int, out: np.ndarray) -> None:
    """`_one_way_every_pass` sample by sample as plain scalar code (numba compiles it,
    `compiled_kernel`), each value with its operations in the same order: the same
    decisions. Writes them into `out`."""
    for i in range(len(u0)):
        u, a, b = u0[i], d0[i], d1[i]
        sg = 1.0 if u > 0 else (-1.0 if u < 0 else 0.0)
        slope = (b - a) / N
        alpha = a + (b - a) * 0.5 / N - rate * sg
        end = PN * u + h * (alpha * G0N + slope * G1N)
        moved = 2.02 * abs(u1[i] - end)
        excess = max(rate - min(sg * a, sg * b), 0.0)
        reach = ts * (max(abs(a), abs(b)) + rate)
        out[i] = u != 0 and abs(u) * k - ts * excess - moved > 0.01 * (reach + moved)


@lru_cache(maxsize=64)
def _tables(visc: float, ts: float) -> tuple[np.ndarray, ...]:
    """`_phases`' tables for m = 0 ... SUBSTEPS: the rows P, h G0, h G1 (`_powers`), which
    give m free sub-steps of velocity u with the drive less the friction c + slope j from
    sub-step j0 as (u, c + slope j0, slope) times them; the weights
    h^2 (SUBSTEPS - j - 1/2) of the states s_j in I2 and their sums over sub-steps before j
    (`ahead`); the sums from sub-step a to the end of (j + 1/2) (`mid`) and of (j + 1/2) times
    the weight (`mid_w`), which sum a drive linear in j. Made once per (visc, ts)."""
    N, h = SUBSTEPS, ts / SUBSTEPS
    P, G0, G1 = _powers(visc, ts)
    j = np.arange(N)
    weight = h * h * (N - j - 0.5)
    ahead = np.concatenate([[0.0], np.cumsum(weight)])
    mid = np.concatenate([np.cumsum((j + 0.5)[::-1])[::-1], [0.0]])
    mid_w = np.concatenate([np.cumsum(((j + 0.5) * weight)[::-1])[::-1], [0.0]])
    out = (np.stack([P, h * G0, h * G1]), weight, ahead, mid, mid_w)
    for x in out:
        x.setflags(write=False)
    return out


def _step(rows: np.ndarray, at: np.ndarray, u: np.ndarray, free: np.ndarray,
          d0: np.ndarray, d1: np.ndarray, rate: float, h: float, weight: np.ndarray,
          I1: np.ndarray, I2: np.ndarray, j0: np.ndarray, v: np.ndarray, end: np.ndarray,
          active: np.ndarray) -> None:
    """`_phases`' event at sub-step `at` of intervals `rows` (`_event`, the drive
    `_slip_stick`'s), added to their integrals and written into the next phase's start j0
    and velocity v (the end velocity, and no longer active, after the interval's last
    sub-step)."""
    if not len(rows):
        return
    d = d0[rows] + (d1[rows] - d0[rows]) * (at + 0.5) / SUBSTEPS
    s, new = _event(u, free, d, rate, h)
    I1[rows] += s * h
    I2[rows] += s * weight[at]
    j0[rows], v[rows] = at + 1, new
    last = rows[at + 1 == SUBSTEPS]
    end[last] = v[last]
    active[last] = False


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


def _one_way_every_pass(u0: np.ndarray, u1: np.ndarray, d0: np.ndarray, d1: np.ndarray,
                        visc: float, rate: float, ts: float, compiled: bool = True
                        ) -> np.ndarray:
    """Intervals `_surely_one_way` in every pass of `friction_integrals`, whatever the shifts:
    while an interval moves one way its end is the free recurrence's closed form (`_powers`),
    end_0 in the first pass, and its shifts are shift_1 = delta = (u1 - end_0) / ts and
    shift_2 = delta (2 - G0 / SUBSTEPS) (or unchanged where the end does not move as
    measured), so |shift| <= 2 |delta|; `_surely_one_way`'s bound with the drive moved by
    that much (1 % more, for the rounding of the shifts) holds in every pass. `compiled`:
    sample by sample (`_one_way_steps`, the same operations) compiled by numba when it is
    installed, else these array operations."""
    k = min(1.0, 1.0 - ts * visc)
    if not k > 0:
        return np.zeros(len(u0), dtype=bool)
    P, G0, G1 = _powers(visc, ts)
    h = ts / SUBSTEPS
    steps = compiled_kernel(_one_way_steps) if compiled else None
    if steps is not None:
        out = np.zeros(len(u0), dtype=np.bool_)
        steps(u0, u1, d0, d1, rate, ts, k, h, P[-1], G0[-1], G1[-1], SUBSTEPS, out)
        return out
    sg = np.sign(u0)
    slope = (d1 - d0) / SUBSTEPS
    alpha = d0 + (d1 - d0) * 0.5 / SUBSTEPS - rate * sg
    end = P[-1] * u0 + h * (alpha * G0[-1] + slope * G1[-1])   # `_interval`'s
    moved = 2.02 * np.abs(u1 - end)                            # ts |shift| at most
    excess = np.maximum(rate - np.minimum(sg * d0, sg * d1), 0.0)
    reach = ts * (np.maximum(np.abs(d0), np.abs(d1)) + rate)
    return (u0 != 0) & (np.abs(u0) * k - ts * excess - moved > 0.01 * (reach + moved))


def _matched(u0: np.ndarray, u1: np.ndarray, d0: np.ndarray, d1: np.ndarray, after: np.ndarray,
             visc: float, rate: float, ts: float) -> tuple[np.ndarray, np.ndarray]:
    """`friction_integrals`' passes over intervals (`_interval`): `after` marks those whose
    preceding interval is among them (the others follow one that moves one way)."""
    shift = np.zeros(len(u0))
    I1, I2, end = _interval(u0, d0, d1, visc, rate, ts)
    # an axis that ended the last interval at rest with the drive still inside the band stays
    # at rest (Karnopp): the velocity measured there is creep or the reconstruction's error,
    # and starting from it would slip for part of the interval, which biases Jm (each
    # interval is integrated on its own: only those whose start changes again)
    rest = np.r_[False, end[:-1] == 0] & after
    held = np.flatnonzero(rest & (np.abs(d0) <= rate) & (u0 != 0))
    u0 = u0.copy()
    u0[held] = 0.0
    if len(held):
        I1[held], I2[held], end[held] = _interval(u0[held], d0[held], d1[held], visc, rate, ts)
    for _ in range(MATCH_PASSES):
        # only where the axis ends the interval moving as measured: an interval that ends at
        # rest says nothing of the drive (any drive inside the band holds it), and shifting it
        # onto a creeping or noisy velocity would invent a breakaway; the intervals whose
        # shift stays are not integrated again
        moving = (np.sign(end) == np.sign(u1)) & (end != 0)
        new = shift + np.where(moving, (u1 - end) / ts, 0.0)
        again = np.flatnonzero(new != shift)
        shift = new
        I1[again], I2[again], end[again] = _interval(u0[again], d0[again] + shift[again],
                                                     d1[again] + shift[again], visc, rate, ts)
    return I1, I2


def _finite(x: np.ndarray) -> np.ndarray:
    """np.nan_to_num(x), or x itself when every value is finite (not written into)."""
    x = np.asarray(x, dtype=float)
    return x if np.isfinite(x).all() else np.nan_to_num(x)


def friction_integrals(v: np.ndarray, drive0: np.ndarray, drive1: np.ndarray, visc: float,
                       rate: float, ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Samples of the first and second integrals of the friction state s(t) in [-1, 1]
    (module docstring), for velocity samples v [rad/s], the drive [rad/s^2] at the start
    (drive0[k]) and end (drive1[k]) of interval k, the viscous rate visc = FV / J [1/s] and
    rate = FS / J [rad/s^2] > 0. The second is NaN where v is. Only the intervals that may
    leave their sign in some pass, and those after them (which may start held), go through
    the passes (`_matched`); the others have a constant sign's integrals in every pass."""
    v = np.asarray(v, dtype=float)
    finite = np.nan_to_num(v)
    u0, u1 = finite[:-1], finite[1:]
    d0, d1 = _finite(drive0)[:-1], _finite(drive1)[:-1]
    p1, p2 = _unit_integrals(ts)
    sg = np.sign(u0)
    I1, I2 = sg * p1, sg * p2
    doubt = ~_one_way_every_pass(u0, u1, d0, d1, visc, rate, ts)
    doubt[1:] |= doubt[:-1]
    rows = np.flatnonzero(doubt)
    if len(rows):
        after = np.r_[False, rows[1:] == rows[:-1] + 1]
        I1[rows], I2[rows] = _matched(u0[rows], u1[rows], d0[rows], d1[rows], after, visc,
                                      rate, ts)
    S1 = np.concatenate([[0.0], np.cumsum(I1)])
    S2 = np.concatenate([[0.0], np.cumsum(S1[:-1] * ts + I2)])
    S2[~np.isfinite(v)] = np.nan
    return S1, S2
