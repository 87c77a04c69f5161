"""The first mode from the link-over-motor response q / q_m and an inertia fit of q / tau_m.

The link equation (5) alone, JL q'' + FV q' = K (q_m - q), gives

    q / q_m = wa^2 / (s^2 + b s + wa^2),   wa^2 = K / JL,  b = FV / JL,

a resonance at the link mode wa = sqrt(K / JL), sharp whatever damps the motor side (a
voltage drive's back-EMF, a stiff position loop) and whatever the controller, since neither
enters it. With P(s) = s^2 + b s + wa^2, eq. (6) then gives the inverse link response

    tau_m / q = (Jm s + FVm) s P(s) / wa^2 + JL s (s + b),

linear in (Jm, FVm, JL) once wa and b are known: a weighted least squares over the coherent
bins gives JL / Jm, and the locked first mode of eqs. (5)-(6)

    f1 = wa sqrt(1 + JL / Jm) / 2 pi

that the band of section 3.2 is designed from. Both responses are the closed-loop indirect
estimates S(q_ref, out) / S(q_ref, in) when q_ref is logged (the encoder's quantisation, in
q_m and in q = theta - alpha alike, is uncorrelated with the reference), else with tau_m as
the instrument. Coulomb friction is left out of the fit: it acts as extra damping on the
motor side, which the shape absorbs into FVm.
"""

from __future__ import annotations

import math

import numpy as np

from jointbench.identification.log import Log
from jointbench.identification.spectra import Spectra, welch

COHERENCE_MIN = 0.5     # bins kept: coherence of the instrument with input and output
SEGMENT_S = 8.0         # Welch segment length [s] of q / q_m, as identification.first_mode
INERTIA_SEGMENT_S = 2.0  # of q / tau_m: smooth (no lightly damped pole), more averages
FMIN_HZ = 0.2           # the link response's fit starts here (below: |q / q_m| = 1, no shape)
MIN_BINS = 8            # coherent bins each fit needs
PEAK_MIN = 2.0          # |q / q_m| at the link mode over 1 (its low-frequency level)
SPREAD_MAX = 0.05       # the two halves' f1 may differ by this share of f1 (else: no estimate)
EXCITATION_MARGIN = 1.1  # an excitation whose top lies under this times f1 gets a note


def _nperseg(n: int, fs: float, seconds: float = SEGMENT_S) -> int:
    return int(min(2 ** math.ceil(math.log2(seconds * fs)), 2 ** math.floor(math.log2(n / 2))))


