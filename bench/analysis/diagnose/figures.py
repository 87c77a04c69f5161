"""The figures of `diagnose --out DIR`: where the nominal residual lives, its spectrum, the
inverse view's predictions and the forward view's replays (atomic writes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy import signal

from jointbench.bench.analysis.diagnose.types import BLOCK_NAMES, Diagnosis
from jointbench.identification.plots import save_figure_atomic
from jointbench.identification.paper_tables import signal_units


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _save(fig, path: Path) -> Path:
    """Write the figure atomically and release it (pyplot keeps every open figure)."""
    try:
        return save_figure_atomic(fig, path)
    finally:
        _pyplot().close(fig)


def _residuals(d: Diagnosis):
    nom = d.inverse.nominal
    before = nom.residual
    c = d.named
    after = None
    if c is not None:
        after = c.residual
    return nom, before, after


def _units(d: Diagnosis) -> tuple[str, str]:
    """(position unit, torque unit) of the log: rad and N m, or m and N (prismatic)."""
    return signal_units(d.log.prismatic)


def plot_spectrum(d: Diagnosis, path: Path) -> Path:
    """Power spectral density of the inverse view's residual per equation, before and after
    the named effect."""
    plt = _pyplot()
    nom, before, after = _residuals(d)
    torque = _units(d)[1]
    fs = 1.0 / (nom.sig.ts * nom.sig.settings.Nd)
    blocks = np.unique(nom.block)
    fig, axes = plt.subplots(len(blocks), 1, figsize=(7, 3 * len(blocks)), squeeze=False)
    for ax, b in zip(axes[:, 0], blocks):
        rows = nom.block == b
        for res, label in ((before, "nominal model"), (after, "extended model")):
            if res is None:
                continue
            f, p = signal.welch(res[rows], fs=fs, nperseg=min(256, rows.sum()))
            ax.semilogy(f, p, label=label)
        ax.set_title(f"{BLOCK_NAMES[b].split(':')[0]}: power spectral density of the "
                     "residual", fontsize=9)
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel(f"PSD [({torque})^2/Hz]")
        ax.legend()
    fig.tight_layout()
    return _save(fig, path)


def plot_structure(d: Diagnosis, path: Path) -> Path:
    """Where the nominal residual lives: against velocity sign, deflection (with q only),
    motor angle and time. Panels that do not apply are left out."""
    plt = _pyplot()
    nom = d.inverse.nominal
    sig = nom.sig
    res = nom.residual
    pos, torque = _units(d)
    n = len(sig.index)
    motor = res[:n]
    link = res[n:] if sig.has_link else None
    qmd = sig.dec(np.nan_to_num(sig.qmd))
    fig, axes = plt.subplots(2, 2, figsize=(10, 7))
    panels = list(axes.ravel())
    ax = panels.pop(0)
    s = np.sign(qmd)
    for k, lab in ((-1, "qm' < 0"), (1, "qm' > 0")):
        ax.hist(motor[s == k], bins=40, alpha=0.6, label=lab)
    ax.set_title("motor equation residual, by sign of the motor velocity", fontsize=9)
    ax.set_xlabel(f"residual [{torque}]")
    ax.set_ylabel("decimated samples")
    ax.legend()
    if link is not None:
        ax = panels.pop(0)
        ax.plot(sig.dec(sig.qm - sig.q), link, ".", ms=2)
        ax.set_title("link equation residual against the deflection qm - q", fontsize=9)
        ax.set_xlabel(f"qm - q [{pos}]")
        ax.set_ylabel(f"residual [{torque}]")
    ax = panels.pop(0)
    ax.plot(sig.dec(sig.qm), motor, ".", ms=2)
    ax.set_title("motor equation residual against the motor position qm", fontsize=9)
    ax.set_xlabel(f"qm [{pos}]")
    ax.set_ylabel(f"residual [{torque}]")
    ax = panels.pop(0)
    t = sig.index * sig.ts
    ax.plot(t, motor, lw=0.6, label="motor equation")
    if link is not None:
        ax.plot(t, link, lw=0.6, label="link equation")
    chirp = d.log.meta.get("chirp")
    ax.set_title("residual against time" + (f" (chirp {chirp.split(',')[0]}: the frequency "
                                            "rises with time)" if chirp else ""), fontsize=9)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"residual [{torque}]")
    ax.legend()
    for ax in panels:  # what does not apply is left out, not drawn empty
        fig.delaxes(ax)
    fig.tight_layout()
    return _save(fig, path)


def plot_inverse(d: Diagnosis, path: Path) -> Path:
    """The inverse view: measured and predicted motor torque (eq. 6 rows) and the link
    equation's residual (eq. 5 rows), nominal and extended."""
    plt = _pyplot()
    nom, before, after = _residuals(d)
    torque = _units(d)[1]
    t = nom.sig.index * nom.sig.ts
    blocks = np.unique(nom.block)
    fig, axes = plt.subplots(len(blocks), 1, figsize=(10, 3.2 * len(blocks)), squeeze=False)
    for ax, b in zip(axes[:, 0], blocks):
        rows = nom.block == b
        if b == 0:
            ax.plot(t, nom.y[rows], "k", lw=0.8, label="measured tau_m")
            ax.plot(t, nom.y[rows] - before[rows], lw=0.7, label="nominal prediction")
            if after is not None:
                ax.plot(t, nom.y[rows] - after[rows], "--", lw=0.7, label="extended prediction")
            ax.set_title("motor equation (eq. 6): measured and predicted motor torque "
                         "(filtered, decimated)", fontsize=9)
            ax.set_ylabel(f"tau_m [{torque}]")
        else:
            ax.plot(t, before[rows], lw=0.7, label="nominal model")
            if after is not None:
                ax.plot(t, after[rows], lw=0.7, label="extended model")
            ax.set_title("link equation (eq. 5): residual (zero for a perfect model)",
                         fontsize=9)
            ax.set_ylabel(f"residual [{torque}]")
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def _replays(d: Diagnosis):
    return ((d.forward_nominal, "nominal replay"), (d.forward_extended, "extended replay"))


