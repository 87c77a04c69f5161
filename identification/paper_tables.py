"""Tables in the layout of the paper's Tables 1-3, with truth and error columns when known,
and the JSON answer of `identify --json` (docs/cli.md)."""

from __future__ import annotations

import math

from jointbench.identification.identify import Identification
from jointbench.identification.output_values import finite_json, pct_error
from jointbench.identification.parameters import units

# The paper's published values (section 4), for side-by-side tables.
PAPER_TABLE1 = {"Jm": (174.7996, 2.7741, 0.7952), "K": (20341.0458, 437.1569, 1.0746),
                "JL": (47.4458, 1.6281, 1.7157), "FSm": (41.4254, 5.5393, 6.6858),
                "FVm": (235.9100, 127.9280, 27.1137), "FV": (83.1508, 41.4113, 24.9013),
                "MX": (-0.7241, 1.1948, 82.5056), "MY": (-53.4201, 10.3659, 9.7023),
                "FS": (8.4612, 2.5726, 15.2025)}
PAPER_TABLE2 = {"X1": (0.0021, 0.0001, 2.5977), "X2": (0.0046, 0.0022, 23.6303),
                "X3": (0.3554, 0.0176, 2.4774), "X4": (3.1739, 0.3569, 5.6218),
                "X5": (205.4558, 7.9221, 1.9279), "X6": (1246.5690, 165.1359, 6.6236),
                "X7": (5.1624, 7.4232, 71.8975)}
PAPER_TABLE3 = {"Jm": 172.1890, "K": 19552.6214, "JL": 40.3601, "FSm": 5.1624,
                "FVm": 1157.4716, "FV": 89.0974}
TABLE1_ORDER = ("Jm", "K", "JL", "FSm", "FVm", "FV", "MX", "MY", "FS")
def model_truth(model: str, truth: dict[str, float] | None) -> dict[str, float]:
    """The truth in the parameters of `model`: for the rigid model (eq. 6 with q = qm, docs/cli.md) J = Jm + JL, FV = FVm + FV, FS = FSm + FS; the other models use the truth as is."""
    truth = dict(truth or {})
    if model != "rigid":
        return truth
    if "Jm" in truth and "JL" in truth:
        truth["J"] = truth["Jm"] + truth["JL"]
    for total, motor in (("FV", "FVm"), ("FS", "FSm")):
        if total in truth or motor in truth:
            truth[total] = truth.get(total, 0.0) + truth.get(motor, 0.0)
    return truth


def signal_units(prismatic: bool) -> tuple[str, str]:
    """(position unit, force or torque unit) of a log's signals."""
    return ("m", "N") if prismatic else ("rad", "N m")


def _num(x: float, width: int = 12) -> str:
    return cell(x, width)


def cell(x: float | None, width: int = 12, fmt: str = ".6g") -> str:
    """A right-aligned table cell, '-' for a missing or non-finite value; `fmt` may start with
    '+' to sign every number. The cell always starts with a space, so that two columns never
    run together: a number too wide for `width` is printed in fewer digits (.6g, .4g, .3g
    for fixed-point formats)."""
    if x is None or not math.isfinite(x):
        return f"{'-':>{width}}"
    sign, fmt = ("+", fmt[1:]) if fmt.startswith("+") else ("", fmt)
    for form in (fmt, ".6g", ".4g", ".3g"):
        text = f"{x:{sign}{form}}"
        if len(text) < width:
            break
    return f" {text:>{width - 1}}"


def expected_x(truth: dict[str, float]) -> dict[str, float]:
    """X1..X9 of eq. (19) (and the corrected terms) from physical truth, for truth columns."""
    try:
        K, Jm, JL, FVm, FSm, FV = (truth[k] for k in ("K", "Jm", "JL", "FVm", "FSm", "FV"))
    except KeyError:
        return {}
    return {"X1": JL / K, "X2": FV / K, "X3": Jm * JL / K, "X4": (Jm * FV + JL * FVm) / K,
            "X5": Jm + JL + FV * FVm / K, "X6": FV + FVm, "X7": FSm, "X8": JL * FSm / K,
            "X9": FV * FSm / K}


