"""A closed-loop replay of a log file (`jointbench simulate --replay`) and its presentation:
the report as text and JSON, and the figure of measured and replayed signals."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco

from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.sim.controller import controller_from_log, describe
from jointbench.bench.sim.friction import log_substeps
from jointbench.bench.sim.nominal import compile_axis, for_log
from jointbench.bench.sim.replay import ReplayResult, forward_errors, replay
from jointbench.identification.identify import identify
from jointbench.bench.sim.plant_keys import check
from jointbench.identification.log import Log, LogError, read_log


def plot_replay(log: Log, result: ReplayResult, title: str = ""):
    """Figure: measured and replayed q_m (and tracking error q_ref - q_m) and tau_m against t.
    pyplot is imported here; the caller picks the backend."""
    import matplotlib.pyplot as plt

    pu, fu = ("m", "N") if log.prismatic else ("rad", "N m")
    fig, ax = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    ax[0].plot(log.t, log.q_m, lw=0.8, label="measured")
    ax[0].plot(result.t, result.q_m, lw=0.8, ls="--", label="replay")
    ax[0].set_ylabel(f"q_m [{pu}]")
    if log.q_ref is not None:
        ax[1].plot(log.t, log.q_ref - log.q_m, lw=0.8, label="measured")
        ax[1].plot(result.t, log.q_ref - result.q_m, lw=0.8, ls="--", label="replay")
        ax[1].set_ylabel(f"q_ref - q_m [{pu}]")
    ax[2].plot(log.t, log.tau_m, lw=0.8, label="measured")
    ax[2].plot(result.t, result.tau_m, lw=0.8, ls="--", label="replay")
    ax[2].set_ylabel(f"tau_m [{fu}]")
    ax[2].set_xlabel("t [s]")
    for a in ax:
        a.legend(loc="upper right", fontsize=8)
        a.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


@dataclass(frozen=True)
class ReplayReport:
    """A replay run from a log file (`replay_log_file`): what was replayed on which model and
    how it compares (`forward_errors`)."""

    log: Log
    result: ReplayResult
    errors: dict
    model: str                            # "nominal rigid", "nominal joint-motor" or the file
    axis: str
    parameters: dict[str, float] | None   # the identified parameters of a nominal model
    notes: tuple[str, ...] = ()
    spec: mujoco.MjSpec | None = None     # the nominal axis (None when a model was given)


def replay_log_file(path, model: str | None = None, joint: str | None = None,
                    config: dict[str, float] | None = None, lock: str = "rigid",
                    substeps: int | None = None, tau0: float | None = None, skip: int = 0,
                    identify_model: str = "auto") -> ReplayReport:
    """Read the log at `path` and replay it (`replay`) on `model` (shipped name or MJCF file,
    through `bench.axes.build_experiment_model` with the other axes locked as `config`
    says), or without a model on the nominal axis of its own identification
    (`identification.identify.identify(log, identify_model)`, then `bench.nominal.for_log`).
    """
    log = check(read_log(path))
    if log.q_ref is None:
        raise LogError("cannot replay: the log has no column 'q_ref' (the reference the "
                       "controller tracked)", log.path, column="q_ref")
    gains = controller_from_log(log)
    if substeps is None:   # the log's plant's discretisation (a measured log: one step)
        substeps = log_substeps(log, 1)
    notes: list[str] = []
    if model is None:
        ident = identify(log, identify_model)
        notes += [f"identify: {n}" for n in ident.notes]
        nominal = for_log(ident, log, joint)
        notes += [f"nominal: {n}" for n in nominal.notes]
        m, axis = compile_axis(nominal.spec, f"nominal {nominal.model} axis of {path}")
        label, params, spec = f"nominal {nominal.model}", dict(nominal.parameters), nominal.spec
    else:
        start = log.q[0] if log.q is not None else log.q_m[0]
        exp = build_experiment_model(model, joint, config=config, center=float(start),
                                     lock=lock, substeps=substeps,
                                     sample_rate_hz=log.sample_rate_hz, tau_max=gains.tau_max)
        m, axis, label, params, spec = exp.model, exp.axis, str(exp.source), None, None
    result = replay(m, axis, log, substeps=substeps, tau0=tau0)
    return ReplayReport(log=log, result=result, errors=forward_errors(log, result, skip),
                        model=label, axis=axis.name, parameters=params, notes=tuple(notes),
                        spec=spec)


def format_report(rep: ReplayReport) -> str:
    """The forward comparison as text (what `jointbench simulate --replay` prints)."""
    log, e = rep.log, rep.errors
    pu, fu = e["position_unit"], e["torque_unit"]
    lines = [f"replayed {log.path}: {len(log)} samples at {log.sample_rate_hz:g} Hz in closed "
             f"loop (docs/controller.md: {describe(controller_from_log(log))}) "
             f"on {rep.model}, axis {rep.axis}"]
    if rep.parameters:
        lines.append("model: " + ", ".join(f"{k} = {v:.6g}" for k, v in rep.parameters.items()))

    def pct(x, what):
        return "" if x is None else f", {x:.3g} % of {what}"

    span = f" (from sample {e['skip']})" if e["skip"] else ""
    lines.append(f"position q_m{span}: RMS error {e['position_rms']:.4g} {pu}"
                 f"{pct(e['position_rel_pct'], 'the motion')}"
                 f"{pct(e['tracking_rel_pct'], 'the measured tracking error')}")
    if "link_position_rms" in e:
        lines.append(f"link position q: RMS error {e['link_position_rms']:.4g} {pu}"
                     f"{pct(e['link_position_rel_pct'], 'the motion')}")
    lines.append(f"{'force' if log.prismatic else 'torque'} tau_m{span}: RMS error "
                 f"{e['torque_rms']:.4g} {fu}{pct(e['torque_rel_pct'], 'the measured RMS')}")
    lines.append(f"saturated samples in the replay: {rep.result.saturated}")
    lines += [f"note: {n}" for n in rep.notes]
    return "\n".join(lines)


def report_json(rep: ReplayReport) -> dict:
    """The JSON object of `jointbench simulate --replay --json`."""
    return {"replay": str(rep.log.path), "model": rep.model, "axis": rep.axis,
            "parameters": rep.parameters, "samples": len(rep.log),
            "saturated_samples": rep.result.saturated, "errors": rep.errors,
            "notes": list(rep.notes)}
