"""`jointbench demo`: the paper's experiment on the virtual prototype, both identification
models, tables against the paper and the truth, Figures 1 and 2 and the frequency response."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.filter_choice import choose_filter
from jointbench.identification.frequency import FRF, first_mode_hz, measured_frf, model_frf, two_mass_tf
from jointbench.identification.identify import identify
from jointbench.identification.log import atomic_write_text, write_log
from jointbench.identification.paper_tables import (PAPER_TABLE1, PAPER_TABLE2, expected_x, parameter_table,
                                   physical_table)


def _err(v: float, t: float) -> str:
    return f"{100 * (v - t) / abs(t):+.2f} %"


def run_demo(out: Path, duration: float = 60.0, seed: int = 1) -> int:
    import matplotlib
    matplotlib.use("Agg")
    from jointbench.identification.plots import figure1_setup, plot_figure1, plot_frf, plot_validation

    start = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    lines: list[str] = []

    def say(text: str = "") -> None:
        print(text, flush=True)
        lines.append(text)

    say("# jointbench demo: the paper's prototype axis, virtual chirp experiment")
    say()
    res = run_experiment("prototype", duration=duration, seed=seed)
    log, truth = res.log, res.log.truth()
    write_log(log, out / "prototype.csv")
    say(f"Simulated {log.t[-1]:.1f} s at {log.sample_rate_hz:g} Hz (seed {seed}): chirp "
        f"{log.meta['chirp']}; gains kp {log.meta['kp']}, kv {log.meta['kv']}, "
        f"ki {log.meta['ki']}; saturated samples {res.saturated}. "
        f"Log: {out / 'prototype.csv'}")
    choice = choose_filter(log)   # the one chooser: f1 measured, the paper's filter kept
    s, mode = choice.settings, choice.first_mode
    say(f"First mode measured on the log: {mode.f1_hz:.3f} +- {mode.sigma_hz:.2g} Hz "
        f"({mode.method}; truth {truth['f1_hz']:.3f} Hz). Filter (paper section 4): "
        f"Butterworth m = {s.m}, wn = {s.wn:g} rad/s, Nd = {s.Nd} (decimated cutoff "
        f"{s.decimated_cutoff_hz:.2f} Hz = {s.decimated_cutoff_hz / mode.f1_hz:.2f} f1); "
        f"{choice.stencil_reason}")
    say()

    jm = identify(log, "joint-motor", s)
    say(parameter_table(jm, truth, PAPER_TABLE1,
                        "## Table 1: joint-motor model, eq. (13) (both encoders)"))
    say(f"direct validation: relative error {jm.relative_error_pct:.2f} %")
    sc = jm.physical_sigma_corrected
    say("autocorrelation-consistent sigma (identification/uncertainty.py; the paper's assumes "
        "white residuals): " + ", ".join(
            f"{n} {sc[n]:.4g} (x{sc[n] / jm.physical_sigma[n]:.2f}, truth at "
            f"{(jm.physical[n] - truth[n]) / sc[n]:+.2f} sigma)"
            for n in ("K", "Jm", "JL") if n in sc))
    say()

    printed = identify(log, "motor-only-printed", s)
    corrected = identify(log, "motor-only", s)
    xt = expected_x(truth)
    say(parameter_table(printed, xt, PAPER_TABLE2,
                        "## Table 2: motor-only model as printed, eqs. (18)-(20)"))
    say()
    say(parameter_table(corrected, xt, None,
                        "## Table 2 (corrected): + s'', s' (Coulomb term of eq. 14 carried "
                        "through the derivatives) and gravity g cos qm, g sin qm"))
    say()
    say(physical_table(printed, truth, "## Table 3: physical parameters, model as printed"))
    say()
    say(physical_table(corrected, truth, "## Table 3 (corrected): physical parameters with "
                                         "standard deviations (the link reconstructed from "
                                         "q_m, from the weighted NLS on all X)"))
    say()
    say("## Why the corrected motor-only model")
    for name in ("K", "Jm", "JL"):
        p, c = printed.physical.get(name), corrected.physical.get(name)
        say(f"- {name}: as printed {p:.5g} ({_err(p, truth[name])}), corrected {c:.5g} "
            f"({_err(c, truth[name])}), truth {truth[name]:.5g}")
    say("Eq. (18) drops the derivatives of sign(qm'): eq. (14) puts FSm sign(qm') in q, so q' "
        "and q'' carry its band-limited derivatives, large when the motor Coulomb friction is "
        f"large (FSm = {truth['FSm']:.4g} N m here). The printed model also neglects the "
        f"gravity stiffness (g MY = {log.gravity * truth['MY']:.4g} N m/rad against "
        f"K = {truth['K']:.5g}), which scales every X by 1 + G/K.")
    say()
    _bias_correction(log, jm, corrected, truth, say)
    say()

    f1_meas = first_mode_hz(measured_frf(log, output="q"))
    frf = measured_frf(log)
    keep = frf.f_hz <= 25.0  # the chirp stops at 30 Hz: nothing to measure beyond
    frf = FRF(frf.f_hz[keep], frf.H[keep], frf.coherence[keep])
    G = log.gravity * (truth["MY"] * np.cos(res.experiment.center)
                       - truth["MX"] * np.sin(res.experiment.center))
    models = {
        "truth (two-mass model)": model_frf(two_mass_tf(truth["Jm"], truth["K"], truth["JL"],
                                                        truth["FVm"], truth["FV"], G), frf.f_hz),
        "identified, joint-motor": model_frf(two_mass_tf(
            jm.physical["Jm"], jm.physical["K"], jm.physical["JL"], jm.physical["FVm"],
            jm.physical["FV"], G), frf.f_hz),
    }
    plot_frf(frf.f_hz, frf.H, models, frf.coherence, truth["f1_hz"], out / "frequency_response.png",
             title="Prototype axis: q_m / tau_m (closed-loop estimate from q_ref)")
    say(f"Measured frequency response: first mode at {f1_meas:.2f} Hz "
        f"(truth sqrt(K (1/Jm + 1/JL)) / 2 pi = {truth['f1_hz']:.3f} Hz; frequency resolution "
        f"{frf.f_hz[1]:.3f} Hz)")
    fig1 = figure1_setup()
    plot_figure1(fig1.wn, fig1.ts, fig1.m, out / "figure1.png")
    plot_validation(corrected.t[corrected.block == 0], corrected.y, corrected.y_pred,
                    corrected.relative_error_pct, out / "figure2.png",
                    title="Figure 2: direct validation, motor-only model (corrected)")
    plot_validation(jm.t[jm.block == 0], jm.y[jm.block == 0], jm.y_pred[jm.block == 0],
                    jm.relative_error_pct, out / "figure2_joint_motor.png",
                    title="Direct validation, joint-motor model")
    say()
    say(f"Figures: {out / 'figure1.png'}, {out / 'figure2.png'}, "
        f"{out / 'figure2_joint_motor.png'}, {out / 'frequency_response.png'}")
    say()
    _discrepancy_example(out / "discrepancy", duration, seed, say)
    atomic_write_text(out / "report.md", "\n".join(lines) + "\n")
    say(f"Report: {out / 'report.md'}  ({time.perf_counter() - start:.1f} s)")
    return 0


def _bias_correction(log, jm, mo, truth: dict[str, float], say, replicas: int = 8) -> None:
    """Both two-mass estimates bias-corrected by closed-loop replicas (bench/analysis/debias.py,
    `identify --debias`)."""
    from jointbench.bench.analysis.debias import debias
    from jointbench.bench.present.debias import debias_table

    d = debias(log, jm, replicas=replicas)
    say(debias_table(d, truth=truth).replace("## Bias correction", "## Bias correction of "
                                             "Table 1", 1))
    m = debias(log, mo, replicas=replicas)
    say()
    say(f"Motor-only (corrected) model, the same correction ({m.replicas} replicas, "
        f"{m.seconds:.1f} s):")
    for n in ("K", "Jm", "JL"):
        say(f"- {n}: least squares {_err(m.ls[n], truth[n])}, bias-corrected "
            f"{_err(m.estimate[n], truth[n])} (truth at "
            f"{(m.estimate[n] - truth[n]) / m.sigma[n]:+.2f} sigma)")


def _discrepancy_example(out: Path, duration: float, seed: int, say) -> None:
    """One discrepancy example (docs/cli.md): the prototype with backlash hidden; only
    the log goes to diagnose, which must find it, extend the model and measure the gain."""
    import dataclasses

    from jointbench.bench.analysis.diagnose import diagnose, summary_text
    from jointbench.bench.effects import HiddenEffect
    from jointbench.identification.log import write_log

    hidden = HiddenEffect("backlash", 0.002)
    say("Discrepancy example: the same experiment with backlash of half-width 0.002 rad hidden "
        "in the transmission; `jointbench diagnose` gets only the log")
    res = run_experiment("prototype", duration=duration, seed=seed, effect=hidden)
    out.mkdir(parents=True, exist_ok=True)
    write_log(res.log, out / "backlash_log.csv")
    d = diagnose(dataclasses.replace(res.log, path=str(out / "backlash_log.csv")), out_dir=out)
    for line in summary_text(d).splitlines():
        say("  " + line)
    say(f"  (hidden: backlash_rad = {hidden.strength}; report: {out / 'report.md'})")
