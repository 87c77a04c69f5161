"""The simulation-based bias correction (`bench.analysis.debias`) as JSON and text: what
`jointbench identify --debias B [--json]` prints after the least-squares answer."""

from __future__ import annotations

import math

from jointbench.bench.analysis.debias import DebiasResult
from jointbench.identification.output_values import pct_error
from jointbench.identification.parameters import units
from jointbench.identification.paper_tables import cell as num


def debiased_json(res: DebiasResult, truth: dict[str, float] | None = None) -> dict:
    """The "debiased" object of `identify --debias N --json`: `DebiasResult.to_json` and,
    with a virtual log's truth, "truth" and "error_pct" {"ls": ..., "debiased": ...}."""
    out = res.to_json()
    out["ls"] = {n: float(v) for n, v in res.ls.items()}
    out["ls_sigma_corrected"] = {n: (float(v) if math.isfinite(v) else None)
                                 for n, v in res.ls_sigma.items()}
    truth = {n: v for n, v in (truth or {}).items() if n in res.estimate and v}
    if truth:
        out["truth"] = truth
        out["error_pct"] = {
            "ls": {n: pct_error(res.ls[n], v) for n, v in truth.items()},
            "debiased": {n: pct_error(res.estimate[n], v) for n, v in truth.items()}}
    return out


def debias_table(res: DebiasResult, prismatic: bool = False,
                 truth: dict[str, float] | None = None) -> str:
    """The bias correction as text (what `jointbench identify --debias N` prints after the LS
    tables): per parameter the LS value, the bias the replicas show, the corrected value and
    its 2 sigma, the replicas' spread over the LS corrected sigma and, with truth, the LS and
    corrected errors in % and in corrected sigmas."""
    unit = units(prismatic)
    truth = {n: v for n, v in (truth or {}).items() if n in res.estimate and v}
    lines = [f"## Bias correction (parametric bootstrap): {res.replicas} closed-loop replicas "
             f"of the experiment on the nominal axis at the LS estimate, {res.seconds:.1f} s"
             + (f"; {len(res.failed)} failed" if res.failed else "")]
    head = (f"{'Parameter':<10}{'LS':>12}{'bias':>12}{'corrected':>12}{'2 sigma':>12}"
            f"{'s*/sigma':>9}")
    if truth:
        head += f"{'truth':>12}{'LS err %':>10}{'(sigma)':>8}{'error %':>10}{'(sigma)':>8}"
    head += "  unit"
    lines += [head, "-" * len(head)]

    for n, est in res.estimate.items():
        sc = res.ls_sigma.get(n, math.nan)
        row = (f"{n:<10}{num(res.ls[n])}{num(res.bias[n])}{num(est)}{num(2 * res.sigma[n])}"
               f"{num(res.spread[n] / sc if sc > 0 else None, 9, '.2f')}")
        if truth:
            tv = truth.get(n)
            row += num(tv)
            row += num(pct_error(res.ls[n], tv), 10, ".3f")
            row += num((res.ls[n] - tv) / sc if tv and sc > 0 else None, 8, "+.1f")
            row += num(pct_error(est, tv), 10, ".3f")
            row += num((est - tv) / res.sigma[n] if tv and res.sigma[n] > 0 else None, 8, "+.1f")
        lines.append(f"{row:<{len(head) - 6}}  {unit.get(n, '')}".rstrip())
    lines.append("")
    lines.append("sigma: sqrt(sigma_c^2 + s*^2 / B), sigma_c the LS autocorrelation-consistent "
                 "sigma, s* the replicas' standard deviation, B the replicas; s*/sigma: s* over "
                 "sigma_c (about 1 when sigma_c is calibrated)")
    for note in res.notes:
        lines.append(f"note: {note}")
    for reason in res.failed[:5]:
        lines.append(f"failed: {reason}")
    return "\n".join(lines)
