"""The replays of `diagnose --model` and their noise floor.

`replay_model` replays a log's experiment in closed loop on an axis of an MJCF file (the log's
reference, gains and encoder resolutions; bench.sim.replay). It adds no torque noise by
default: the log's noise realisation is unknown. So even a perfect model leaves a torque error,
the closed-loop response to the log's own torque noise: the replay's noise floor. A forward
gain (wrong model / corrected) cannot exceed err_wrong / floor.

`replay_floor` estimates that floor from the log alone (no true model):
1. the torque noise level: the robust scale (median absolute deviation) of the motor equation's
   residual in the identification (eq. 13, filtered and decimated), over the standard
   deviation of unit white noise sent through the same filter chain: the noise is assumed
   white and normal at the sample rate, as a current loop's is. The median ignores the rows
   near velocity reversals, where the Coulomb model of eq. (13) is wrong (there the residual
   is 1.4-1.7 x the noise on the arm6 joints). On the prototype and the arm6 joints it gives
   0.96-1.07 x the noise the log declares; the residual's RMS would give 1.01-1.19 x;
2. the floor: the corrected model replayed with white torque noise of that level (seeded) and
   without, their torque difference in % RMS of the logged torque, combined over FLOOR_SEEDS.
   On the same logs: 0.975-1.058 x the true model's replay error
   (benchmarks/diagnose_model.py).

The excess over the floor, sqrt(err^2 - floor^2), is the part of a replay error a better model
can remove (noise response and model error add in power: they are uncorrelated).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from jointbench.bench.analysis.diagnose.forward import replay_tau0
from jointbench.bench.effects import loop_effects_from_model
from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.sim.replay import ReplayResult, replay
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.filtering import decimate_parallel, lowpass, zoh_align
from jointbench.identification.identify import Identification
from jointbench.identification.log import Log
from jointbench.identification.output_values import rms

FLOOR_SEEDS = (1, 2)   # noise realisations of the floor (each one replay)


def replay_model(path: Path, joint: str, config: dict[str, float], log: Log,
                 noise_std: float = 0.0, seed: int = 0) -> ReplayResult:
    """Replay `log` on axis `joint` of the MJCF at `path` (locked at `config`) in closed loop
    with the log's reference, gains and encoder resolutions (exact encoders when the log does
    not give them), adding white torque noise of `noise_std` [N m or N] seeded by `seed`.
    Raises ReplayError, ValueError (bench.sim.replay)."""
    exp = build_experiment_model(path, joint, config=config, sample_rate_hz=1.0 / log.ts,
                                 tau_max=log.meta_float("tau_max"))
    sensors = Sensors.from_log(log)
    if sensors is not None or noise_std > 0:
        sensors = dataclasses.replace(sensors or Sensors.ideal(), torque_noise_std=noise_std)
    return replay(exp.model, exp.axis, log, tau0=replay_tau0(log),
                  loop=loop_effects_from_model(exp.model, joint), sensors=sensors, seed=seed)


def _torque_chain(x: np.ndarray, ident: Identification) -> np.ndarray:
    """`x` through the torque's filter chain of the joint-motor regressor (Butterworth,
    zero-order-hold alignment, parallel decimation: identification.regressors)."""
    s = ident.settings
    if s.zoh and s.stencil == 5:
        x = zoh_align(lowpass(x, s.wn, s.ts, s.m), exact=True, ts=s.ts)
    else:
        x = lowpass(zoh_align(x) if s.zoh else x, s.wn, s.ts, s.m)
    return decimate_parallel(x, np.zeros((len(x), 1)), s)[0]


CALIBRATION_SAMPLES = 2 ** 20   # white noise through the chain: its scale to 0.1 %
MAD_NORMAL = 0.6744897501960817  # median absolute deviation of a unit normal variable


def _mad(x: np.ndarray) -> float:
    return float(np.median(np.abs(x - np.median(x))))


def torque_noise_std(log: Log, ident: Identification) -> float:
    """The log's torque noise standard deviation [N m or N] at the sample rate (module
    docstring, step 1): the residual's median absolute deviation over that of a normal
    variable with the chain's gain (measured on CALIBRATION_SAMPLES of seeded white noise);
    NaN unless the identification is the joint-motor model."""
    if ident.model != "joint-motor":
        return math.nan
    rows = ident.block == 0
    residual = ident.y[rows] - ident.y_pred[rows]
    white = _torque_chain(np.random.default_rng(0).standard_normal(CALIBRATION_SAMPLES), ident)
    gain = float(np.std(white))
    return _mad(residual) / (MAD_NORMAL * gain) if gain > 0 else math.nan


def replay_floor(path: Path, joint: str, config: dict[str, float], log: Log,
                 clean: ReplayResult, noise_std: float) -> float:
    """The replay's noise floor [% RMS of the logged torque] (module docstring, step 2):
    the model at `path` replayed with torque noise `noise_std` against its replay without
    (`clean`). NaN when the noise level is not known."""
    if not (math.isfinite(noise_std) and noise_std > 0):
        return math.nan
    power = [rms(replay_model(path, joint, config, log, noise_std, seed).tau_m - clean.tau_m)
             ** 2 for seed in FLOOR_SEEDS]
    return 100.0 * math.sqrt(float(np.mean(power))) / rms(log.tau_m)


def excess(error_pct: float, floor_pct: float) -> float:
    """The part of a replay's torque error [%] above the noise floor: sqrt(err^2 - floor^2),
    0 when the error is at or under the floor."""
    return math.sqrt(max(error_pct ** 2 - floor_pct ** 2, 0.0))