ZOOM_S = 0.5  # half-width of forward.png's zoom window around the largest torque error


def plot_forward(d: Diagnosis, path: Path) -> Path | None:
    """The forward view: per signal, the replay errors over the whole log (left) and the
    measured and replayed signals in a window around the nominal replay's largest torque
    error (right), where a 60 s overlay would hide the difference."""
    if d.forward_nominal is None:
        return None
    plt = _pyplot()
    log = d.log
    pos, torque = _units(d)
    series = [("q_m", pos), ("q", pos), ("tau_m", torque)]
    series = [(name, unit) for name, unit in series if getattr(log, name) is not None]
    f0 = d.forward_nominal
    err0 = f0.tau_m - np.interp(f0.t, log.t, log.tau_m)
    t_peak = float(f0.t[int(np.argmax(np.abs(err0)))])
    lo, hi = t_peak - ZOOM_S, t_peak + ZOOM_S
    win = (log.t >= lo) & (log.t <= hi)
    fig, axes = plt.subplots(len(series), 2, figsize=(12, 2.8 * len(series)), squeeze=False,
                             gridspec_kw={"width_ratios": [3, 2]})
    for (name, unit), (ax, zoom) in zip(series, axes):
        meas = getattr(log, name)
        zoom.plot(log.t[win], meas[win], "k", lw=1.0, label="measured")
        for f, lab in _replays(d):
            sim = None if f is None else getattr(f, name)
            if sim is None:
                continue
            ax.plot(f.t, sim - np.interp(f.t, log.t, meas), lw=0.6, label=lab)
            keep = (f.t >= lo) & (f.t <= hi)
            zoom.plot(f.t[keep], sim[keep], lw=0.8, label=lab)
        ax.axvspan(lo, hi, color="0.85", lw=0)
        ax.set_ylabel(f"{name} error [{unit}]")
        ax.set_title(f"{name}: replay - measured", fontsize=9)
        ax.legend(fontsize=8)
        zoom.set_ylabel(f"{name} [{unit}]")
        zoom.set_title(f"{name} around the largest torque error (t = {t_peak:.2f} s)",
                       fontsize=9)
        zoom.legend(fontsize=8)
    axes[-1, 0].set_xlabel("t [s]")
    axes[-1, 1].set_xlabel("t [s]")
    fig.suptitle("forward view: the logged experiment replayed in closed loop (grey band: "
                 "the zoom window)", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def plot_forward_frf(d: Diagnosis, path: Path) -> Path | None:
    if d.forward_nominal is None:
        return None
    plt = _pyplot()
    log = d.log
    fs = log.sample_rate_hz
    nper = min(len(log), int(2 ** np.floor(np.log2(fs * 8))))
    out = "q" if log.q is not None else "q_m"
    fig, ax = plt.subplots(figsize=(7, 4))

    def frf(y, tau):
        f, sxy = signal.csd(log.q_ref, y, fs=fs, nperseg=nper)
        _, sxt = signal.csd(log.q_ref, tau, fs=fs, nperseg=nper)
        return f, np.abs(sxy / sxt)
    f, h = frf(getattr(log, out), log.tau_m)
    band = (f > 0.2) & (f < min(40, fs / 4))
    ax.loglog(f[band], h[band], "k", label="measured")
    for fv, lab in _replays(d):
        if fv is not None and getattr(fv, out) is not None:
            f2, h2 = frf(getattr(fv, out), fv.tau_m)
            ax.loglog(f2[band], h2[band], lw=0.8, label=lab)
    pos, torque = _units(d)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"|{out} / tau_m| [{pos}/({torque})]")
    ax.set_title(f"forward view: frequency response {out} / tau_m, measured and replayed "
                 "(cross spectra with q_ref)", fontsize=10)
    ax.legend()
    fig.tight_layout()
    return _save(fig, path)
