"""A survey (bench.campaign.robot_survey) as text, as the `survey --json` object, as its CSV table
and as its figure: what `jointbench survey` prints and writes."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from jointbench.bench.campaign.robot_survey import ACCURACY_BAR_PCT, Estimate, JointSurvey, Survey
from jointbench.identification.output_values import finite_json, pct_error
from jointbench.identification.parameters import FRICTIONS, STIFFNESS_AND_INERTIAS, units

F1 = "f1"   # the first mode's row of the table [Hz]


def f1_estimate(j: JointSurvey) -> Estimate | None:
    """The first mode measured on the log as a table row (its sigma for both sigmas), None
    when no resonance was found."""
    m = j.first_mode
    if m is None or not m.found:
        return None
    return Estimate(m.f1_hz, m.sigma_hz, m.sigma_hz, j.f1_truth_hz)


def rows(j: JointSurvey) -> list[tuple[str, Estimate]]:
    """(name, estimate) of one axis in table order: f1, then K Jm JL FVm FSm FV FS (J for a
    rigid axis)."""
    f1 = f1_estimate(j)
    return ([(F1, f1)] if f1 is not None else []) + list(j.estimates.items())


def _unit(name: str) -> str:
    return "Hz" if name == F1 else units(False)[name]


def _filter_text(j: JointSurvey) -> str:
    s = j.settings
    return (f"filter wn = {s.wn:.4g} rad/s (order {s.m}), Nd = {s.Nd}, decimated cutoff "
            f"{s.decimated_cutoff_hz:.3g} Hz, {s.stencil}-point differences")


def _mode_text(j: JointSurvey) -> str:
    m = j.first_mode
    if m is None or not m.found:
        return f"no first mode found ({m.note if m else 'not measured'})"
    return f"f1 {m.f1_hz:.4g} +- {m.sigma_hz:.2g} Hz (truth {j.f1_truth_hz:.4g} Hz; {m.method})"


def _axes(n: int) -> str:
    return f"{n} axis" if n == 1 else f"{n} axes"


def _num(x: float | None, fmt: str) -> str:
    return "" if x is None or not math.isfinite(x) else format(x, fmt)


def survey_text(sv: Survey, out: Path | None) -> str:
    """The table (one row per axis and parameter), each axis' filter, first mode and
    warnings, the accuracy against the survey's bar, the wall time and the files written."""
    models = sorted({j.model for j in sv.joints if j.status == "ok"})
    lines = [f"survey of {sv.model} ({sv.source.name}): {_axes(len(sv.joints))}, each a "
             f"{sv.duration:g} s chirp at {sv.sample_rate_hz:g} Hz with the others locked, "
             f"seed {sv.seed}; identified with the defaults ({', '.join(models) or 'none'} "
             "model, filter from the first mode measured on each log)", ""]
    head = (f"{'joint':<8}{'param':<7}{'estimate':>12}{'2 sigma':>11}{'truth':>12}"
            f"{'error %':>9}{'z':>7}  unit")
    lines += [head, "-" * len(head)]
    for j in sv.joints:
        if j.status != "ok":
            lines.append(f"{j.joint:<8}failed: {j.reason}")
            continue
        for i, (name, e) in enumerate(rows(j)):
            lines.append(f"{j.joint if i == 0 else '':<8}{name:<7}{e.value:>12.6g}"
                         f"{_num(2 * e.sigma_c, '.4g'):>11}{_num(e.truth, '.6g'):>12}"
                         f"{_num(e.error_pct, '+.3f'):>9}{_num(e.z, '+.2f'):>7}  {_unit(name)}")
    lines += ["", "2 sigma: autocorrelation-consistent (f1: the first mode's own); "
                  "z = (estimate - truth) / sigma", ""]
    for j in sv.joints:
        if j.status != "ok":
            continue
        lines.append(f"{j.joint}: {j.model} model, {_filter_text(j)}; {_mode_text(j)}; "
                     f"direct validation {j.relative_error_pct:.2f} %"
                     + (f"; saturated samples {j.saturated}" if j.saturated else ""))
        lines += [f"  warning: {w}" for w in j.warnings]
    ok = [j for j in sv.joints if j.status == "ok"]
    within = sum(j.within_bar() for j in ok)
    worst = sv.worst()
    lines += ["", f"K, Jm, JL within {ACCURACY_BAR_PCT:g} % of the truth: "
                  f"{within} of {_axes(len(sv.joints))}"
              + (f"; largest |error| {worst[1]} {worst[2]:+.3f} % on {worst[0]}" if worst else "")]
    sim = sum(j.sim_s for j in ok if math.isfinite(j.sim_s))
    ident = sum(j.identify_s for j in ok if math.isfinite(j.identify_s))
    lines.append(f"wall time {sv.wall_s:.1f} s on {sv.workers} worker"
                 f"{'s' if sv.workers > 1 else ''} (summed over the axes: simulation "
                 f"{sim:.1f} s, identification {ident:.1f} s)")
    if out is not None:
        lines.append(f"wrote {out / TABLE}, {out / FIGURE} and {len(logged(sv))} logs in "
                     f"{out / LOGS}/")
    return "\n".join(lines)


