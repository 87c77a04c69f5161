"""identification/link_sim.simulate_link against a plain statement of the same stepper: the
link of eq. (5) driven by a motor angle linear between samples, the linear part propagated
exactly, the friction and the gravity (at the step's middle angle) added as a constant
acceleration over the step, the reversal or sticking instant placed inside the step by linear
interpolation of the velocity. Both do the same floating-point operations, so they agree to
rounding (1e-12 of the deflection's rms; measured: equal), the stepper interpreted and, when
numba is installed (the extra "fast"), compiled."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointbench.identification.link_sim import _transition, rest_angle, simulate_link

TS = 1 / 350.87


def plain_stepper(qm, ts, a, b, c=0.0, gx=0.0, gy=0.0):
    """Each step written out: q, q' at every sample from the exact one-step maps."""
    (p00, p01, p10, p11), (u0q, u0v), (s0q, s0v), (f0q, f0v) = _transition(a, b, ts)
    u = list(map(float, qm))
    n = len(u)
    q, v = rest_angle(u[0], a, gx, gy), 0.0
    stuck = c > 0
    out_q, phi = np.empty(n), np.zeros(n)
    out_q[0] = q

    def gravity(x):
        return gx * math.cos(x) + gy * math.sin(x)

    def step(q, v, k, slope, f):
        return (p00 * q + p01 * v + u0q * u[k] + s0q * slope + f0q * f,
                p10 * q + p11 * v + u0v * u[k] + s0v * slope + f0v * f)

    for k in range(n - 1):
        slope = (u[k + 1] - u[k]) / ts
        grav = gravity(q) if gx != 0 or gy != 0 else 0.0
        if stuck:
            force = a * (u[k + 1] - q) - grav
            if abs(force) <= c:
                phi[k] = (a * (0.5 * (u[k] + u[k + 1]) - q) - grav) / c
                out_q[k + 1] = q
                continue
            stuck = False
            sg = 1.0 if force > 0 else -1.0
        else:
            sg = 1.0 if v > 0 else -1.0
        qn, vn = step(q, v, k, slope, -c * sg - grav)
        if gx != 0 or gy != 0:
            grav = gravity(0.5 * (q + qn))
            qn, vn = step(q, v, k, slope, -c * sg - grav)
        if vn * sg > 0 or c == 0:
            phi[k], q, v = sg, qn, vn
        else:
            th = v / (v - vn) if v != vn else 0.0
            qx = q + (qn - q) * th
            end = a * (u[k + 1] - qx) - grav
            ux = u[k] + (u[k + 1] - u[k]) * th
            hold = abs(a * (ux - qx) - grav) <= c
            held = a * (0.5 * (ux + u[k + 1]) - qx) - grav
            after = max(-1.0, min(1.0, end / c)) if hold else -sg
            phi[k] = sg * th + after * (1.0 - th)
            qn, vn = step(q, v, k, slope, -c * phi[k] - grav)
            stuck = hold and abs(end) <= c
            if stuck:
                phi[k] = sg * th + held / c * (1.0 - th)
            q, v = (qx if stuck else qn), (0.0 if stuck else vn)
        out_q[k + 1] = q
    return out_q, phi


def motor_angle(seed: int, duration: float = 8.0) -> np.ndarray:
    """A chirp of the motor angle (0.2-15 Hz, 0.05 rad) with a slow drift and sensor noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, TS)
    f = 0.2 + (15.0 - 0.2) * t / (2 * duration)
    return (0.05 * np.sin(2 * np.pi * f * t) + 0.02 * np.sin(0.3 * t + rng.uniform(0, 6))
            + 1e-5 * rng.standard_normal(len(t)))


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("c, gx, gy", [(0.0, 0.0, 0.0), (2.0, 0.0, 0.0), (0.0, 0.1, -9.0),
                                       (2.0, 0.1, -9.0), (15.0, 0.0, 4.0)],
                         ids=["linear", "friction", "gravity", "both", "heavy-friction"])
@pytest.mark.parametrize("compiled", [False, True], ids=["interpreted", "compiled"])
def test_stepper_equals_the_plain_steps(seed, c, gx, gy, compiled):
    if compiled:
        pytest.importorskip("numba")
    qm = motor_angle(seed)
    a, b = (2 * np.pi * 3.3) ** 2, 1.8
    q0, phi0 = plain_stepper(qm, TS, a, b, c, gx, gy)
    q1, phi1 = simulate_link(qm, TS, a, b, c, gx, gy, compiled=compiled)
    scale = np.std(qm - q0)
    np.testing.assert_allclose(q1, q0, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(phi1, phi0, rtol=0, atol=1e-12)
    if c > 0:   # the cases exercise the stick phases and the reversals inside a step
        assert 0 < np.sum(np.abs(phi0[:-1]) < 1) < len(qm) - 1


@pytest.mark.parametrize("first, step, count", [(0, 26, 300), (7, 10, 500), (13, 17, 120)])
def test_inverse_at_reads_the_inverse_transform(first, step, count):
    """`inverse_at` (Bluestein's chirp convolution) against scipy.fft.irfft of the same
    band-limited spectrum read at first + k step: equal to rounding (measured: 8e-16 of the
    largest sample)."""
    from scipy import fft

    from jointbench.identification.link_sim import inverse_at
    rng = np.random.default_rng(first)
    n_fft, bins = 8192, 700
    X = np.zeros((3, n_fft // 2 + 1), dtype=complex)
    X[:, :bins] = rng.standard_normal((3, bins)) + 1j * rng.standard_normal((3, bins))
    X[:, 0] = X[:, 0].real                  # a real signal's mean
    full = fft.irfft(X, n_fft)[:, first + step * np.arange(count)]
    got = inverse_at(X[:, :bins], n_fft, first, step, count)
    np.testing.assert_allclose(got, full, rtol=0, atol=1e-13 * np.abs(full).max())


@pytest.mark.parametrize("n", [2, 3, 1000, 3510, 21053])
def test_spectra_pad_to_twice_the_record(n):
    """`spectra` pads to an even FFT length of at least 2 n (the link's response does not
    wrap onto the record; `inverse` reads the length off the bins), and `inverse` gives the
    signals back (to rounding)."""
    from jointbench.identification.link_sim import inverse, spectra
    u = np.random.default_rng(n).standard_normal((2, n))
    s, U, u0 = spectra(list(u), 1 / 350.87)
    L = 2 * (len(s) - 1)
    assert L >= 2 * n and L % 2 == 0
    np.testing.assert_allclose(inverse(U, s, n) + u0[:, None], u, rtol=0, atol=1e-12)