def design_lines(result: Identification) -> list[str]:
    """The first mode (measured or given, with how and its uncertainty), the design it gave
    (wn, Nd, decimated cutoff against f1, stencil and why) and the warnings; [] when the
    caller chose the filter without a first mode."""
    mode, s = result.first_mode, result.settings
    if mode is None:
        return []
    if mode.found:
        sd = f" +- {mode.sigma_hz:.2g}" if math.isfinite(mode.sigma_hz) else ""
        head = f"first mode f1 = {mode.f1_hz:.4g}{sd} Hz ({mode.method})"
        if mode.method.startswith("identified"):   # the band's own estimate, first in the note
            head += f"; {mode.note.split('; ')[0]}"
        ratio = f" = {s.decimated_cutoff_hz / mode.f1_hz:.2f} f1"
    else:
        head, ratio = f"first mode: not found ({mode.note})", ""
    return [head, f"design: wn = {s.wn:.4g} rad/s (order {s.m}), Nd = {s.Nd}, decimated cutoff "
            f"{s.decimated_cutoff_hz:.3g} Hz{ratio}; {result.stencil_reason}"] + \
        [f"warning: {w}" for w in result.warnings]


def parameter_table(result: Identification, truth: dict[str, float] | None = None,
                    paper: dict[str, tuple[float, float, float]] | None = None,
                    title: str = "") -> str:
    """The LS estimate in the paper's layout (parameter, X, 2 sigma, % sigma_r), with the
    paper's value, the truth and the error % when given."""
    ls = result.ls
    truth = model_truth(result.model, truth)
    unit = units(result.prismatic)
    paper = paper if result.paper_axis else None   # the paper's values: its prototype only
    order = [n for n in TABLE1_ORDER if n in ls.names] if result.model == "joint-motor" \
        else list(ls.names)
    head = f"{'Parameter':<10}{'X':>12}{'2 sigma':>12}{'% sigma_r':>11}"
    if paper:
        head += f"{'paper':>12}"
    if truth:
        head += f"{'truth':>12}{'error %':>10}"
    head += "  unit"
    lines = ([title] if title else []) + design_lines(result) + [head, "-" * len(head)]
    for n in order:
        x, s = ls.value(n), ls.std(n)
        row = f"{n:<10}{_num(x)}{_num(2 * s)}{_num(100 * s / abs(x) if x else float('nan'), 11)}"
        if n in ls.unidentifiable:
            row = f"{n:<10}{'not identifiable':>35}"
        if paper:
            row += _num(paper[n][0]) if n in paper else f"{'':>12}"
        if truth:
            tv = truth.get(n)
            if tv is None or n in ls.unidentifiable:
                row += f"{'':>22}"
            else:
                row += f"{_num(tv)}{cell(pct_error(x, tv), 10, '.3f')}"
        if n in unit:
            row = f"{row:<{len(head) - 6}}  {unit[n]}"
        lines.append(row)
    return "\n".join(lines)


def physical_table(result: Identification, truth: dict[str, float] | None = None,
                   title: str = "") -> str:
    """Physical parameters: this method (with sigma), Table 3 as printed, the paper, truth."""
    truth = truth or {}
    unit = units(result.prismatic)
    paper = PAPER_TABLE3 if result.paper_axis else {}   # the paper's values: its prototype only
    head = f"{'Parameter':<10}{'estimate':>12}{'2 sigma':>12}{'Table 3 eq.':>13}" + \
        (f"{'paper':>12}" if paper else "")
    if truth:
        head += f"{'truth':>12}{'error %':>10}{'T3 err %':>10}"
    head += "  unit"
    lines = [title, head, "-" * len(head)] if title else [head, "-" * len(head)]
    for n in ("Jm", "K", "JL", "FSm", "FVm", "FV", "MX", "MY"):
        if n not in result.physical:
            continue
        v = result.physical[n]
        s = result.physical_sigma.get(n, float("nan"))
        t3 = result.table3.get(n, float("nan"))
        row = f"{n:<10}{_num(v)}{_num(2 * s)}{_num(t3, 13)}" + \
            (_num(paper.get(n, float("nan"))) if paper else "")
        if truth and n in truth:
            tv = truth[n]
            row += (f"{_num(tv)}{cell(pct_error(v, tv), 10, '.3f')}"
                    f"{cell(pct_error(t3, tv), 10, '.3f')}")
        lines.append(f"{row:<{len(head) - 6}}  {unit.get(n, '')}".rstrip())
    return "\n".join(lines)


