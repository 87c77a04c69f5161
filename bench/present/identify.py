"""An identification (least squares, optionally refined and bias-corrected) as text and as
the `identify --json` object of docs/cli.md: what `jointbench identify` prints."""

from __future__ import annotations

from jointbench.bench.analysis.debias import DebiasResult
from jointbench.bench.analysis.refine import RefineResult
from jointbench.bench.present.debias import debias_table, debiased_json
from jointbench.bench.present.refine import refined_json, refinement_table
from jointbench.identification.identify import Identification
from jointbench.identification.log import Log
from jointbench.identification.parameters import STIFFNESS_AND_INERTIAS
from jointbench.identification.paper_tables import parameter_table, physical_table, to_json


def identify_json(result: Identification, truth: dict[str, float] | None, flags: list[dict],
                  warnings: list[str], refined: RefineResult | None = None,
                  debiased: DebiasResult | None = None) -> dict:
    """The `identify --json` object: `identification.paper_tables.to_json` with the estimate flags,
    the log's unit warnings and, when run, the "refined" and "debiased" objects."""
    answer = to_json(result, truth)
    answer["flags"] = flags
    answer["warnings"] = list(warnings) + [w for w in result.warnings if w not in warnings]
    if result.band is not None:   # the joint-motor band picked by its precision (band_choice)
        answer["band"] = result.band.to_json()
    if refined is not None:
        answer["refined"] = refined_json(refined, result, truth)
    if debiased is not None:
        answer["debiased"] = debiased_json(debiased, truth)
    return answer


def _filter_chain(source: str, log: Log, result: Identification) -> list[str]:
    """The first lines: `source` (the file name), the Butterworth and decimation of `result`,
    which band and why (`band_choice`, joint-motor with defaults) and the identification
    chain's departures from the paper's (eq. 22, ZOH alignment, torque filter)."""
    s = result.settings
    lines = [f"{source}: model {result.model}, {len(log)} samples at "
             f"{log.sample_rate_hz:g} Hz; filter wn = {s.wn:g} rad/s (order {s.m}), Nd = {s.Nd} "
             f"(decimated cutoff {s.decimated_cutoff_hz:.2f} Hz); {result.ls.r} equations, "
             f"condition number {result.ls.cond:.3g}"]
    chain = [text for on, text in ((not s.zoh, "torque not ZOH-aligned"),
                                   (not s.filter_torque, "torque not Butterworth-filtered"),
                                   (s.skip, f"first {s.skip} samples dropped"),
                                   (s.stencil != 3, f"{s.stencil}-point central differences"))
             if on]
    if result.band is not None:
        lines.append(f"band: {result.band.reason}")
    lines.append("corrections beyond the paper: " + (", ".join(result.corrections)
                                                     or "none (the paper's chain)"))
    if log.prismatic or chain:
        lines.append("; ".join((["prismatic axis: positions in m, forces in N, masses in kg"]
                                if log.prismatic else []) + chain))
    return lines


def identify_text(source: str, log: Log, result: Identification,
                  truth: dict[str, float] | None, flags: list[dict],
                  refined: RefineResult | None = None,
                  debiased: DebiasResult | None = None) -> str:
    """The identification of `log` (read from `source`) as text: the filter, the parameter
    table (and the physical one for motor-only), the direct validation, the corrected
    2 sigma, notes, flags and, when run, the refinement and bias-correction tables."""
    lines = _filter_chain(source, log, result)
    lines += ["", parameter_table(result, truth)]
    if result.model.startswith("motor-only"):
        lines += ["", physical_table(result, truth, "Physical parameters")]
    lines += ["", f"direct validation: relative error {result.relative_error_pct:.2f} %, "
                  f"residual rms {result.ls.rms:.4g} {'N' if log.prismatic else 'N m'}"]
    sc = result.physical_sigma_corrected
    if sc:
        lines.append("2 sigma, autocorrelation-consistent (the paper's assumes white "
                     "residuals): " + ", ".join(f"{n} {2 * sc[n]:.4g}"
                                                for n in (*STIFFNESS_AND_INERTIAS, "J")
                                                if n in sc))
    lines += [f"note: {note}" for note in result.notes]
    lines += [f"flag: {flag['message']}" for flag in flags]
    if refined is not None:
        lines += ["", refinement_table(refined, result, truth)]
    if debiased is not None:
        lines += ["", debias_table(debiased, log.prismatic, truth)]
    return "\n".join(lines)
