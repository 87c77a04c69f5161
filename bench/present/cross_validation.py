"""The forward view of `identify --validate OTHER.csv`: the identified model, built as the
nominal MuJoCo axis (bench.sim.nominal), replays the other log's experiment in closed loop
(its q_ref and controller gains, docs/controller.md) and its torque and positions are
compared with the measured ones, beside the same replay of the fit's own log. Applies when
both logs are replayable (q_ref and the gains kp, kv, ki, tau_max)."""

from __future__ import annotations

from jointbench.bench.sim.nominal import compile_axis, for_log
from jointbench.bench.sim.replay import forward_errors, replay
from jointbench.identification.identify import Identification
from jointbench.identification.log import Log

GAINS = ("kp", "kv", "ki", "tau_max")


def replayable(log: Log) -> bool:
    """A replay needs q_ref and the controller gains."""
    return log.q_ref is not None and all(log.meta_float(k) is not None for k in GAINS)


def _replay_errors(result: Identification, log: Log) -> dict:
    nominal = for_log(result, log)
    model, axis = compile_axis(nominal.spec, f"nominal {nominal.model} axis")
    return forward_errors(log, replay(model, axis, log))


def forward_validation(result: Identification, fit_log: Log, other: Log) -> dict | None:
    """`{"other": forward_errors of OTHER, "fit": forward_errors of the fit's log,
    "unused_columns": OTHER's extra columns}` (keys of bench.sim.replay.forward_errors), or
    None when either log cannot be replayed. No disturbance is applied: a log with one (an
    extra column such as EMPS's pulses_N) replays well only through `diagnose --validate
    --disturbance-column`."""
    if not (replayable(fit_log) and replayable(other)):
        return None
    return {"other": _replay_errors(result, other), "fit": _replay_errors(result, fit_log),
            "unused_columns": sorted(other.extra)}


def forward_text(forward: dict | None, other_path: str | None) -> str:
    """One line for the `identify --validate` report (or why there is no forward view)."""
    if forward is None:
        return ("validation, forward view: not run (both logs need q_ref and the gains "
                "kp, kv, ki, tau_max)")
    o, f = forward["other"], forward["fit"]

    def pct(x):
        return "-" if x is None else f"{x:.3g} %"
    text = (f"validation on {other_path}, forward view (the identified model replays that "
            f"log's experiment in closed loop): torque {pct(o['torque_rel_pct'])} RMS against "
            f"{pct(f['torque_rel_pct'])} on the fit's own log; q_m {o['position_rms']:.3g} "
            f"against {f['position_rms']:.3g} {o['position_unit']} RMS")
    if "link_position_rms" in o and "link_position_rms" in f:
        text += (f"; q {o['link_position_rms']:.3g} against {f['link_position_rms']:.3g} "
                 f"{o['position_unit']} RMS")
    if forward["unused_columns"]:
        text += (f" (no disturbance applied: the log has the columns "
                 f"{', '.join(forward['unused_columns'])}; `diagnose --validate "
                 "--disturbance-column COL` replays with one)")
    return text
