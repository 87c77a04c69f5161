"""The figures of `diagnose --out DIR`: where the nominal residual lives, its spectrum, the
inverse view's predictions and the forward view's replays (atomic writes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy import signal

from jointbench.bench.analysis.diagnose.types import BLOCK_NAMES, Diagnosis
from jointbench.identification.plots import save_figure_atomic


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _residuals(d: Diagnosis):
    nom = d.inverse.nominal
    before = nom.residual
    c = d.named
    after = None
    if c is not None:
        after = c.residual
    return nom, before, after


def plot_spectrum(d: Diagnosis, path: Path) -> Path:
    plt = _pyplot()
    nom, before, after = _residuals(d)
    fs = 1.0 / (nom.sig.ts * nom.sig.settings.Nd)
    blocks = np.unique(nom.block)
    fig, axes = plt.subplots(len(blocks), 1, figsize=(7, 3 * len(blocks)), squeeze=False)
    for ax, b in zip(axes[:, 0], blocks):
        rows = nom.block == b
        for res, label in ((before, "nominal"), (after, "extended")):
            if res is None:
                continue
            f, p = signal.welch(res[rows], fs=fs, nperseg=min(256, rows.sum()))
            ax.semilogy(f, p, label=label)
        ax.set_title(BLOCK_NAMES[b].split(":")[0] + ": residual spectrum", fontsize=9)
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("PSD")
        ax.legend()
    fig.tight_layout()
    return save_figure_atomic(fig, path)


def plot_structure(d: Diagnosis, path: Path) -> Path:
    """Where the nominal residual lives: against velocity sign, deflection, motor angle and
    the chirp's frequency (time)."""
    plt = _pyplot()
    nom = d.inverse.nominal
    sig = nom.sig
    res = nom.residual
    n = len(sig.index)
    motor = res[:n]
    link = res[n:] if sig.has_link else None
    qmd = sig.dec(np.nan_to_num(sig.qmd))
    qm = sig.dec(sig.qm)
    t = sig.index * sig.ts
    fig, axes = plt.subplots(2, 2, figsize=(10, 7))
    ax = axes[0, 0]
    s = np.sign(qmd)
    for k, lab in ((-1, "qm' < 0"), (1, "qm' > 0")):
        ax.hist(motor[s == k], bins=40, alpha=0.6, label=lab)
    ax.set_title("motor residual against velocity sign", fontsize=9)
    ax.set_xlabel("residual [N m]")
    ax.legend()
    ax = axes[0, 1]
    if link is not None:
        defl = sig.dec(sig.qm - sig.q)
        ax.plot(defl, link, ".", ms=2)
        ax.set_title("link residual against deflection qm - q", fontsize=9)
        ax.set_xlabel("qm - q [rad]")
    else:
        ax.text(0.5, 0.5, "no link position q:\ndeflection not observable", ha="center",
                va="center", transform=ax.transAxes)
    ax = axes[1, 0]
    ax.plot(qm, motor, ".", ms=2)
    ax.set_title("motor residual against motor angle", fontsize=9)
    ax.set_xlabel("qm")
    ax = axes[1, 1]
    ax.plot(t, motor, lw=0.6, label="motor")
    if link is not None:
        ax.plot(t, link, lw=0.6, label="link")
    ax.set_title("residual against time (the chirp's frequency rises with time)", fontsize=9)
    ax.set_xlabel("t [s]")
    ax.legend()
    fig.tight_layout()
    return save_figure_atomic(fig, path)


def plot_inverse(d: Diagnosis, path: Path) -> Path:
    plt = _pyplot()
    nom, before, after = _residuals(d)
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
        else:
            ax.plot(t, before[rows], lw=0.7, label="link residual, nominal")
            if after is not None:
                ax.plot(t, after[rows], lw=0.7, label="link residual, extended")
        ax.set_title(BLOCK_NAMES[b], fontsize=9)
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure_atomic(fig, path)


def _replays(d: Diagnosis):
    return ((d.forward_nominal, "nominal replay"), (d.forward_extended, "extended replay"))


def plot_forward(d: Diagnosis, path: Path) -> Path | None:
    if d.forward_nominal is None:
        return None
    plt = _pyplot()
    log = d.log
    rows = 3 if log.q is not None else 2
    fig, axes = plt.subplots(rows, 1, figsize=(10, 2.8 * rows), sharex=True)
    series = [("q_m", log.q_m, "q_m"), ("tau_m", log.tau_m, "tau_m")]
    if log.q is not None:
        series.insert(1, ("q", log.q, "q"))
    for ax, (name, meas, attr) in zip(axes, series):
        ax.plot(log.t, meas, "k", lw=0.8, label="measured")
        for f, lab in _replays(d):
            if f is not None and getattr(f, attr) is not None:
                ax.plot(f.t, getattr(f, attr), lw=0.6, label=lab)
        ax.set_ylabel(name)
        ax.legend(fontsize=8)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle("forward view: the logged experiment replayed in closed loop", fontsize=10)
    fig.tight_layout()
    return save_figure_atomic(fig, path)


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
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"|{out} / tau_m|")
    ax.set_title("forward view: frequency response", fontsize=10)
    ax.legend()
    fig.tight_layout()
    return save_figure_atomic(fig, path)
