"""What `jointbench diagnose LOG --model ROBOT.xml` prints and writes: the parameter errors,
the named causes, the forward gain (and its cross-validation), the JSON answer of docs/cli.md
(`parameter_errors` added), and with --out DIR: corrected.xml, extended.xml, report.md and
diagnosis.json, all or nothing (bench.output_files.OutputFolder), each atomically."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Callable

from jointbench.bench.analysis.diagnose.against_model import (FLOOR_PCT, MODELS, SIGMAS,
                                                              ModelDiagnosis, ParameterError)
from jointbench.bench.analysis.diagnose.model_precision import CONFIDENCE, POINTS, describe
from jointbench.bench.effects import axis_keys
from jointbench.bench.output_files import OutputFolder
from jointbench.identification.log import atomic_write_text
from jointbench.identification.output_values import finite_json
from jointbench.identification.parameters import units

FILES = ("corrected.xml", "extended.xml", "report.md", "diagnosis.json")
RULE = (f"significant: |model - data| > {SIGMAS:g} corrected sigma of the log's "
        f"identification AND |error| > {FLOOR_PCT:g} % of the data's value (MX, MY: of the "
        "gravity moment sqrt(MX^2 + MY^2)); a significant one's data value is then refitted "
        f"with the parameters within {SIGMAS:g} sigma of the data held at the model's")


def output_folder(out: Path) -> OutputFolder:
    """The checked output folder of `diagnose --model ... --out` (before any computation)."""
    return OutputFolder(out, FILES)


def _views_json(views: dict[str, dict]) -> dict:
    keep = ("torque_rel_pct", "torque_rms", "position_rms", "position_rel_pct",
            "link_position_rms", "torque_noise_std", "error")
    return {label: {k: v[k] for k in keep if k in v} for label, v in views.items()}


def to_json(md: ModelDiagnosis) -> dict:
    """The JSON answer (docs/cli.md, `diagnose --model`)."""
    prismatic = md.log.prismatic
    out = {
        "named_cause": md.named_cause,
        "named_causes": list(md.named_causes),
        "model": str(md.source), "joint": md.joint, "config": md.config,
        "parameter_errors": {n: e.to_json() for n, e in md.errors.items()},
        "wrong_parameters": list(md.wrong_parameters),
        "rule": RULE,
        "precision": {"points": POINTS, "confidence": CONFIDENCE,
                      "log_duration_s": len(md.log) * md.log.ts,
                      "coarse": {n: c.to_json() for n, c in md.coarse.items()}},
        "units": {n: u for n, u in units(prismatic).items() if n in md.errors},
        "corrected_parameters": md.corrected.values,
        "extended_effects": [{"effect": n, "parameters": axis_keys(p, prismatic)}
                             for n, p in md.effects],
    }
    d = md.log_diagnosis
    if d is not None:
        log_json = d.to_json()
        out["candidates"] = log_json["candidates"]
        # the structural causes' tests (the log's own diagnosis, identification.discrepancy)
        out["causes"] = log_json["causes"]
        out["floor_pct"] = log_json["floor_pct"]
    if md.forward:
        out["forward"] = _views_json(md.forward)
        out["gain"] = md.gain()
    if md.validation:
        out["cross_validation"] = {"file": md.validate_path,
                                   "forward": _views_json(md.validation),
                                   "gain": md.gain(md.validation)}
    out["notes"] = list(md.notes)
    if md.files:
        out["files"] = list(md.files)
    return finite_json(out)


def _error_lines(md: ModelDiagnosis) -> list[str]:
    u = units(md.log.prismatic)
    L = [f"{'parameter':9s} {'model':>12s} {'data':>12s} {'sigma':>10s} {'error %':>8s}  "
         "significant"]
    for n, e in md.errors.items():
        refit = (f"  (refitted; identified {e.identified:.5g})"
                 if math.isfinite(e.identified) else "")
        L.append(f"{n:9s} {e.model:12.5g} {e.data:12.5g} {e.sigma:10.3g} {e.error_pct:8.2f}  "
                 f"{'yes' if e.significant else 'no'}  [{u.get(n, '')}]{refit}")
    return L


def _unit(md: ModelDiagnosis) -> str:
    return "N" if md.log.prismatic else "N m"


def _gain_lines(label: str, g: dict, unit: str = "N m") -> list[str]:
    if "model" not in g:
        return []
    parts = [f"model {g['model']:.2f} %"]
    for key in ("corrected", "extended"):
        if key in g:
            parts.append(f"{key} {g[key]:.2f} % ({g.get(f'ratio_{key}', float('nan')):.2f}x)")
    L = [f"{label}: torque error " + ", ".join(parts)]
    if "floor" in g:
        over = ", ".join(f"{key} {g[f'excess_{key}']:.2f} %" for key in MODELS
                         if f"excess_{key}" in g)
        L.append(f"  replay noise floor {g['floor']:.2f} % (the log's torque noise, "
                 f"{g['noise_std']:.3g} {unit}, replayed on the corrected model); excess over "
                 f"it: {over}; the largest gain a perfect model could show: "
                 f"{g['ratio_ceiling']:.2f}x")
    return L


def _wrong(e: ParameterError) -> str:
    """"K +23.0 +- 0.2 %": the error and the sigma the log's value carries into it."""
    sd = f" +- {e.error_sigma_pct:.1f}" if math.isfinite(e.error_sigma_pct) else ""
    return f"{e.name} {e.error_pct:+.1f}{sd} %"


