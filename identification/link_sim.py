"""The link of eq. (5) driven by the measured motor angle: what the motor-only model needs in
place of the link encoder (identification/link_fit.py).

    q'' = a (qm - q) - b q' - c phi - gx cos q - gy sin q,   phi in sign(q')

with a = K / JL, b = FV / JL, c = FS / JL, gx = g MX / JL, gy = g MY / JL (per unit link
inertia). The link Coulomb friction sticks and slips: phi = sign(q') while the link moves, and
the force that holds it (|phi| <= 1) while the spring cannot overcome FS (on a heavy link at the
chirp's low frequencies the link is held about half the time). A smoothed sign(q') would need
steps far below the sample period; this stepper is exact between events instead.

Three pieces:
- `simulate_link`: one pass over the samples (the motor angle linear between samples, the
  linear part propagated exactly, the reversal or sticking instant placed inside the step by
  linear interpolation of the velocity), returning q and the friction phi averaged over each
  step; the pass (`_steps`) is plain scalar code, compiled by numba when it is installed (the
  optional extra "fast": the link fit runs it at every parameter point it tries) and
  interpreted otherwise, the same floating-point operations either way;
- `link_response`: the linear part, d = H u with H = 1 / (s^2 + b s + a), applied in the
  frequency domain (exact for band-limited samples; the filtered derivatives the regressors
  use are), with its derivatives with respect to a and b for Gauss-Newton.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy import fft
from scipy.linalg import expm

from jointbench.identification.compiled import compiled as compiled_kernel


def _transition(a: float, b: float, ts: float) -> tuple[list[float], ...]:
    """Exact one-step maps of x = (q, q') for x' = A x + (0, a u + f): the state's, the motor
    angle's value and slope at the step start (u linear over the step), a constant
    acceleration f's."""
    M = np.zeros((5, 5))
    M[:2, :2] = [[0.0, 1.0], [-a, -b]]
    M[1, 2] = a
    M[2, 3] = 1.0
    M[1, 4] = 1.0
    E = expm(M * ts)
    return E[:2, :2].ravel().tolist(), E[:2, 2].tolist(), E[:2, 3].tolist(), E[:2, 4].tolist()


def rest_angle(qm0: float, a: float, gx: float, gy: float) -> float:
    """The link angle at rest with the motor at qm0: a (qm0 - q) = gx cos q + gy sin q."""
    q = qm0
    for _ in range(50):
        q = qm0 - (gx * math.cos(q) + gy * math.sin(q)) / a
    return q


def simulate_link(qm: np.ndarray, ts: float, a: float, b: float, c: float = 0.0,
                  gx: float = 0.0, gy: float = 0.0, compiled: bool = True
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The link angle q [rad] at the samples of the motor angle `qm` [rad] (sample period `ts`
    [s]), from rest at the start, and the link friction phi = friction / FS averaged over each
    step (phi[k] over [t_k, t_k+1); the last is 0). Raises ValueError unless a > 0, b, c >= 0.

    Each step is x' = P x + U0 u_k + S0 u'_k + F0 f (`_transition`), the linear part
    P x + U0 u_k + S0 u'_k summed once and the friction and gravity f added to it (once more
    with the gravity at the step's middle angle, and once more when the velocity reaches zero
    inside the step); the gravity is evaluated only where q moved. `compiled`: the steps
    (`_steps`) compiled by numba when it is installed (the optional extra "fast"), else
    interpreted; both do the same floating-point operations."""
    if not (a > 0 and b >= 0 and c >= 0):
        raise ValueError(f"the link needs a > 0, b >= 0, c >= 0 (got {a}, {b}, {c})")
    P, U0, S0, F0 = _transition(a, b, ts)
    qm = np.ascontiguousarray(qm, dtype=float)
    n = len(qm)
    q0 = rest_angle(float(qm[0]), a, gx, gy)
    slope = (qm[1:] - qm[:-1]) / ts
    steps = compiled_kernel(_steps) if compiled else None
    if steps is not None:
        out_q, phi = np.empty(n), np.empty(n)
        steps(qm, slope, out_q, phi, q0, float(a), float(c), float(gx), float(gy),
              *P, *U0, *S0, *F0)
        return out_q, phi
    out_q, phi = [0.0] * n, [0.0] * n
    _steps(qm.tolist(), slope.tolist(), out_q, phi, q0, a, c, gx, gy, *P, *U0, *S0, *F0)
    return np.array(out_q), np.array(phi)


def _steps(u, slope, out_q, phi, q: float, a: float, c: float, gx: float, gy: float,
           p00: float, p01: float, p10: float, p11: float, u0q: float, u0v: float,
           s0q: float, s0v: float, f0q: float, f0v: float) -> None:
    """`simulate_link`'s pass over the samples u (the motor angle) with slopes `slope`,
    writing q and phi into `out_q` and `phi` (lists, or arrays when compiled), from rest at
    q. Plain scalar code, so that numba compiles it as it is."""
    n = len(u)
    v = 0.0
    stuck = c > 0
    gravity = gx != 0 or gy != 0
    grav, grav_at = 0.0, math.nan    # the gravity gx cos q + gy sin q, and the q it is of
    out_q[0] = q
    for k in range(n - 1):
        uk, uk1, sl = u[k], u[k + 1], slope[k]
        if gravity and q != grav_at:
            grav, grav_at = gx * math.cos(q) + gy * math.sin(q), q
        if stuck:
            force = a * (uk1 - q) - grav
            if abs(force) <= c:                # the spring cannot move it yet
                # the friction holds the spring's force: its mean over the step, not its end
                # value (that would lead the motor by half a sample while the link sticks)
                phi[k] = (a * (0.5 * (uk + uk1) - q) - grav) / c
                out_q[k + 1] = q
                continue
            stuck = False
            sg = 1.0 if force > 0 else -1.0    # breaks away (at the sample)
        else:
            sg = 1.0 if v > 0 else -1.0
        lin_q = p00 * q + p01 * v + u0q * uk + s0q * sl
        lin_v = p10 * q + p11 * v + u0v * uk + s0v * sl
        f = -c * sg - grav
        qn = lin_q + f0q * f
        if gravity:
            # gravity at the step's middle angle: held at its start it would lag half a step,
            # a negative damping of g MY T / 2 (12 % of FV on the arm's axis 6)
            qh = 0.5 * (q + qn)
            grav, grav_at = gx * math.cos(qh) + gy * math.sin(qh), math.nan
            f = -c * sg - grav
            qn = lin_q + f0q * f
        vn = lin_v + f0v * f
        if vn * sg > 0 or c == 0:
            phi[k] = sg
            q, v = qn, vn
        else:
            # the velocity reaches zero inside the step, at the share th of it: the friction
            # is sg until then, and after it either holds the link or reverses
            th = v / (v - vn) if v != vn else 0.0
            qx = q + (qn - q) * th
            end = a * (uk1 - qx) - grav
            ux = uk + (uk1 - uk) * th
            hold = abs(a * (ux - qx) - grav) <= c
            held = a * (0.5 * (ux + uk1) - qx) - grav    # its mean over the rest
            after = max(-1.0, min(1.0, end / c)) if hold else -sg
            mean = sg * th + after * (1.0 - th)
            f = -c * mean - grav
            qn = lin_q + f0q * f
            vn = lin_v + f0v * f
            stuck = hold and abs(end) <= c
            if stuck:     # held to the step's end: the holding force's mean, as above
                mean = sg * th + held / c * (1.0 - th)
            phi[k] = mean
            if stuck:
                q, v = qx, 0.0
            else:
                q, v = qn, vn
        out_q[k + 1] = q
    phi[n - 1] = 0.0


def spectra(signals: list[np.ndarray], ts: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Laplace variable s = j w on the FFT bins (the record zero padded to at least twice
    its length, so that the link's response does not wrap: to twice the next length with
    small prime factors, `scipy.fft.next_fast_len`, which a batch of rows transforms several
    times faster than the next power of two), the spectra of the signals less their first
    sample (rows), and those first samples. NaN counts as 0."""
    u = np.nan_to_num(np.asarray(signals, dtype=float))
    n = u.shape[-1]
    L = 2 * fft.next_fast_len(max(n, 2), real=True)    # even: `inverse` reads L off the bins
    u0 = u[:, 0].copy()
    return 2j * np.pi * fft.rfftfreq(L, ts), fft.rfft(u - u0[:, None], L), u0


def inverse(X: np.ndarray, s: np.ndarray, n: int) -> np.ndarray:
    """The first n samples of the signals whose spectra are the rows of X (bins of s)."""
    return fft.irfft(X, 2 * (len(s) - 1))[..., :n]


def inverse_at(X: np.ndarray, n_fft: int, first: int, step: int, count: int) -> np.ndarray:
    """Samples first + k step, k < count, of the real signals of length n_fft whose spectra
    (`scipy.fft.rfft`'s bins) are the rows of X, with every bin past X's last one zero (a
    band-limited spectrum: `inverse` read at a few samples). The real inverse transform
    x[t] = (2 / n_fft) Re sum_j X_j' w^(j t), X_0' = X_0 / 2, w = exp(2 pi i / n_fft), is
    evaluated on the stride by Bluestein's chirp convolution (jk = (j^2 + k^2 - (k - j)^2) / 2),
    one FFT pair of about len + count points per row instead of n_fft."""
    pre, kernel, post, size = _bluestein(X.shape[-1], n_fft, first, step, count)
    c = fft.ifft(fft.fft(X * pre, size) * kernel, size)[..., :count]
    return (c * post).real


@lru_cache(maxsize=8)
def _bluestein(bins: int, n_fft: int, first: int, step: int, count: int
               ) -> tuple[np.ndarray, ...]:
    """`inverse_at`'s factors for one grid: the input's (the half DC bin, the shift to `first`,
    the chirp w^(step j^2 / 2)), the kernel's FFT (w^(-step t^2 / 2), t from -(bins - 1) to
    count - 1) and the output's (the chirp and 2 / n_fft); each phase exact as an integer
    modulo 2 n_fft. Made once per grid, read-only: shared."""
    def chirp(t: np.ndarray) -> np.ndarray:       # w^(step t^2 / 2)
        return np.exp(1j * np.pi * ((step * t * t) % (2 * n_fft)) / n_fft)

    j, k = np.arange(bins, dtype=np.int64), np.arange(count, dtype=np.int64)
    size = fft.next_fast_len(bins + count - 1)
    pre = chirp(j) * np.exp(2j * np.pi * ((j * first) % n_fft) / n_fft)
    pre[0] *= 0.5
    t = np.arange(-(bins - 1), count, dtype=np.int64)
    v = np.zeros(size, dtype=complex)
    v[t % size] = np.conj(chirp(t))
    out = (pre, fft.fft(v), chirp(k) * (2.0 / n_fft), size)
    for x in out[:3]:
        x.setflags(write=False)
    return out


def link_response(u: np.ndarray, a: float, b: float, ts: float, order: int = 1,
                  times_s: bool = False) -> np.ndarray:
    """(H^order u) with H = 1 / (s^2 + b s + a), or (s H^order u) when `times_s`, from rest at
    the first sample: the response to u - u[0] plus the static one to u[0] (u[0] / a^order,
    none with the factor s). NaN in u counts as 0."""
    s, U, u0 = spectra([u], ts)
    H = (1.0 / (s * s + b * s + a)) ** order
    if times_s:
        H = H * s
    out = inverse(H * U, s, len(u))[0]
    return out if times_s else out + u0[0] / a ** order
