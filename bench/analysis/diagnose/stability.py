"""The loop's own stability: does a named torque lag make the logged closed loop unstable, where
the nominal's is stable, at the frequency where the log's torque sits at its limit?

**Why not the replay alone.** A lag that drives the loop into its limit leaves the loop
linearly unstable, and the clip bounds the growing oscillation to a limit cycle. Whether a
closed-loop replay starting from rest reaches that cycle, and when, depends on how fast the
small oscillation grows against the Coulomb frictions while the motor sticks, which near the
stability limit is a fraction of a percent a sample: the replay's friction law and its
discretisation of the lag's filter decide it, not the lag. A replay with the identified lag
can stay stable beside a log that has clipped a quarter of its samples since its second
second; its clipping then says nothing either way (verdict.every_row_reason). What the lag
does say, whatever the friction, is the linear loop's growth and its frequency.

**The loop.** The linear part of eqs. (5)-(6) (Jm, FVm, K, JL, FV, and a named spring
damping's D in parallel with K; the rigid J, FV), the
torque through the lag 1 / (1 + T s) (T = 0: none), held over the sample (zero-order hold,
exact discretisation), and the PI cascade of docs/controller.md with q_ref = 0:
e[k] = -kp q_m[k] - (q_m[k] - q_m[k-1]) / ts, I[k] = I[k-1] + ki ts e[k],
tau_m[k] = kv e[k] + I[k] (velocity feed-forward acts on the reference only). The spectral
radius of its transition matrix is the growth per sample of its slowest-decaying mode.

**The cycle's frequency.** The clip is a saturation, whose describing function is real and
at most 1: harmonic balance puts the limit cycle where the loop's phase is -180 degrees and
its gain over 1 (the phase crossover, `crossover_hz`), and the growing linear mode's
frequency is where a small oscillation grows. The log's oscillation at the limit lies
between the two; the log's dominant torque frequency after it first reaches tau_max
(`cycle_hz`) is asked to lie there, widened by that spectrum's resolution.

**The fitted values' spread.** T and D are estimates, and near the stability onset the mode
and the crossover move fast with them (a lag a tenth off moves the pendulum's mode by over a
hertz). So the band the log's frequency is asked to lie in is the one the fitted values allow:
the span of the mode's and the crossover's frequencies over the corners of the box T +- dT,
D +- dD (`spread`), each half-width the fit's own standard error at the agreement level of two
estimates (verdict.loop_cycle), the point estimate's two frequencies included where its loop
grows. The loop's growth is judged over the same box: near the onset the growth turns on a
few percent of T and of the inertias it is fitted with (the pendulum's onset moves by a fifth
of T for 4 % of Jm), so a point estimate a standard error short of the onset does not say the
lag leaves the loop stable. The log's cycle is a growing loop's, so the band is taken over the part of the box
where the loop grows, edged by the corners and, on the line from the point estimate to a
corner where the loop's growth changes sign, by the onset (bisection on the spectral radius).

Only a torque lag changes the loop's linear phase among docs/effects.md's effects (the
others act through the deflection's nonlinearity, low speed or the link), so only a named lag
is judged here. Pure numerics over numpy arrays.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm
from scipy.signal import welch

from jointbench.identification.discrepancy.heldout import SEGMENTS
from jointbench.identification.log import Log
from jointbench.identification.saturation import at_limit


@dataclass(frozen=True)
class LimitCycle:
    """What the loop's linearisation says of a clipped log: the spectral radius of the
    nominal's loop and of the extended model's (its lag `lag_s`), the growing mode's
    frequency and the phase crossover of the extended loop [Hz] (nan when none), the log's
    dominant torque frequency after it first reaches tau_max and its resolution [Hz], and the
    band [Hz] the mode and the crossover span over the fitted values' spread (module
    docstring; the two frequencies themselves without one)."""

    nominal_radius: float
    extended_radius: float
    lag_s: float
    mode_hz: float
    crossover_hz: float
    cycle_hz: float
    resolution_hz: float
    band_hz: tuple[float, float] = (math.nan, math.nan)
    spread_radius: float = math.nan

    @property
    def grows(self) -> bool:
        """The extended loop grows at the point estimate or somewhere over the fitted
        values' spread (`spread_radius`, module docstring)."""
        return max(self.extended_radius, self.spread_radius) > 1.0 if \
            math.isfinite(self.spread_radius) else self.extended_radius > 1.0

    @property
    def confirms(self) -> bool:
        """The nominal's loop is stable, the extended one's unstable (over the fitted
        values' spread), and the log's torque at the limit oscillates between the phase
        crossover and the growing mode of the growing loops over that spread (module
        docstring), within the resolution."""
        if all(math.isfinite(b) for b in self.band_hz):
            lo, hi = self.band_hz
        else:
            lo, hi = sorted((self.mode_hz, self.crossover_hz))
        return (self.nominal_radius < 1.0 and self.grows
                and lo - self.resolution_hz <= self.cycle_hz <= hi + self.resolution_hz)

    def text(self) -> str:
        return (f"the loop linearised under the logged PI cascade grows by a factor "
                f"{self.extended_radius:.4g} a sample with the lag of {1e3 * self.lag_s:.3g} ms "
                f"(mode {self.mode_hz:.3g} Hz, phase crossover {self.crossover_hz:.3g} Hz"
                + (f"; {self.band_hz[0]:.3g}-{self.band_hz[1]:.3g} Hz where it grows over the "
                   f"fitted values' spread, by up to {self.spread_radius:.4g} a sample"
                   if all(math.isfinite(b) for b in self.band_hz) else
                   f"; at most {self.spread_radius:.4g} over the fitted values' spread"
                   if math.isfinite(self.spread_radius) else "")
                + "), "
                f"{self.nominal_radius:.4g} without it; the log's torque at the limit "
                f"oscillates at {self.cycle_hz:.3g} +- {self.resolution_hz:.2g} Hz")

    def to_json(self) -> dict:
        return {"nominal_radius": self.nominal_radius, "extended_radius": self.extended_radius,
                "lag_s": self.lag_s, "mode_hz": self.mode_hz,
                "crossover_hz": self.crossover_hz, "cycle_hz": self.cycle_hz,
                "resolution_hz": self.resolution_hz,
                "band_hz": [b if math.isfinite(b) else None for b in self.band_hz],
                "spread_radius": (self.spread_radius if math.isfinite(self.spread_radius)
                                  else None),
                "confirms": self.confirms}


