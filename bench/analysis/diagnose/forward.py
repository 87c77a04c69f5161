"""Forward view of `diagnose`: the nominal and the extended MuJoCo axes, built from the
parameters identified on the log, replay the logged experiment in closed loop (docs/controller.md,
bench.replay) and are compared with the measured q_m, q and tau_m.

The named effect goes into the MJCF where MuJoCo expresses it (bench.effects.write_extended,
each effect's module there): backlash as a dead-band tendon, spring damping as tendon damping,
hardening as a stacked dead-band tendon, link Coulomb friction as frictionloss, torque lag as
an exact first-order filter actuator, gravity as the link's mass and centre of mass, an offset
as a passive constant-bias actuator. Torque ripple and asymmetric friction depend on the
motor angle and velocity in ways no MuJoCo actuator bias does: they are written as custom
numerics (`X_ripple` = amplitude, period, phase; `X_asymmetry` = a, FVm, FSm) that the bench
loop applies (bench.effects.loop_effects_from_model), in the replay and in `jointbench simulate`.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Callable

import mujoco
import numpy as np

from jointbench.bench.analysis.diagnose.types import Diagnosis, ForwardView
from jointbench.bench.effects import loop_effects_from_model, write_effects
from jointbench.bench.effects.base import positive_part as _pos
from jointbench.bench.sim import nominal as nominal_axes
from jointbench.bench.sim.replay import ReplayError, replay
from jointbench.identification.discrepancy import nominal as nominal_rows, predict, with_parameters
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log


def _axis_name(d: Diagnosis) -> str:
    return d.log.meta.get("joint") or "axis1"


def build_spec(d: Diagnosis, extended: bool, substeps: int = 1) -> mujoco.MjSpec:
    """The nominal (extended=False) or extended MjSpec of the diagnosed axis, with MuJoCo's
    timestep the log's period over `substeps`."""
    log = d.log
    name = _axis_name(d)
    p = dict(d.nominal_parameters)
    causes = d.causes if extended else ()
    if causes:
        p.update(d.extended_parameters)
    common = dict(timestep=log.ts / substeps, tau_max=log.meta_float("tau_max"),
                  gravity=log.gravity, prismatic=log.prismatic, name=name)
    if "K" in d.nominal_parameters:
        # FS: the nominal's link Coulomb friction (eq. 13); the extended model's is refitted.
        FS = _pos(p, "FS")
        spec = nominal_axes.two_mass_axis(
            Jm=p["Jm"], FVm=_pos(p, "FVm"), FSm=_pos(p, "FSm"), K=p["K"], JL=p["JL"],
            FV=_pos(p, "FV"), FS=FS, MX=0.0 if log.prismatic else p.get("MX", 0.0),
            MY=0.0 if log.prismatic else p.get("MY", 0.0), **common)
        K = p["K"]
    else:
        spec = nominal_axes.rigid_axis(J=p["J"], FV=_pos(p, "FV"), FS=_pos(p, "FS"),
                                       offset=0.0, **common)
        K = 0.0
    if causes:   # every named cause, in order: one (effect, parameters) pair each
        # d.extended_parameters holds every cause's parameters from one joint fit
        write_effects(spec, name, [(c.effect, p) for c in causes], K)
    return spec


def replay_substeps(d: Diagnosis, extended: bool) -> int:
    """MuJoCo steps per log sample for the model's replay: 1, or for a named torque lag as short
    as the log's half period, enough that the filter written half a step shorter
    (bench.effects.torque_lag.extend) keeps a positive time constant of at least half a step,
    where RK4 on it is stable; otherwise a lag under ts / 2 (a bench lag run with substeps, a
    drive's fast current loop) would be written as no lag at all."""
    lag = d.extended_parameters.get("lag_s", 0.0) if extended else 0.0
    if not (lag > 0 and any(c.effect == "torque_lag" for c in d.causes)):
        return 1
    return max(1, math.ceil(d.log.ts / lag))


def replay_tau0(log: Log) -> float | None:
    """The integrator's initial state of a replay of `log` (None: the logged tau_m[0])."""
    # With ki = 0 there is no integrator: docs/controller.md's I[-1] = tau_m[0] would hold the first
    # logged torque for ever, which is only right for a log starting at rest (EMPS starts in
    # motion: 89 N held, a constant 65 um off). A P-only drive starts with I = 0.
    return 0.0 if log.meta_float("ki") == 0 else None