def summary_text(md: ModelDiagnosis) -> str:
    """What `jointbench diagnose LOG --model ROBOT.xml` prints."""
    L = [f"model: {md.source} axis {md.joint}"
         + (f" (config {', '.join(f'{k}={v:g}' for k, v in md.config.items())})"
            if md.config else ""),
         f"data: {md.log.path or 'log'} ({md.identification.model} identification)", ""]
    L += _error_lines(md)
    L += [f"({RULE})", "",
          "wrong parameters: " + (", ".join(_wrong(md.errors[n]) for n in md.wrong_parameters)
                                  or "none"),
          describe(md.coarse),
          "named causes: " + (", ".join(md.named_causes) or "none")]
    L += [f"note: {n}" for n in md.notes]
    for label, views in (("forward view", md.forward), ("cross-validation", md.validation)):
        for name, v in views.items():
            if "error" in v:
                L.append(f"{label}: {name} not replayed: {v['error']}")
        L += _gain_lines(label + (f" on {md.validate_path}" if label != "forward view" else ""),
                         md.gain(views), _unit(md))
    if md.files:
        L.append("wrote: " + ", ".join(Path(f).name for f in md.files))
    return "\n".join(L)


def _bullet(line: str) -> str:
    """A text line as a markdown list item; an indented one (the noise floor) nested."""
    return f"  - {line.strip()}" if line.startswith(" ") else f"- {line}"


def report_markdown(md: ModelDiagnosis) -> str:
    """DIR/report.md."""
    L = [f"# Diagnosis of `{md.log.path or 'log'}` against `{md.source}`", "",
         f"Axis `{md.joint}`. The MJCF is the nominal; the data's values come from the log's "
         f"{md.identification.model} identification (eq. 13) with the autocorrelation-"
         "corrected sigma.", "", "## 1. Parameters", "", "```"]
    L += _error_lines(md) + ["```", "", RULE + ".", "", "## 2. Causes", ""]
    L += [f"- wrong parameter {n}: model {md.errors[n].model:.5g}, data "
          f"{md.errors[n].data:.5g} ({_wrong(md.errors[n])[len(n) + 1:]})"
          for n in md.wrong_parameters]
    L += [f"- effect {n}" for n in md.named_causes] or ["- no structural effect"]
    L += [f"- {describe(md.coarse)}"]
    L += [f"- note: {n}" for n in md.notes]
    L += ["", "## 3. Models", "",
          "`corrected.xml`: the MJCF with the wrong parameters set to the data's values "
          "(everything else kept). " + ("`extended.xml`: corrected plus "
                                        f"{', '.join(n for n, _ in md.effects)}."
                                        if md.effects else "No structural effect to add."),
          "", "## 4. Gain (closed-loop replay of the logged experiment)", ""]
    L += [_bullet(line) for line in _gain_lines("this log", md.gain(), _unit(md))]
    if md.validation:
        L += [_bullet(line) for line in _gain_lines(f"{md.validate_path}",
                                                    md.gain(md.validation), _unit(md))]
    return "\n".join(L) + "\n"


def write(md: ModelDiagnosis, out: Path, say: Callable[[str], None]) -> ModelDiagnosis:
    """corrected.xml, extended.xml (when effects are named), report.md, diagnosis.json."""
    say(f"models and report in {out}")
    with output_folder(out).writing() as folder:
        files = []
        for name, text in md.xml.items():
            atomic_write_text(folder / name, text)
            files.append(str(out / name))
        atomic_write_text(folder / "report.md", report_markdown(md))
        files += [str(out / "report.md"), str(out / "diagnosis.json")]
        md = dataclasses.replace(md, files=tuple(files))
        atomic_write_text(folder / "diagnosis.json",
                          json.dumps(to_json(md), indent=2, allow_nan=False) + "\n")
    return md
