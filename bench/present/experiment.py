"""A virtual experiment (`bench.sim.experiment.run_experiment`) summarised: what
`jointbench simulate` prints, as text or JSON, and its warnings about the torque limit and a soft MuJoCo friction."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from jointbench.bench.sim.experiment import ExperimentResult
from jointbench.bench.sim.friction import friction_bands, soft_friction_warnings


def saturation_warnings(result: ExperimentResult) -> list[str]:
    """Warnings about the torque limit in a virtual experiment (also in the log metadata:
    saturated_samples, actuator_clamped_samples)."""
    out = []
    n = len(result.log)
    if result.saturated:
        tau_max = result.log.meta_float("tau_max")
        hit = np.flatnonzero(np.abs(result.log.tau_m) >= (tau_max or np.inf))
        first = f", first at t = {result.log.t[hit[0]]:.4g} s" if hit.size else ""
        out.append(f"the torque command saturated at tau_max on {result.saturated} of {n} "
                   f"samples ({100 * result.saturated / n:.2g} %{first}); the logged tau_m is "
                   "the clipped command")
    if getattr(result, "clamped", 0):
        out.append(f"MuJoCo's actuator ctrlrange cut the applied torque (command plus noise) on "
                   f"{result.clamped} of {n} samples")
    return out + friction_warnings(result)


def friction_warnings(result: ExperimentResult) -> list[str]:
    """bench.sim.friction's check on the experiment's model and true velocities."""
    exp, log = result.experiment, result.log
    bands = friction_bands(exp.model, exp.axis.motor_dof, exp.axis.link_dof)
    rate = log.sample_rate_hz
    v_link = np.diff(result.q_true) * rate if result.q_true is not None else None
    return soft_friction_warnings(bands, np.diff(result.q_m_true) * rate, v_link,
                                  result.tau_applied[1:], 1.0 / rate)


def experiment_json(result: ExperimentResult, out: Path, warnings: list[str]) -> dict:
    """The JSON summary of `simulate --json`: the log written to `out`, its length, joint,
    first mode (null for a rigid axis), saturated samples, hidden effect and warnings."""
    log = result.log
    f1 = float(log.meta["truth_f1_hz"])
    return {"out": str(out), "samples": len(log), "duration_s": float(log.t[-1]),
            "joint": log.meta["joint"], "f1_hz": f1 if math.isfinite(f1) else None,
            "saturated_samples": result.saturated,
            "effect": log.meta.get("truth_effect", "none"), "warnings": warnings}


def experiment_text(result: ExperimentResult, out: Path) -> str:
    """The one-line summary `simulate` prints."""
    log = result.log
    f1 = float(log.meta["truth_f1_hz"])
    return (f"wrote {out}: {len(log)} samples over {log.t[-1]:.2f} s at "
            f"{log.sample_rate_hz:g} Hz, joint {log.meta['joint']} "
            f"({f'f1 = {f1:.3f} Hz' if math.isfinite(f1) else 'rigid axis'}), "
            f"saturated samples: {result.saturated}, "
            f"effect: {log.meta.get('truth_effect', 'none')}")