def _estimate_json(name: str, e: Estimate) -> dict:
    return {"value": e.value, "sigma": e.sigma, "sigma_corrected": e.sigma_c, "truth": e.truth,
            "error_pct": e.error_pct, "z": e.z, "unit": _unit(name)}


def _joint_json(j: JointSurvey, out: Path | None) -> dict:
    doc: dict = {"joint": j.joint, "status": j.status, "reason": j.reason or None}
    if j.status != "ok":
        return doc
    s, m = j.settings, j.first_mode
    doc.update({
        "model": j.model,
        "log": str(out / LOGS / f"{j.joint}.csv") if out is not None else None,
        "filter": {"wn_rad_s": s.wn, "order": s.m, "decimate": s.Nd,
                   "decimated_cutoff_hz": s.decimated_cutoff_hz, "stencil": s.stencil,
                   "stencil_reason": j.stencil_reason},
        "first_mode": None if m is None else {
            "f1_hz": m.f1_hz, "sigma_hz": m.sigma_hz, "found": m.found, "method": m.method,
            "truth_hz": j.f1_truth_hz, "error_pct": pct_error(m.f1_hz, j.f1_truth_hz)},
        "parameters": {n: _estimate_json(n, e) for n, e in j.estimates.items()},
        "within_bar": j.within_bar(), "relative_error_pct": j.relative_error_pct,
        "saturated": j.saturated, "warnings": list(j.warnings), "notes": list(j.notes),
        "sim_s": j.sim_s, "identify_s": j.identify_s})
    return doc


def survey_json(sv: Survey, out: Path | None) -> dict:
    """The `survey --json` object (docs/cli.md), strict JSON (NaN and inf as null)."""
    worst = sv.worst()
    return finite_json({
        "model": sv.model, "model_file": str(sv.source), "duration_s": sv.duration,
        "seed": sv.seed, "sample_rate_hz": sv.sample_rate_hz,
        "joints": [_joint_json(j, out) for j in sv.joints],
        "accuracy": {"bar_pct": ACCURACY_BAR_PCT, "parameters": list(STIFFNESS_AND_INERTIAS),
                     "within": sum(j.within_bar() for j in sv.joints if j.status == "ok"),
                     "axes": len(sv.joints),
                     "worst": None if worst is None else
                     {"joint": worst[0], "parameter": worst[1], "error_pct": worst[2]}},
        "failed": [j.joint for j in sv.failed],
        "out": None if out is None else str(out),
        "files": [] if out is None else [str(out / TABLE), str(out / FIGURE)]
        + [str(out / LOGS / f"{j.joint}.csv") for j in logged(sv)],
        "workers": sv.workers, "wall_s": sv.wall_s})


# The files `survey --out DIR` writes (bench.output_files.OutputFolder).
TABLE, FIGURE, LOGS = "survey.csv", "survey.png", "logs"
FILES = (TABLE, FIGURE, f"{LOGS}/*")
COLUMNS = ("joint", "parameter", "unit", "estimate", "sigma", "sigma_corrected", "truth",
           "error_pct", "z", "note")


