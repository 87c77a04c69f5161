"""The closed-loop output-error refinement (`bench.analysis.refine`) as JSON and text:
what `jointbench identify --refine [--json]` prints after the least-squares answer."""

from __future__ import annotations

import math

from jointbench.bench.analysis.refine import ALL_PARAMETERS, RefineResult
from jointbench.identification.identify import Identification
from jointbench.identification.output_values import pct_error
from jointbench.identification.parameters import STIFFNESS_AND_INERTIAS, units
from jointbench.identification.paper_tables import cell as num


def refined_json(res: RefineResult, ident: Identification,
                 truth: dict[str, float] | None = None) -> dict:
    """The "refined" object of `identify --refine --json`: `RefineResult.to_json`, each
    parameter's least-squares value ("ls", null when least squares does not give it), and
    with a virtual log's truth "truth" and "error_pct" {"ls": ..., "refined": ...}."""
    out = res.to_json()
    for n, entry in out["parameters"].items():
        v = ident.physical.get(n)
        entry["ls"] = float(v) if v is not None and math.isfinite(v) else None
    truth = {n: v for n, v in (truth or {}).items() if n in res.parameters and v}
    if truth:
        out["truth"] = truth
        out["error_pct"] = {
            "ls": {n: pct_error(out["parameters"][n]["ls"], v) for n, v in truth.items()
                   if n in out["parameters"] and out["parameters"][n]["ls"] is not None},
            "refined": {n: pct_error(res.parameters[n], v) for n, v in truth.items()}}
    return out


def refinement_table(res: RefineResult, ident: Identification,
                     truth: dict[str, float] | None = None) -> str:
    """The refinement as text (what `jointbench identify --refine` prints after the LS
    tables): parameter, LS value, refined value, 2 sigma (white residuals) and, with truth,
    the LS and refined errors."""
    unit = units(ident.prismatic)
    truth = {n: v for n, v in (truth or {}).items() if n in res.parameters and v}
    outs = " and ".join(res.outputs)
    lines = [f"## Refinement (closed-loop output error, DIDIM-style): {len(res.free)} "
             f"parameters fitted to {outs} over {res.forward_after['samples']} samples;"
             f" {res.iterations} iterations, {res.replays} replays, {res.wall_s:.1f} s"]
    head = f"{'Parameter':<10}{'LS':>12}{'refined':>12}{'2 sigma':>12}"
    if truth:
        head += f"{'truth':>12}{'LS err %':>10}{'error %':>10}"
    head += "  unit"
    lines += [head, "-" * len(head)]

    for n in ALL_PARAMETERS:
        ls = ident.physical.get(n)
        fitted = n in res.free
        row = f"{n:<10}{num(ls)}{num(res.parameters[n])}"
        row += num(2 * res.sigma[n]) if fitted else f"{'fixed':>12}"
        if truth:
            tv = truth.get(n)
            row += num(tv)
            row += num(pct_error(ls, tv) if tv and ls is not None else None, 10, ".3f")
            row += num(pct_error(res.parameters[n], tv) if tv else None, 10, ".3f")
        lines.append(f"{row:<{len(head) - 6}}  {unit.get(n, '')}".rstrip())
    lines.append("")
    lines.append(f"cost (mean squared output error over its start value): "
                 f"{res.cost_before:.4g} -> {res.cost_after:.4g}")
    lines.append(_forward_line(res.forward_before, res.forward_after))
    if res.sigma_corrected:
        lines.append("2 sigma, autocorrelation-consistent (the column's assumes white "
                     "residuals): " + ", ".join(f"{n} {2 * res.sigma_corrected[n]:.4g}"
                                                for n in STIFFNESS_AND_INERTIAS
                                                if n in res.sigma_corrected))
    lines.append(f"optimizer: {res.message}")
    lines += [f"note: {n}" for n in res.notes]
    return "\n".join(lines)


def _forward_line(fb: dict, fa: dict) -> str:
    """The forward errors (`bench.sim.replay.forward_errors`) before -> after."""
    pu, fu = fb["position_unit"], fb["torque_unit"]
    view = (f"forward view: torque {fb['torque_rms']:.4g} -> {fa['torque_rms']:.4g} {fu} RMS "
            f"({fb['torque_rel_pct']:.3g} % -> {fa['torque_rel_pct']:.3g} % of the measured), "
            f"q_m {fb['position_rms']:.3g} -> {fa['position_rms']:.3g} {pu}")
    if "link_position_rms" in fb and "link_position_rms" in fa:
        view += f", q {fb['link_position_rms']:.3g} -> {fa['link_position_rms']:.3g} {pu}"
    return view
