"""What `diagnose` prints and writes: the summary text, the JSON answer, and with --out DIR the
figures, nominal.xml, extended.xml, report.md and diagnosis.json. The folder is written all
or nothing, never over a file that is not ours (bench.output_files.OutputFolder), every file
atomically (temporary file, then rename)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Callable

import numpy as np

from jointbench.bench.analysis.diagnose.figures import (plot_forward, plot_forward_frf,
                                                        plot_inverse, plot_spectrum,
                                                        plot_structure)
from jointbench.bench.analysis.diagnose.forward import write_models
from jointbench.bench.analysis.diagnose.types import BLOCK_NAMES, Diagnosis
from jointbench.bench.effects import axis_keys
from jointbench.bench.output_files import OutputFolder
from jointbench.identification.discrepancy import ALPHA, FOLDS, MATERIAL, SEGMENTS
from jointbench.identification.effects import EFFECTS
from jointbench.identification.log import atomic_write_text
from jointbench.identification.output_values import finite_json


def report_markdown(d: Diagnosis, figures: dict[str, str],
                    models: tuple[str, ...] | None = None,
                    model_notes: tuple[str, ...] = ()) -> str:
    """report.md. `models`: the MJCF files written beside it (None: as if all were); the
    report names only those, and says why another was not written (`model_notes`)."""
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
        L += ["", "Forward view (the experiment replayed in closed loop, docs/controller.md):",
              "", f"- torque error: {f.tau_rel_pct:.2f} % RMS",
              f"- motor position error: {f.q_m_rms:.4g} RMS ({f.q_m_rel_pct:.2f} % of its motion)"]
        if f.q_rms is not None:
            L.append(f"- link position error: {f.q_rms:.4g} RMS")
    if d.forward_note:
        L += ["", f"Forward view: {d.forward_note}"]
    for key in ("structure", "spectrum", "inverse", "forward", "forward_frf"):
        if key in figures:
            L += ["", f"![{key}]({figures[key]})"]
    L += ["", "## 3. The cause", "", RULE, "",
          "| effect | significant | held-out % | t | explained % | delta BIC | size % | "
          "parameters |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for c in inv.candidates:
        if c.testable:
            pars = ", ".join(f"{k} = {v:.4g}" for k, v in
                             axis_keys(c.parameters, d.log.prismatic).items())
            if c.unphysical:
                pars += f" (unphysical: {c.unphysical})"
            L.append(f"| {c.effect} | {'yes' if c.significant else 'no'} | "
                     f"{c.heldout_pct:.1f} | {c.t_stat:.2f} | {c.explained_pct:.1f} | "
                     f"{c.delta_bic:.1f} | {c.size_pct:.2f} | {pars} |")
        else:
            L.append(f"| {c.effect} | not testable | | | | | | {c.reason} |")
    L += ["", f"**Named cause: {d.named_cause}** (verdict: {d.verdict})", ""]
    L += _causes_lines(d)
    L += [f"Ambiguity: {a}.\n" for a in d.ambiguities]
    not_named = _not_named_lines(d, "Considered and not named:", "- ")
    L += not_named[:1] + [""] + not_named[1:] + [""] if not_named else []
    if d.inverse.stopped:
        L += [f"The rounds stopped at {d.inverse.stopped}.", ""]
    if d.reason:
        L += [f"Why: {d.reason}.", ""]
    if d.clipped is not None and d.clipped.text() not in d.reason:
        L += [f"Clipped torque: {d.clipped.text()}.", ""]
    L += [f"Warning: {w}" for w in d.warnings] + ([""] if d.warnings else [])
    c = d.named
    if c is not None:
        info = EFFECTS[c.effect]
        L += [f"{info.what}; {info.parameter} = {c.parameters[info.parameter]:.5g} {info.unit}.",
              "", "## 4. Extended model", "",
              ("`extended.xml` is the nominal axis with the effect added "
               "(`jointbench simulate --model extended.xml` runs it)."
               if models is None or "extended.xml" in models else
               "No `extended.xml` is written (MuJoCo cannot build it, below)."), ""]
        L += [f"- {k} = {v:.6g}" for k, v in
              axis_keys(d.extended_parameters, d.log.prismatic).items()]
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
    elif d.overruled:
        L += ["The answer is inconclusive: no extended model is written."]
    else:
        L += ["No effect is significant: the nominal model explains this log. No extended "
              "model is written."]
    if model_notes:
        L += ["", "## Models not written", ""] + [f"- {n}" for n in model_notes]
    return "\n".join(L) + "\n"


def _one_of(d: Diagnosis, c) -> str:
    """A named cause as the claim it is: "one of A or B (held out A explains x %, B y %)"
    where the log cannot tell B from it (Diagnosis.alternatives_of), else its name."""
    alts = d.alternatives_of(c.effect)
    if not alts:
        return c.effect
    names = " or ".join([c.effect, *(a.other for a in alts)])
    shares = ", ".join([f"{c.effect} {alts[0].named_pct:.3g} %",
                        *(f"{a.other} {a.other_pct:.3g} %" for a in alts)])
    return f"one of {names} (held out {shares} of the residual)"


def _causes_lines(d: Diagnosis) -> list[str]:
    """Every named cause with the test it is named on (at the level of the round it
    entered) and its own gain."""
    if not d.causes:
        return []
    L = ["Named causes, in order (each tested against the nominal extended by the ones "
         "before it):", ""]
    for c in d.causes:
        pars = ", ".join(f"{k} = {v:.4g}" for k, v in c.parameters.items())
        # the test that passed: its own band's, or the second band's that confirmed it
        L.append(f"- {_one_of(d, c)}: {pars}; its test, round {c.round}, "
                 f"{c.test.describe()}; {BLOCK_NAMES[c.block].split(':')[0]} "
                 f"{c.before_pct:.3g} % -> {c.after_pct:.3g} % ({c.gain:.2f}x)")
    return L + [""]


def _not_named_lines(d: Diagnosis, head: str, indent: str) -> list[str]:
    """Every effect considered and not named, with why (inverse.NotNamed)."""
    rows = [n for n in d.not_named if n.kind != "untestable"]
    if not rows:
        return []
    return [head] + [f"{indent}{n.effect} ({n.kind.replace('_', ' ')}): {n.why}" for n in rows]


RULE = ("Every effect of docs/effects.md added to the nominal model and fitted on all rows but "
        f"one of {FOLDS} folds (each made of contiguous segments spread over the experiment), "
        "which it then predicts. An effect is significant when, segment by segment, its "
        f"held-out errors are smaller than the nominal's by more than {100 * MATERIAL:g} % "
        f"(t of the log-ratios over {SEGMENTS} segments, their spread from successive "
        f"differences, one-sided, at {ALPHA:g} divided by the number of effects the round "
        "tests: Holm's step-down Bonferroni), it removes a positive share of the whole "
        "held-out residual, and its fit is physical. The named cause "
        "is the significant one that explains the most of the held-out residual; the others "
        "are then tested again on top of it, and a later one is named only when it also "
        f"explains more than {100 * MATERIAL:g} % of the held-out residual (the floor). With "
        "more than two causes each must pass again against the model holding all the "
        "others. Every named cause carries the test it is named on. Delta BIC and size are "
        "information.")


FIGURES = ("structure", "spectrum", "inverse", "forward", "forward_frf")
# Every file `diagnose --out DIR` may write (bench.output_files.OutputFolder refuses to replace one
# that is not ours, and removes ours that a new run does not write again).
FILES = tuple(f"{k}.png" for k in FIGURES) + ("nominal.xml", "extended.xml", "report.md",
                                                "diagnosis.json", "cross_validation.json")


def output_folder(out: Path) -> OutputFolder:
    """The checked output folder of `diagnose --out` (OutputError before any computation)."""
    return OutputFolder(out, FILES)


def write(d: Diagnosis, out: Path, say: Callable[[str], None],
          extra: dict[str, str] | None = None) -> Diagnosis:
    """Write the figures, models, report.md, diagnosis.json and the `extra` files (name ->
    text) into `out`, all or nothing (bench.output_files.OutputFolder)."""
    say(f"figures and report in {out}")
    with output_folder(out).writing() as folder:
        figures: dict[str, str] = {}
        for key, fn in zip(FIGURES, (plot_structure, plot_spectrum, plot_inverse, plot_forward,
                                     plot_forward_frf)):
            p = fn(d, folder / f"{key}.png")
            if p is not None:
                figures[key] = Path(p).name
        files = [str(out / f) for f in figures.values()]
        failures: list[str] = []
        models = tuple(Path(p).name for p in write_models(d, folder, failures))
        files += [str(out / m) for m in models]
        atomic_write_text(folder / "report.md",
                          report_markdown(d, figures, models, tuple(failures)))
        files.append(str(out / "report.md"))
        for name, text in (extra or {}).items():
            atomic_write_text(folder / name, text)
            files.append(str(out / name))
        d = dataclasses.replace(d, files=tuple(files + [str(out / "diagnosis.json")]))
        atomic_write_text(folder / "diagnosis.json", dumps(d) + "\n")
    return d


def dumps(d: Diagnosis) -> str:
    """The JSON answer, strict (NaN and infinities as null)."""
    return json.dumps(finite_json(d.to_json()), indent=2, allow_nan=False)


def _controller(log) -> str:
    """The controller the replay ran (docs/controller.md), in words."""
    from jointbench.bench.sim.controller import controller_from_log, describe

    try:
        return describe(controller_from_log(log))
    except ValueError:
        return "controller"


def summary_text(d: Diagnosis) -> str:
    """What `jointbench diagnose` prints: the ranking, the named cause and the gain."""
    inv = d.inverse
    nom = inv.nominal
    L = [f"filter: wn = {d.settings.wn:.1f} rad/s, Nd = {d.settings.Nd} ({d.settings_note})",
         "nominal model: " + ", ".join(f"{k} = {v:.5g}" for k, v in d.nominal_parameters.items()),
         "inverse view, nominal: " + "; ".join(
             f"{BLOCK_NAMES[b].split(':')[0]} {nom.relative_error_pct(nom.residual, b):.2f} %"
             for b in np.unique(nom.block))]
    if d.forward_nominal is not None:
        f = d.forward_nominal
        L.append(f"forward view, nominal: torque {f.tau_rel_pct:.2f} % RMS, q_m {f.q_m_rms:.3g} "
                 "RMS" + (f", q {f.q_rms:.3g} RMS" if f.q_rms is not None else "")
                 + f" (closed-loop replay under the log's {_controller(d.log)})")
    if d.forward_note:
        L.append(f"forward view: {d.forward_note}")
    L += ["", f"{'effect':20s} {'signif.':>7s} {'held-out %':>10s} {'t':>7s} "
              f"{'explained %':>11s} {'delta BIC':>10s} {'size %':>7s}  parameters"]
    for c in inv.candidates:
        if not c.testable:
            L.append(f"{c.effect:20s} {'-':>7s}  not testable: {c.reason}")
            continue
        pars = ", ".join(f"{k} = {v:.4g}" for k, v in
                         axis_keys(c.parameters, d.log.prismatic).items())
        if c.unphysical:
            pars += " (unphysical)"
        L.append(f"{c.effect:20s} {'yes' if c.significant else 'no':>7s} "
                 f"{c.heldout_pct:10.1f} {c.t_stat:7.2f} {c.explained_pct:11.1f} "
                 f"{c.delta_bic:10.1f} {c.size_pct:7.2f}  {pars}")
    L += [f"second view of {c.effect}: {c.second_note}" for c in d.inverse.candidates
          if c.second is not None]
    L += ["", f"named cause: {d.named_cause}" + (" (inconclusive)" if d.overruled else "")]
    if len(d.causes) > 1:
        L += [f"named causes: {', '.join(c.effect for c in d.causes)}"]
    L += [f"  {_one_of(d, c)}: {BLOCK_NAMES[c.block].split(':')[0]} {c.before_pct:.3g} % -> "
          f"{c.after_pct:.3g} % ({c.gain:.2f}x); its test, round {c.round}, "
          f"{c.test.describe()}" for c in d.causes]
    L += [f"ambiguity: {a}" for a in d.ambiguities]
    L += _not_named_lines(d, "considered, not named:", "  ")
    if d.inverse.stopped and d.inverse.causes:
        L.append(f"rounds stopped: {d.inverse.stopped}")
    if d.reason:
        L.append(f"why: {d.reason}")
    if d.clipped is not None and d.clipped.text() not in d.reason:
        L.append(f"clipped torque: {d.clipped.text()}")
    if d.named is not None:
        info = EFFECTS[d.named_cause]
        before, after = d.inverse_before_after
        L.append(f"{info.parameter} = {d.extended_parameters[info.parameter]:.5g} "
                 f"{info.unit_for(d.log.prismatic)}")
        L.append(f"gain, inverse view ({BLOCK_NAMES[d.view_block].split(':')[0]}): "
                 f"{before:.2f} % -> {after:.2f} % ({before / after:.2f}x)")
        if d.forward_nominal is not None and d.forward_extended is not None:
            a, b = d.forward_nominal, d.forward_extended
            L.append(f"gain, forward view: torque {a.tau_rel_pct:.2f} % -> {b.tau_rel_pct:.2f} %, "
                     f"q_m {a.q_m_rms:.3g} -> {b.q_m_rms:.3g}"
                     + (f", q {a.q_rms:.3g} -> {b.q_rms:.3g}" if a.q_rms is not None
                        and b.q_rms is not None else ""))
    if d.files:
        L.append("wrote: " + ", ".join(Path(f).name for f in d.files))
    return "\n".join(L)