def logged(sv: Survey) -> list[JointSurvey]:
    """The axes whose experiment ran (their log is written)."""
    return [j for j in sv.joints if j.log is not None]


def _cell(x: float | None) -> str:
    return "" if x is None or not math.isfinite(x) else repr(float(x))


def table_csv(sv: Survey) -> str:
    """The survey's table as CSV: `#` lines (model, duration, seed, rate), a header, one row
    per axis and parameter (full precision; empty cells for missing values; a failed axis
    is one row with its reason in `note`). Deterministic: no wall time."""
    buf = io.StringIO()
    buf.write(f"# jointbench survey\n# model: {sv.model}\n# duration_s: {sv.duration!r}\n"
              f"# seed: {sv.seed}\n# sample_rate_hz: {sv.sample_rate_hz!r}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for j in sv.joints:
        if j.status != "ok":
            w.writerow([j.joint] + [""] * (len(COLUMNS) - 2) + [" ".join(j.reason.split())])
            continue
        for name, e in rows(j):
            sigma_c = math.nan if name == F1 else e.sigma_c
            w.writerow([j.joint, name, _unit(name), _cell(e.value), _cell(e.sigma),
                        _cell(sigma_c), _cell(e.truth), _cell(e.error_pct), _cell(e.z), ""])
    return buf.getvalue()


def plot_survey(sv: Survey):
    """Error in % of the truth per axis and parameter, with +-2 sigma bars (corrected; f1:
    its own): f1, K, Jm, JL above with the survey's +-0.5 % band, the frictions below."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [j for j in sv.joints if j.status == "ok"]
    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for ax, names in zip(axes, ((F1,) + STIFFNESS_AND_INERTIAS, FRICTIONS)):
        width = 0.8 / len(names)
        for k, name in enumerate(names):
            xs, ys, bars = [], [], []
            for i, j in enumerate(ok):
                e = dict(rows(j)).get(name)
                if e is None or e.error_pct is None:
                    continue
                xs.append(i - 0.4 + (k + 0.5) * width)
                ys.append(e.error_pct)
                bars.append(200 * e.sigma_c / abs(e.truth) if math.isfinite(e.sigma_c) else 0)
            ax.errorbar(xs, ys, yerr=bars, fmt="o", ms=4, capsize=3, label=name)
        ax.axhline(0, color="k", lw=0.6)
        ax.set_ylabel("error [% of truth]")
        ax.grid(alpha=0.3)
        ax.legend(ncol=len(names), fontsize=8, loc="upper right")
    axes[0].axhspan(-ACCURACY_BAR_PCT, ACCURACY_BAR_PCT, color="tab:green", alpha=0.12,
                    label=f"+-{ACCURACY_BAR_PCT:g} %")
    axes[0].set_title(f"{sv.model}: first mode, stiffness and inertias (green: +-"
                      f"{ACCURACY_BAR_PCT:g} %), bars +-2 sigma")
    axes[1].set_title("frictions (motor FVm, FSm; link FV, FS), bars +-2 sigma")
    axes[1].set_xticks(range(len(ok)), [j.joint for j in ok])
    axes[1].set_xlabel(f"axis ({sv.duration:g} s chirp at {sv.sample_rate_hz:g} Hz, seed "
                       f"{sv.seed}, the others locked)")
    fig.tight_layout()
    return fig



def write_survey(sv: Survey, folder: Path) -> None:
    """The logs, the table and the figure into `folder` (inside bench.output_files.OutputFolder's
    `writing()`: atomic files, all or nothing)."""
    from jointbench.identification.log import write_log
    from jointbench.identification.log.write import atomic_write_text, save_figure_atomic

    (folder / LOGS).mkdir(exist_ok=True)
    for j in logged(sv):
        write_log(j.log, folder / LOGS / f"{j.joint}.csv")
    atomic_write_text(folder / TABLE, table_csv(sv))
    fig = plot_survey(sv)   # selects the Agg backend before pyplot is imported here
    import matplotlib.pyplot as plt

    try:
        save_figure_atomic(fig, folder / FIGURE)
    finally:
        plt.close(fig)