def to_json(result: Identification, truth: dict[str, float] | None = None) -> dict:
    """The `identify --json` object of docs/cli.md (plus optional keys)."""
    ls = result.ls
    truth = model_truth(result.model, truth)
    params = {}
    for n in ls.names:
        if n in ls.unidentifiable:
            params[n] = {"value": None, "sigma": None, "rel_sigma_pct": None,
                         "identifiable": False, "reason": ls.reasons[n],
                         "sigma_corrected": None}
            continue
        x, s = ls.value(n), ls.std(n)
        sc = ls.std_corrected(n) if ls.cov_corrected is not None else math.nan
        params[n] = {"value": x, "sigma": s,
                     "rel_sigma_pct": 100 * s / abs(x) if x else None,
                     "sigma_corrected": sc if math.isfinite(sc) else None}
    unit = units(result.prismatic)
    out = {"model": result.model, "parameters": params,
           "axis": "prismatic" if result.prismatic else "revolute",
           "units": {n: unit[n] for n in list(params) + list(result.physical) if n in unit},
           "physical": dict(result.physical),
           "physical_sigma": dict(result.physical_sigma),
           "filter": {"wn_rad_s": result.settings.wn, "order": result.settings.m,
                      "decimate": result.settings.Nd, "stencil": result.settings.stencil,
                      "decimated_cutoff_hz": result.settings.decimated_cutoff_hz,
                      "cutoff_over_f1": _cutoff_over_f1(result),
                      "stencil_reason": result.stencil_reason},
           "residual_rms": ls.rms,
           "relative_error_pct": result.relative_error_pct,
           "condition_number": ls.cond,
           "notes": list(result.notes),
           "warnings": list(result.warnings),
           "corrections": list(result.corrections)}
    if result.reversals is not None:   # joint-motor with the reversal passes: how they ended
        out["reversals"] = result.reversals.to_json()
    mode = result.first_mode
    if mode is not None:
        out["first_mode"] = finite_json({"f1_hz": mode.f1_hz, "sigma_hz": mode.sigma_hz,
                                         "method": mode.method, "found": mode.found,
                                         "source": "given" if mode.method == "given"
                                         else "measured", "note": mode.note})
    if result.physical_sigma_corrected:
        out["physical_sigma_corrected"] = {k: v for k, v in
                                           result.physical_sigma_corrected.items()
                                           if math.isfinite(v)}
    if ls.hac is not None:
        out["uncertainty"] = {"estimator": "instrumental variables (instruments from q_ref)"
                              if ls.instrumental else "least squares",
                              "sigma": "paper: ||rho||^2 / (r - Np) (W^T W)^-1, white residuals"
                              if not ls.instrumental else "||rho||^2 / (r - Np) "
                              "(Z^T W)^-1 Z^T Z (W^T Z)^-1, white residuals",
                              "sigma_corrected": "HAC sandwich, VAR(1) prewhitened, "
                                                 f"{ls.hac.kernel} kernel",
                              "bandwidth": ls.hac.bandwidth, "lag1_autocorrelation": ls.hac.ar1}
    if result.table3:
        out["table3"] = dict(result.table3)
    if truth:
        out["truth"] = {k: v for k, v in truth.items()
                        if k in result.physical or k in params}
        errors = {k: pct_error(result.physical[k], v) for k, v in truth.items()
                  if k in result.physical}
        out["error_pct"] = {k: e for k, e in errors.items() if e is not None}
    return out


def _cutoff_over_f1(result: Identification) -> float | None:
    mode = result.first_mode
    if mode is None or not mode.found:
        return None
    return result.settings.decimated_cutoff_hz / mode.f1_hz