def _ratio(spectra: Spectra, x: str, inp: str, out: str, sl: slice, nperseg: int,
           noverlap: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(f, out / inp through the instrument x (log column names) on the samples `sl`,
    weight): the weight is the inverse relative variance of the ratio, 2 n g^2 / (1 - g^2)
    summed over both coherences g (Bendat & Piersol), zero where either coherence is under
    COHERENCE_MIN."""
    kw = dict(nperseg=nperseg, noverlap=noverlap, sl=sl)
    f = spectra.frequencies(nperseg)
    s_xo = spectra.csd(x, out, **kw)
    s_xi = spectra.csd(x, inp, **kw)
    with np.errstate(divide="ignore", invalid="ignore"):
        c_o = np.nan_to_num(spectra.coherence(x, out, **kw))
        c_i = np.nan_to_num(spectra.coherence(x, inp, **kw))
        H = s_xo / s_xi
    step = nperseg - (noverlap if noverlap is not None else nperseg // 2)
    n_avg = max(1, (len(spectra.log.t[sl]) - nperseg) // step + 1)
    ok = (c_o >= COHERENCE_MIN) & (c_i >= COHERENCE_MIN) & np.isfinite(H) & (f > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        var = sum((1 - c) / (2 * n_avg * c) for c in (c_o, c_i))
        w = np.where(ok, 1.0 / np.maximum(var, 1e-12), 0.0)
    return f, np.where(ok, H, 0.0), w


def link_over_motor(f: np.ndarray, H: np.ndarray, w: np.ndarray, top_hz: float
                    ) -> tuple[float, float] | None:
    """(wa^2, b) of q / q_m = wa^2 / (s^2 + b s + wa^2) from the measured response H (module
    docstring): 1 / H - 1 = s^2 / wa^2 + s b / wa^2, a weighted linear least squares in
    (1 / wa^2, b / wa^2) over the bins of positive weight from half to twice the peak of |H|
    in the excited band FMIN_HZ-`top_hz` (the weight, the inverse relative variance of H, is
    that of 1 / H too). None when fewer than MIN_BINS bins, no positive 1 / wa^2, or no peak
    of at least PEAK_MIN inside the band."""
    band = (w > 0) & (f >= FMIN_HZ) & (f <= top_hz)
    if band.sum() < MIN_BINS:
        return None
    k = np.flatnonzero(band)[np.argmax(np.abs(H[band]))]
    if abs(H[k]) < PEAK_MIN:
        return None
    use = band & (f >= 0.5 * f[k]) & (f <= 2.0 * f[k])
    if use.sum() < MIN_BINS:
        return None
    s = 2j * np.pi * f[use]
    y = 1.0 / H[use] - 1.0
    # relative error d of H is an absolute error d / |H| of 1 / H - 1's scale: weight |H|^2
    sw = np.sqrt(w[use]) * np.abs(H[use])
    A = np.column_stack([s ** 2, s])
    A_ri = np.vstack([A.real, A.imag]) * np.concatenate([sw, sw])[:, None]
    y_ri = np.concatenate([y.real, y.imag]) * np.concatenate([sw, sw])
    c, *_ = np.linalg.lstsq(A_ri.real, y_ri, rcond=None)
    if not c[0] > 0:
        return None
    wa2, b = 1.0 / c[0], c[1] / c[0]
    fa = math.sqrt(wa2) / (2 * math.pi)
    if not f[use].min() < fa < f[use].max():
        return None
    return wa2, b


def inertia_ratio(f: np.ndarray, Hq: np.ndarray, w: np.ndarray, wa2: float, b: float,
                  top_hz: float, fs: float) -> tuple[float, float, float] | None:
    """(Jm, FVm, JL) from tau_m / q = (Jm s + FVm) s P / wa^2 + JL s (s + b) (module
    docstring) fitted to the measured q / tau_m response Hq over the excited band
    FMIN_HZ-`top_hz`, each bin weighted by its inverse relative variance; the logged torque,
    held over each period, acts half a sample late (ZOH). None when fewer than MIN_BINS bins
    or a non-positive inertia."""
    use = (w > 0) & (f >= FMIN_HZ) & (f <= top_hz)
    if use.sum() < MIN_BINS:
        return None
    s = 2j * np.pi * f[use]
    y = np.exp(-s / (2 * fs)) / Hq[use]
    P = s ** 2 + b * s + wa2
    A = np.column_stack([s ** 2 * P / wa2, s * P / wa2, s * (s + b)])
    sw = np.sqrt(w[use]) * np.abs(Hq[use])
    A_ri = np.vstack([A.real, A.imag]) * np.concatenate([sw, sw])[:, None]
    y_ri = np.concatenate([y.real, y.imag]) * np.concatenate([sw, sw])
    c, *_ = np.linalg.lstsq(A_ri, y_ri, rcond=None)
    Jm, FVm, JL = (float(v) for v in c)
    if not (Jm > 0 and JL > 0):
        return None
    return Jm, FVm, JL


def _estimate(log: Log, sl: slice, nperseg: int, noverlap: int | None, top_hz: float,
              spectra: Spectra) -> tuple[float, float, float] | None:
    """(fa, f1, JL / Jm) [Hz, Hz, -] on the samples `sl`, or None."""
    fs = log.sample_rate_hz
    x = "q_ref" if log.q_ref is not None else "tau_m"
    f, H, w = _ratio(spectra, x, "q_m", "q", sl, nperseg, noverlap)
    ab = link_over_motor(f, H, w, top_hz)
    if ab is None:
        return None
    nperseg = min(nperseg, _nperseg(len(log.t[sl]), fs, INERTIA_SEGMENT_S))
    f2, Hq, w2 = _ratio(spectra, x, "tau_m", "q", sl, nperseg, noverlap)
    if log.q_ref is None:
        # tau_m is its own instrument: H1 = S(tau, q) / S(tau, tau), no coherence on the input
        f2 = spectra.frequencies(nperseg)
        s_tq = spectra.csd("tau_m", "q", nperseg, noverlap, sl)
        s_tt = spectra.welch("tau_m", nperseg, noverlap, sl)
        with np.errstate(divide="ignore", invalid="ignore"):
            Hq = s_tq / s_tt
    fit = inertia_ratio(f2, Hq, w2, *ab, top_hz, spectra.hold_hz)
    if fit is None:
        return None
    Jm, _, JL = fit
    wa2 = ab[0]
    return (math.sqrt(wa2) / (2 * math.pi), math.sqrt(wa2 * (1 + JL / Jm)) / (2 * math.pi),
            JL / Jm)


def link_mode(log: Log) -> tuple[float, float] | None:
    """(wa^2, b) = (K / JL, FV / JL) [rad^2/s^2, 1/s] of q / q_m over the whole record
    (`link_over_motor`, through q_ref when logged, else tau_m): what the two encoders alone
    say of the link, whatever the drive and the controller. None without q or a link mode in
    the excited band."""
    if log.q is None:
        return None
    fs = log.sample_rate_hz
    x = "q_ref" if log.q_ref is not None else "tau_m"
    f, H, w = _ratio(Spectra(log), x, "q_m", "q", slice(None), _nperseg(len(log), fs))
    return link_over_motor(f, H, w, 1.1 * excitation_top_hz(log))


def excitation_top_hz(log: Log, spectra: Spectra | None = None) -> float:
    """The top of the excited band [Hz]: the highest frequency under which 99 % of the power
    of the excitation's (q_ref's, else tau_m's) time derivative lies (the derivative weighs
    the top, which the band of section 3.2 needs). Computed once per `spectra`."""
    if spectra is not None:
        return spectra.memo("link_mode.excitation_top_hz", lambda: excitation_top_hz(log))
    x = log.q_ref if log.q_ref is not None else log.tau_m
    fs = log.sample_rate_hz
    f, p = welch(np.diff(x) * fs, fs, _nperseg(len(x) - 1, fs))
    c = np.cumsum(p)
    return float(f[np.searchsorted(c, 0.99 * c[-1])]) if c[-1] > 0 else math.nan


def link_mode_first_mode(log: Log, spectra: Spectra | None = None
                         ) -> tuple[float, float, str, str] | None:
    """(f1, sigma, method, note) from q / q_m and the inertia fit (module docstring), or None
    when the log has no q, the link response shows no mode, or either half of the record
    (analysed with half-length segments) gives none or an f1 more than SPREAD_MAX apart.
    sigma combines half the spread of the two halves and the bin width / sqrt(12)."""
    if log.q is None:
        return None
    n, fs = len(log), log.sample_rate_hz
    nperseg = _nperseg(n, fs)
    if nperseg < 64:
        return None
    spectra = spectra or Spectra(log)
    top = 1.1 * excitation_top_hz(log, spectra)
    whole = _estimate(log, slice(None), nperseg, None, top, spectra)
    if whole is None:
        return None
    fa, f1, ratio = whole
    half = n // 2
    parts = [_estimate(log, sl, max(64, nperseg // 2), None, top, spectra)
             for sl in (slice(0, half), slice(half, n))]
    if any(p is None for p in parts) or abs(parts[0][1] - parts[1][1]) > SPREAD_MAX * f1:
        return None     # a shape the record's halves do not both show is no estimate
    spread = abs(parts[0][1] - parts[1][1]) / 2
    df = fs / nperseg
    sigma = math.hypot(df / math.sqrt(12), spread)
    indirect = log.q_ref is not None
    method = ("link over motor q/q_m (link mode sqrt(K/JL)) and inertias from q/tau_m, "
              + ("indirect via q_ref" if indirect else "tau_m as instrument"))
    note = (f"link mode sqrt(K/JL) = {fa:.4g} Hz from q/q_m, JL/Jm = {ratio:.3g} from q/tau_m: "
            f"f1 = sqrt(K/JL (1 + JL/Jm)) / 2 pi = {f1:.4g} Hz; sigma {sigma:.2g} Hz from the "
            f"bin width ({df / math.sqrt(12):.2g} Hz) and half the spread of the two halves "
            f"({spread:.2g} Hz: {parts[0][1]:.4g}, {parts[1][1]:.4g} Hz)")
    return f1, sigma, method, note