def _view(d: Diagnosis, spec: mujoco.MjSpec, disturbance: np.ndarray | None = None,
          disturbance_at: str = "link", substeps: int = 1) -> ForwardView:
    log = d.log
    model, axis = nominal_axes.compile_axis(spec, "<diagnosis>")
    loop = loop_effects_from_model(model, axis.name)
    r = replay(model, axis, log, disturbance=disturbance, disturbance_at=disturbance_at,
               tau0=replay_tau0(log), loop=loop, substeps=substeps)
    e_qm = float(np.sqrt(np.mean((r.q_m - log.q_m) ** 2)))
    motion = float(np.sqrt(np.mean((log.q_m - np.mean(log.q_m)) ** 2)))
    e_tau = 100 * float(np.linalg.norm(r.tau_m - log.tau_m) / np.linalg.norm(log.tau_m))
    e_q = None
    if r.q is not None and log.q is not None:
        e_q = float(np.sqrt(np.mean((r.q - log.q) ** 2)))
    return ForwardView(q_m_rms=e_qm, q_rms=e_q, tau_rel_pct=e_tau,
                       q_m_rel_pct=100 * e_qm / motion if motion > 0 else float("nan"),
                       t=r.t, q_m=r.q_m, q=r.q, tau_m=r.tau_m)


def add_forward_view(d: Diagnosis, say: Callable[[str], None]) -> Diagnosis:
    """Replay the nominal and (when an effect is named) the extended axis."""
    log = d.log
    if log.q_ref is None or log.meta_float("kv") is None:
        return dataclasses.replace(d, forward_note=(
            "not replayed: the log has no q_ref column or no controller gains (kp, kv, ki) "
            "in its metadata (docs/controller.md)"))
    try:
        say("forward view: nominal replay")
        fn = _view(d, build_spec(d, extended=False))
    except (ReplayError, ValueError) as err:
        return dataclasses.replace(d, forward_note=f"not replayed: {err}")
    fe, note = None, ""
    if d.named is not None:
        say(f"forward view: extended replay ({d.named_cause})")
        try:
            n = replay_substeps(d, extended=True)
            fe = _view(d, build_spec(d, extended=True, substeps=n), substeps=n)
        except (ReplayError, ValueError) as err:
            note = f"extended model not replayed: {err}"
    return dataclasses.replace(d, forward_nominal=fn, forward_extended=fe, forward_note=note)


def write_models(d: Diagnosis, out: Path) -> list[Path]:
    """nominal.xml and, when an effect is named, extended.xml (atomic writes)."""
    paths = []
    try:
        nominal_axes.write_xml(build_spec(d, extended=False), out / "nominal.xml")
        paths.append(out / "nominal.xml")
        if d.named is not None:
            nominal_axes.write_xml(build_spec(d, extended=True), out / "extended.xml")
            paths.append(out / "extended.xml")
    except ValueError:
        pass
    return paths


def cross_validate(d: Diagnosis, other: Log, disturbance: np.ndarray | None = None,
                   disturbance_at: str = "link", settings: FilterSettings | None = None) -> dict:
    """Both models of diagnosis `d` (identified and extended on d.log) evaluated, unchanged, on
    another log: the inverse view (relative error of the motor equation, section 4's metric)
    and the forward view (closed-loop replay with `disturbance` applied to the link or
    carriage, or at the motor input: EMPS's pulses are volts at the drive input, already in
    the logged force, so they go in as gtau x pulses at the motor). `settings`: the other
    log's own band (diagnosis_settings(other); d's band when None)."""
    rows = with_parameters(nominal_rows(other, settings or d.settings), d.inverse.nominal.X)
    out: dict = {"inverse": {}, "forward": {}}
    models = {"nominal": None, "extended": d.causes[-1] if d.causes else None}
    for label, c in models.items():
        if label == "extended" and c is None:
            continue
        res = predict(rows, c)
        out["inverse"][label] = {("motor", "link")[int(b)]: rows.relative_error_pct(res, int(b))
                                 for b in np.unique(rows.block)}
    dv = dataclasses.replace(d, log=other)
    for label, ext in (("nominal", False), ("extended", True)):
        if ext and d.named is None:
            continue
        n = replay_substeps(dv, ext)
        f = _view(dv, build_spec(dv, extended=ext, substeps=n), disturbance, disturbance_at, n)
        out["forward"][label] = {"tau_rel_pct": f.tau_rel_pct, "q_m_rms": f.q_m_rms,
                                 "q_m_rel_pct": f.q_m_rel_pct}
    return out
