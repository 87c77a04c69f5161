"""Tables in the layout of the paper's Tables 1-3, with truth and error columns when known,
and the JSON answer of `identify --json` (CONTRACT section 3)."""

from __future__ import annotations

import math

from identification.identify import Identification

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
UNITS_REVOLUTE = {"Jm": "kg m^2", "JL": "kg m^2", "J": "kg m^2", "K": "N m/rad",
                  "FVm": "N m s/rad", "FV": "N m s/rad", "FSm": "N m", "FS": "N m",
                  "MX": "kg m", "MY": "kg m", "offset": "N m"}
UNITS_PRISMATIC = {"J": "kg", "FV": "N s/m", "FS": "N", "offset": "N", "K": "N/m",
                   "Jm": "kg", "JL": "kg", "FVm": "N s/m", "FSm": "N"}


def _num(x: float, width: int = 12) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return f"{'-':>{width}}"
    return f"{x:>{width}.6g}"


def expected_x(truth: dict[str, float]) -> dict[str, float]:
    """X1..X9 of eq. (19) (and the corrected terms) from physical truth, for truth columns."""
    try:
        K, Jm, JL, FVm, FSm, FV = (truth[k] for k in ("K", "Jm", "JL", "FVm", "FSm", "FV"))
    except KeyError:
        return {}
    return {"X1": JL / K, "X2": FV / K, "X3": Jm * JL / K, "X4": (Jm * FV + JL * FVm) / K,
            "X5": Jm + JL + FV * FVm / K, "X6": FV + FVm, "X7": FSm, "X8": JL * FSm / K,
            "X9": FV * FSm / K}


def parameter_table(result: Identification, truth: dict[str, float] | None = None,
                    paper: dict[str, tuple[float, float, float]] | None = None,
                    title: str = "") -> str:
    """The LS estimate in the paper's layout (parameter, X, 2 sigma, % sigma_r), with the
    paper's value, the truth and the error % when given."""
    ls = result.ls
    truth = truth or {}
    order = [n for n in TABLE1_ORDER if n in ls.names] if result.model == "joint-motor" \
        else list(ls.names)
    head = f"{'Parameter':<10}{'X':>12}{'2 sigma':>12}{'% sigma_r':>11}"
    if paper:
        head += f"{'paper':>12}"
    if truth:
        head += f"{'truth':>12}{'error %':>10}"
    lines = [title, head, "-" * len(head)] if title else [head, "-" * len(head)]
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
                err = 100 * (x - tv) / abs(tv) if tv else float("nan")
                row += f"{_num(tv)}{err:>10.3f}"
        lines.append(row)
    return "\n".join(lines)


def physical_table(result: Identification, truth: dict[str, float] | None = None,
                   title: str = "") -> str:
    """Physical parameters: this method (with sigma), Table 3 as printed, the paper, truth."""
    truth = truth or {}
    head = f"{'Parameter':<10}{'estimate':>12}{'2 sigma':>12}{'Table 3 eq.':>13}{'paper':>12}"
    if truth:
        head += f"{'truth':>12}{'error %':>10}{'T3 err %':>10}"
    lines = [title, head, "-" * len(head)] if title else [head, "-" * len(head)]
    for n in ("Jm", "K", "JL", "FSm", "FVm", "FV", "MX", "MY"):
        if n not in result.physical:
            continue
        v = result.physical[n]
        s = result.physical_sigma.get(n, float("nan"))
        t3 = result.table3.get(n, float("nan"))
        row = f"{n:<10}{_num(v)}{_num(2 * s)}{_num(t3, 13)}{_num(PAPER_TABLE3.get(n, float('nan')))}"
        if truth and n in truth:
            tv = truth[n]
            row += f"{_num(tv)}{100 * (v - tv) / abs(tv):>10.3f}{100 * (t3 - tv) / abs(tv):>10.3f}"
        lines.append(row)
    return "\n".join(lines)


def to_json(result: Identification, truth: dict[str, float] | None = None) -> dict:
    """The `identify --json` object of CONTRACT section 3 (plus optional keys)."""
    ls = result.ls
    params = {}
    for n in ls.names:
        if n in ls.unidentifiable:
            params[n] = {"value": None, "sigma": None, "rel_sigma_pct": None,
                         "identifiable": False, "reason": ls.reasons[n]}
            continue
        x, s = ls.value(n), ls.std(n)
        params[n] = {"value": x, "sigma": s,
                     "rel_sigma_pct": 100 * s / abs(x) if x else None}
    out = {"model": result.model, "parameters": params,
           "physical": dict(result.physical),
           "physical_sigma": dict(result.physical_sigma),
           "filter": {"wn_rad_s": result.settings.wn, "order": result.settings.m,
                      "decimate": result.settings.Nd},
           "residual_rms": ls.rms,
           "relative_error_pct": result.relative_error_pct,
           "condition_number": ls.cond,
           "notes": list(result.notes)}
    if result.table3:
        out["table3"] = dict(result.table3)
    if truth:
        out["truth"] = {k: v for k, v in truth.items()
                        if k in result.physical or k in params}
        out["error_pct"] = {k: 100 * (result.physical[k] - v) / abs(v)
                            for k, v in truth.items() if k in result.physical and v}
    return out
