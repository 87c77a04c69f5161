"""What `diagnose --out DIR` writes: figures, nominal.xml, extended.xml, report.md, diagnosis.json.
Every file is written atomically (temporary file, then rename)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Callable

import numpy as np
from scipy import signal

from jointbench.bench.analysis.diagnose.run import BLOCK_NAMES, Diagnosis
from jointbench.identification.discrepancy import SIZE_MIN_PCT
from jointbench.identification.effects import EFFECTS
from jointbench.identification.log import atomic_write_text
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
        for f, lab in ((d.forward_nominal, "nominal replay"),
                       (d.forward_extended, "extended replay")):
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
    for fv, lab in ((d.forward_nominal, "nominal replay"), (d.forward_extended, "extended replay")):
        if fv is not None and getattr(fv, out) is not None:
            f2, h2 = frf(getattr(fv, out), fv.tau_m)
            ax.loglog(f2[band], h2[band], lw=0.8, label=lab)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"|{out} / tau_m|")
    ax.set_title("forward view: frequency response", fontsize=10)
    ax.legend()
    fig.tight_layout()
    return save_figure_atomic(fig, path)


def report_markdown(d: Diagnosis, figures: dict[str, str]) -> str:
    inv = d.inverse
    nom = inv.nominal
    L = [f"# Diagnosis of `{d.log.path or 'log'}`", ""]
    L += ["## 1. Nominal model from the data", "",
          f"Filter: Butterworth order {d.settings.m} at wn = {d.settings.wn:.1f} rad/s, "
          f"Nd = {d.settings.Nd} ({d.settings_note}).", "",
          "| parameter | value |", "| --- | --- |"]
    L += [f"| {k} | {v:.6g} |" for k, v in d.nominal_parameters.items()]
    L += ["", "## 2. What the simulation gets wrong", "", "Inverse view (the nominal model's "
          "prediction on the measured motion):", ""]
    for b in np.unique(nom.block):
        L.append(f"- {BLOCK_NAMES[b]}: {nom.relative_error_pct(nom.residual, b):.2f} %")
    if d.forward_nominal is not None:
        f = d.forward_nominal
        L += ["", "Forward view (the experiment replayed in closed loop, CONTRACT section 2):",
              "", f"- torque error: {f.tau_rel_pct:.2f} % RMS",
              f"- motor position error: {f.q_m_rms:.4g} RMS ({f.q_m_rel_pct:.2f} % of its motion)"]
        if f.q_rms is not None:
            L.append(f"- link position error: {f.q_rms:.4g} RMS")
    elif d.forward_note:
        L += ["", f"Forward view: {d.forward_note}"]
    for key in ("structure", "spectrum", "inverse", "forward", "forward_frf"):
        if key in figures:
            L += ["", f"![{key}]({figures[key]})"]
    L += ["", "## 3. The cause", "",
          "Every effect of CONTRACT section 4 added to the nominal model, ranked. Named only "
          "when significant: delta BIC > 10, F-test p < 1e-3, and a practical size (the "
          f"effect moves its equation's prediction by >= {SIZE_MIN_PCT[0]:g} % RMS on the "
          f"motor side, {SIZE_MIN_PCT[1]:g} % on the link side).", "",
          "| effect | significant | explained % | delta BIC | size % | parameters |",
          "| --- | --- | --- | --- | --- | --- |"]
    for c in inv.candidates:
        if c.testable:
            pars = ", ".join(f"{k} = {v:.4g}" for k, v in c.parameters.items())
            if c.unphysical:
                pars += f" (unphysical: {c.unphysical})"
            L.append(f"| {c.effect} | {'yes' if c.significant else 'no'} | "
                     f"{c.explained_pct:.1f} | {c.delta_bic:.1f} | {c.size_pct:.2f} | {pars} |")
        else:
            L.append(f"| {c.effect} | not testable | | | | {c.reason} |")
    L += ["", f"**Named cause: {d.named_cause}**", ""]
    c = d.named
    if c is not None:
        info = EFFECTS[c.effect]
        L += [f"{info.what}; {info.parameter} = {c.parameters[info.parameter]:.5g} {info.unit}.",
              "", "## 4. Extended model", "",
              "`extended.xml` is the nominal axis with the effect added "
              "(`jointbench simulate --model extended.xml` runs it).", ""]
        L += [f"- {k} = {v:.6g}" for k, v in d.extended_parameters.items()]
        before, after = d.inverse_before_after
        L += ["", "## 5. Gain", "", "| view | metric | nominal | extended | gain |",
              "| --- | --- | --- | --- | --- |",
              f"| inverse | {BLOCK_NAMES[d.view_block]} | {before:.2f} | {after:.2f} | "
              f"{before / after:.2f}x |"]
        if d.forward_nominal is not None and d.forward_extended is not None:
            a, b = d.forward_nominal, d.forward_extended
            L.append(f"| forward | torque error, % RMS | {a.tau_rel_pct:.2f} | "
                     f"{b.tau_rel_pct:.2f} | {a.tau_rel_pct / b.tau_rel_pct:.2f}x |")
            L.append(f"| forward | motor position error, RMS | {a.q_m_rms:.4g} | "
                     f"{b.q_m_rms:.4g} | {a.q_m_rms / b.q_m_rms:.2f}x |")
            if a.q_rms is not None and b.q_rms is not None:
                L.append(f"| forward | link position error, RMS | {a.q_rms:.4g} | "
                         f"{b.q_rms:.4g} | {a.q_rms / b.q_rms:.2f}x |")
    else:
        L += ["No effect is significant: the nominal model explains this log. No extended "
              "model is written."]
    return "\n".join(L) + "\n"


def write(d: Diagnosis, out: Path, say: Callable[[str], None]) -> Diagnosis:
    out.mkdir(parents=True, exist_ok=True)
    say(f"figures and report in {out}")
    figures: dict[str, str] = {}
    for key, fn in (("structure", plot_structure), ("spectrum", plot_spectrum),
                    ("inverse", plot_inverse), ("forward", plot_forward),
                    ("forward_frf", plot_forward_frf)):
        p = fn(d, out / f"{key}.png")
        if p is not None:
            figures[key] = Path(p).name
    files = [str(out / f) for f in figures.values()]
    from jointbench.bench.analysis.diagnose import forward as diagnose_forward
    files += [str(p) for p in diagnose_forward.write_models(d, out)]
    atomic_write_text(out / "report.md", report_markdown(d, figures))
    files.append(str(out / "report.md"))
    d = dataclasses.replace(d, files=tuple(files + [str(out / "diagnosis.json")]))
    atomic_write_text(out / "diagnosis.json", json.dumps(d.to_json(), indent=2) + "\n")
    return d