def plant(p: dict[str, float], ts: float, lag_s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(Ad, Bd) of the axis over one sample with the torque held (module docstring): state
    (q_m, q_m', q, q', tau_a) for a two-mass `p` (K in it), (q_m, q_m', tau_a) for a rigid
    one (J); tau_a the lagged torque, left out when lag_s is 0."""
    if "K" in p:
        Jm, JL, K = p["Jm"], p["JL"], p["K"]
        D = p.get("D", 0.0)   # a spring damping named beside the lag (effects.spring_damping)
        A = np.array([[0, 1, 0, 0], [-K / Jm, -(p.get("FVm", 0.0) + D) / Jm, K / Jm, D / Jm],
                      [0, 0, 0, 1], [K / JL, D / JL, -K / JL, -(p.get("FV", 0.0) + D) / JL]])
        b = np.array([0, 1 / Jm, 0, 0])
    else:
        A = np.array([[0, 1], [0, -p.get("FV", 0.0) / p["J"]]])
        b = np.array([0, 1 / p["J"]])
    if lag_s > 0:
        n = len(b)
        A = np.block([[A, b[:, None]], [np.zeros((1, n)), -1 / lag_s * np.ones((1, 1))]])
        b = np.r_[np.zeros(n), 1 / lag_s]
    n = len(b)
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n] = A * ts, b * ts
    E = expm(M)
    return E[:n, :n], E[:n, n]


def closed_loop(p: dict[str, float], kp: float, kv: float, ki: float, ts: float,
                lag_s: float = 0.0) -> np.ndarray:
    """Transition matrix of the plant under the PI cascade (module docstring), state
    (plant state, q_m[k-1], I[k-1])."""
    Ad, Bd = plant(p, ts, lag_s)
    n = len(Bd)
    e = np.zeros(n + 2)              # e[k] = -kp q_m - (q_m - q_m[k-1]) / ts
    e[0], e[n] = -kp - 1 / ts, 1 / ts
    integral = ki * ts * e           # I[k] = I[k-1] + ki ts e[k]
    integral[n + 1] += 1.0
    tau = kv * e + integral
    F = np.zeros((n + 2, n + 2))
    F[:n, :n] = Ad
    F[:n] += np.outer(Bd, tau)
    F[n, 0] = 1.0
    F[n + 1] = integral
    return F


def dominant_mode(F: np.ndarray, ts: float) -> tuple[float, float]:
    """(spectral radius, its mode's frequency [Hz]) of transition matrix F."""
    ev = np.linalg.eigvals(F)
    i = int(np.argmax(np.abs(ev)))
    return float(np.abs(ev[i])), abs(float(np.angle(ev[i]))) / (2 * math.pi * ts)


def crossover_hz(p: dict[str, float], kp: float, kv: float, ki: float, ts: float,
                 lag_s: float) -> float:
    """The highest frequency [Hz] below Nyquist where the loop's phase is -180 degrees with
    a gain over 1: L(z) = (kv + ki ts z / (z - 1)) (kp + (z - 1) / (z ts)) G(z), G the plant's
    q_m per held torque (nan when there is none)."""
    Ad, Bd = plant(p, ts, lag_s)
    w, V = np.linalg.eig(Ad)
    c = V[0] * np.linalg.solve(V, Bd)        # G(z) = sum_i c_i / (z - w_i)
    f = np.linspace(0.0, 0.5 / ts, 4001)[1:-1]
    z = np.exp(2j * math.pi * f * ts)
    G = (c[None, :] / (z[:, None] - w[None, :])).sum(axis=1)
    L = (kv + ki * ts * z / (z - 1)) * (kp + (z - 1) / (z * ts)) * G
    cross = np.nonzero((np.sign(L.imag[:-1]) != np.sign(L.imag[1:])) & (L.real[:-1] < -1.0))[0]
    if not len(cross):
        return math.nan
    i = int(cross[-1])
    # the zero of Im L between the two grid points, linearly
    return float(f[i] + (f[i + 1] - f[i]) * L.imag[i] / (L.imag[i] - L.imag[i + 1]))


def cycle_hz(log: Log) -> tuple[float, float] | None:
    """The dominant frequency [Hz] of the logged torque from its first sample at tau_max on,
    and its resolution [Hz]: the power spectrum averaged over pieces of the held-out test's
    segment length (SEGMENTS to the log; Welch, no overlap), whose bins are 1 / segment
    duration apart. The reference's chirp moves the loop's operating point from one segment
    to the next, and the cycle's frequency with it: a segment is the span the other tests
    take as one observation. None when the log never reaches tau_max or less than a segment
    follows."""
    at = at_limit(log)
    n = len(log.tau_m) // SEGMENTS
    if not at.any() or n < 8:
        return None
    tau = np.asarray(log.tau_m, float)[int(np.argmax(at)):]
    if len(tau) < n:
        return None
    f, S = welch(tau, fs=1.0 / log.ts, window="boxcar", nperseg=n, noverlap=0,
                 detrend="constant")
    return float(f[int(np.argmax(S[1:])) + 1]), float(f[1] - f[0])


def _loop(q: dict[str, float], kp: float, kv: float, ki: float,
          ts: float) -> tuple[float, float, float]:
    """(spectral radius, growing mode's frequency, phase crossover) of the loop with `q` (its
    lag q["lag_s"])."""
    lag = float(q.get("lag_s", 0.0))
    r, f = dominant_mode(closed_loop(q, kp, kv, ki, ts, lag), ts)
    return r, f, crossover_hz(q, kp, kv, ki, ts, lag)


def _onset(p: dict[str, float], q: dict[str, float], kp: float, kv: float, ki: float,
           ts: float, steps: int = 30) -> tuple[float, float, float]:
    """The loop on the line from `p` to `q`, one growing and one not, at its onset: the
    growing end of the bracket left by `steps` bisections on the spectral radius (a
    2**-steps share of the line)."""
    keys = [k for k in q if k in p]

    def at(x: float) -> dict[str, float]:
        return {**p, **{k: p[k] + x * (q[k] - p[k]) for k in keys}}

    grows = _loop(p, kp, kv, ki, ts)[0] > 1.0
    a, b = 0.0, 1.0          # a: p's side, b: q's side
    for _ in range(steps):
        m = 0.5 * (a + b)
        if (_loop(at(m), kp, kv, ki, ts)[0] > 1.0) == grows:
            a = m
        else:
            b = m
    return _loop(at(a if grows else b), kp, kv, ki, ts)


def over_spread(p: dict[str, float], kp: float, kv: float, ki: float, ts: float,
                spread: dict[str, float]) -> tuple[float, float, float]:
    """(largest spectral radius, lowest and highest frequency [Hz]) of the loop with `p` (its
    lag p["lag_s"]) over the box p[k] +- spread[k] (each value kept positive; its corners,
    the middles of its edges and p itself): the frequencies are the growing mode's and the
    phase crossover's of the loops that grow, the crossover left out where there is none,
    and, on the line from p to a point of the box where the loop's growth differs from p's,
    those at the onset (_onset; module docstring); nan when no loop grows."""
    keys = [k for k, w in spread.items() if k in p and w > 0]
    here = _loop(p, kp, kv, ki, ts)
    largest, found = here[0], list(here[1:]) if here[0] > 1.0 else []
    for signs in itertools.product((-1.0, 0.0, 1.0), repeat=len(keys)):
        if not any(signs):
            continue
        q = dict(p)
        for k, s in zip(keys, signs):
            q[k] = max(p[k] + s * spread[k], 0.0)
        there = _loop(q, kp, kv, ki, ts)
        largest = max(largest, there[0])
        if there[0] > 1.0:
            found += there[1:]
        if (there[0] > 1.0) != (here[0] > 1.0):
            found += _onset(p, q, kp, kv, ki, ts)[1:]
    found = [f for f in found if math.isfinite(f)]
    return (largest, min(found), max(found)) if found else (largest, math.nan, math.nan)


def band_hz(p: dict[str, float], kp: float, kv: float, ki: float, ts: float,
            spread: dict[str, float]) -> tuple[float, float]:
    """The lowest and highest of the growing mode's and the phase crossover's frequencies
    [Hz] where the loop with `p` (its lag p["lag_s"]) grows over the box p[k] +- spread[k]
    (over_spread; module docstring: the fitted values' spread)."""
    return over_spread(p, kp, kv, ki, ts, spread)[1:]


def limit_cycle(log: Log, nominal: dict[str, float], extended: dict[str, float],
                kp: float, kv: float, ki: float,
                spread: dict[str, float] | None = None) -> LimitCycle | None:
    """The loop's linearisation for a named lag on a clipped log under the PI cascade of
    gains kp, kv, ki (module docstring): None when the extended model has no lag or the log
    never reaches tau_max. `spread`: the half-width of each fitted value's range (lag_s, D),
    over which the band of the mode and the crossover is taken (band_hz); None: none."""
    lag = float(extended.get("lag_s", 0.0))
    cycle = cycle_hz(log)
    if not lag > 0 or cycle is None:
        return None
    ts = log.ts
    ext = {**nominal, **extended}
    rn, _ = dominant_mode(closed_loop(nominal, kp, kv, ki, ts), ts)
    re, fe = dominant_mode(closed_loop(ext, kp, kv, ki, ts, lag), ts)
    largest, lo, hi = over_spread(ext, kp, kv, ki, ts, spread) if spread else (math.nan,) * 3
    return LimitCycle(nominal_radius=rn, extended_radius=re, lag_s=lag, mode_hz=fe,
                      crossover_hz=crossover_hz(ext, kp, kv, ki, ts, lag),
                      cycle_hz=cycle[0], resolution_hz=cycle[1], band_hz=(lo, hi),
                      spread_radius=largest)
