"""A plug-in estimator written against jointbench's public API only: the two-mass model fitted
to the measured frequency responses (the spectral alternative the paper cites, its ref. [3]).

    jointbench campaign --runs 50 --method examples/frf_fit.py:estimate

`estimate(log)` takes a `jointbench.Log` (a closed-loop experiment with both encoders and the
reference, `q_ref`) and returns {name: (value, sigma)} for K, Jm and JL by the paper's names.

1. The closed-loop (indirect) frequency responses q_m / tau_m and q / tau_m: cross-spectra
   with the reference, one Hann window over the whole log (scipy.signal.csd), 0.3-10 Hz.
2. A start without any prior: eqs. (5)-(6) linearised are linear in the parameters in the
   frequency domain (equation error), with Q_m, Q the responses to a unit torque:
       1 = (Jm s^2 + FVm s) Q_m + K (Q_m - Q)      0 = (JL s^2 + FV s + G) Q - K (Q_m - Q)
   (G: the gravity stiffness of the link about its working point).
3. Output error on the complex log ratio (log magnitude and phase) of both responses,
   scipy.optimize.least_squares from that start; sigma from the Jacobian at the optimum
   (white residuals assumed: the campaign's coverage column tells whether that holds).

Coulomb friction has no place in a linear model: it is lumped into the viscous terms, so FVm
and FV are fitted but not returned (they come out 50-90 % off and say nothing about the
method's use, the stiffness).
"""

from __future__ import annotations

import numpy as np
from scipy import optimize, signal

import jointbench

BAND_HZ = (0.3, 10.0)
RETURNED = ("Jm", "K", "JL")


def responses(log: jointbench.Log, band_hz=BAND_HZ):
    """(s = 2j pi f, Q_m / tau_m, Q / tau_m) over the band, estimated through the reference."""
    if log.q is None or log.q_ref is None:
        raise ValueError("the FRF fit needs the link encoder (q) and the reference (q_ref)")
    fs, n = log.sample_rate_hz, len(log)
    f, s_rm = signal.csd(log.q_ref, log.q_m, fs=fs, nperseg=n)
    _, s_rl = signal.csd(log.q_ref, log.q, fs=fs, nperseg=n)
    _, s_rt = signal.csd(log.q_ref, log.tau_m, fs=fs, nperseg=n)
    band = (f >= band_hz[0]) & (f <= band_hz[1])
    return 2j * np.pi * f[band], s_rm[band] / s_rt[band], s_rl[band] / s_rt[band]


def equation_error(s, hm, hl) -> np.ndarray:
    """Jm, K, JL, FVm, FV, G by linear least squares on the two linearised equations."""
    d, z = hm - hl, np.zeros_like(s)
    cols = [[s**2 * hm, d, z, s * hm, z, z],          # motor equation
            [z, -d, s**2 * hl, z, s * hl, hl]]        # link equation
    a = np.vstack([np.column_stack(c) for c in cols])
    b = np.concatenate([np.ones_like(s), z])
    w = 1.0 / np.abs(np.concatenate([hm, hm]))        # both equations at the motor's scale
    a, b = a * w[:, None], b * w
    p, *_ = np.linalg.lstsq(np.vstack([a.real, a.imag]), np.concatenate([b.real, b.imag]),
                            rcond=None)
    return p


def two_mass(p, s):
    """Q_m / tau_m and Q / tau_m of eqs. (5)-(6) linearised, stacked."""
    Jm, K, JL, FVm, FV, G = p
    link = JL * s**2 + FV * s + K + G
    den = (Jm * s**2 + FVm * s + K) * link - K**2
    return np.concatenate([link / den, K / den])


def estimate(log: jointbench.Log) -> dict[str, tuple[float, float]]:
    s, hm, hl = responses(log)
    start = equation_error(s, hm, hl)
    scale = np.abs(start[:5])
    measured = np.concatenate([hm, hl])

    def params(x):   # log-scaled positive parameters, G in kN m/rad (any sign)
        return np.concatenate([scale * np.exp(x[:5]), [1e3 * x[5]]])

    def residual(x):
        r = np.log(two_mass(params(x), s) / measured)
        return np.concatenate([r.real, r.imag])

    sol = optimize.least_squares(residual, np.r_[np.zeros(5), start[5] / 1e3],
                                 method="trf", x_scale="jac")
    dof = sol.fun.size - sol.x.size
    cov = (sol.fun @ sol.fun / dof) * np.linalg.pinv(sol.jac.T @ sol.jac)
    p = params(sol.x)
    rel_sigma = np.sqrt(np.diag(cov))[:5]   # d(value) / value = d(x) on the log scale
    fitted = dict(zip(("Jm", "K", "JL", "FVm", "FV"), zip(p[:5], p[:5] * rel_sigma)))
    return {name: (float(v), float(sd)) for name, (v, sd) in fitted.items() if name in RETURNED}
