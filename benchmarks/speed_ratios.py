"""The estimator's cost as ratios measured in one run (`make bench`; docs/validation.md,
section speed-ratios, through benchmarks/validate.py).

On one 60 s prototype log (seed 1, the bench's defaults), in this process, each figure the
least of N calls (wall time, time.perf_counter; the process's CPU time, time.process_time,
beside it: the machine is shared, and the CPU time is what the load changes least):

- `identify(log, "joint-motor")`, every default correction, over the plain chain
  `identify(log, "joint-motor", corrections=())` (`identify --plain`): target <= 5x;
- `identify(log, "motor-only")` over its plain chain: <= 8x;
- the plain joint-motor chain over five `scipy.signal.sosfiltfilt` passes of the paper's
  Butterworth (order 4, 176 rad/s) over the log: <= 3x;
- `diagnose(log)`, forward view included, over the plain joint-motor chain: <= 20x;
- `debias(log, ident, replicas=8)` over the time its 8 replays (the experiments) take
  inside it: <= 2x.

Besides, the floors under the plain chain: the first mode measured alone (the band is
designed from it), the plain chain with f1 given (`--f1`, no measurement), and the filtering
eq. (13)'s chain cannot do without at the chooser's band (three Butterworth passes, q_m, q,
tau_m, and the decimation of y and the ten columns of the two equations that are not zero,
each a zero-phase order-8 Chebyshev pass); and the full joint-motor fit with one correction
switched off at a time (what each costs); and diagnose without its forward view (the forward
view's MuJoCo replays are what is left), and under those replays the physics alone: one
replay's MuJoCo steps (the log's samples x its plant's substeps, one C call, no controller),
the floor no forward view at the plant's discretisation can go under. The verdict is read on the CPU-time ratio (the
machine is shared: wall times there swing with the other processes). The script prints
figures and ratios and asserts nothing: timings depend on the machine and its load, and no
unit test holds one.
"""

from __future__ import annotations

import copy
import os
import time

import mujoco

import numpy as np
from scipy import signal

import jointbench.bench.analysis.debias as debias_module
from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.forward import plant_substeps
from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.corrections import CORRECTIONS
from jointbench.identification.filter_choice import PAPER_WN, choose_filter
from jointbench.identification.filtering import decimate, lowpass
from jointbench.identification.first_mode import measure_first_mode
from jointbench.identification.identify import identify

REPEATS = 7
SLOW_REPEATS = 3   # diagnose, the corrections one at a time
TARGETS = {"joint-motor / plain": 5.0, "motor-only / plain motor-only": 8.0,
           "plain / five sosfiltfilt": 3.0, "diagnose / plain": 20.0,
           "debias 8 / its 8 experiments": 2.0}


def best_of(fn, repeats: int = REPEATS) -> tuple[float, float]:
    """(least wall time [s], least CPU time [s]) of `repeats` calls of fn()."""
    wall = cpu = np.inf
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall = min(wall, time.perf_counter() - w0)
        cpu = min(cpu, time.process_time() - c0)
    return wall, cpu


def five_passes(log) -> None:
    """Five zero-phase Butterworth passes over the log's columns (q_m, q, tau_m, q_ref, q_m)."""
    sos = signal.butter(4, PAPER_WN * log.ts / np.pi, output="sos")
    for x in (log.q_m, log.q, log.tau_m, log.q_ref, log.q_m):
        signal.sosfiltfilt(sos, x)


def chain_filtering(log, settings) -> None:
    """The plain joint-motor chain's filtering alone: the Butterworth on q_m, q, tau_m and the
    decimation of eleven columns (y and the ten non-zero columns of eq. 13's two equations,
    here stand-ins of the log's length)."""
    for x in (log.q_m, log.q, log.tau_m):
        lowpass(x, settings.wn, settings.ts, settings.m)
    decimate(np.column_stack([log.q_m] * 11), settings.Nd, axis=0)


def replay_steps(model: mujoco.MjModel, log) -> None:
    """The physics of one replay of the log and nothing else: len(log) x the plant's substeps
    MuJoCo steps (`plant_substeps`, the discretisation the forward view replays with) in one
    C call, from rest, with no controller, sensors or Python per tick."""
    m = copy.deepcopy(model)
    m.opt.timestep = log.ts / plant_substeps(log)
    mujoco.mj_step(m, mujoco.MjData(m), nstep=len(log) * plant_substeps(log))


def debias_times(log, ident) -> tuple[float, float, float, float]:
    """(wall, CPU) of `debias(log, ident, replicas=8)` and (wall, CPU) of its 8 replays,
    timed where debias calls them (bench.sim.replay.replay)."""
    spent = [0.0, 0.0]
    replay = debias_module.replay

    def timed(*args, **kw):
        w0, c0 = time.perf_counter(), time.process_time()
        try:
            return replay(*args, **kw)
        finally:
            spent[0] += time.perf_counter() - w0
            spent[1] += time.process_time() - c0

    debias_module.replay = timed
    try:
        w0, c0 = time.perf_counter(), time.process_time()
        debias_module.debias(log, ident, replicas=8)
        return time.perf_counter() - w0, time.process_time() - c0, spent[0], spent[1]
    finally:
        debias_module.replay = replay


def main() -> None:
    threads = {k: os.environ[k] for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                          "MKL_NUM_THREADS") if k in os.environ}
    print(f"BLAS threads: {threads or 'library default'}; load average "
          f"{os.getloadavg()[0]:.1f} at the start")
    log = run_experiment("prototype", duration=60.0, seed=1).log
    f1 = measure_first_mode(log).f1_hz
    chooser = choose_filter(log, f1).settings
    calls = {
        "five sosfiltfilt": lambda: five_passes(log),
        "the plain chain's filtering": lambda: chain_filtering(log, chooser),
        "first mode alone": lambda: measure_first_mode(log),
        "plain joint-motor": lambda: identify(log, "joint-motor", corrections=()),
        "plain joint-motor, f1 given": lambda: identify(log, "joint-motor", f1_hz=f1,
                                                        corrections=()),
        "plain motor-only": lambda: identify(log, "motor-only", corrections=()),
        "joint-motor": lambda: identify(log, "joint-motor"),
        "motor-only": lambda: identify(log, "motor-only"),
    }
    t = {name: best_of(fn) for name, fn in calls.items()}
    for c in ("stick_phases", "reversals", "wide_band", "instruments", "stencil5"):
        rest = tuple(n for n in CORRECTIONS if n != c)
        t[f"joint-motor without {c}"] = best_of(
            lambda: identify(log, "joint-motor", corrections=rest), SLOW_REPEATS)
    t["diagnose (forward view included)"] = best_of(lambda: diagnose(log), SLOW_REPEATS)
    t["diagnose, inverse view alone"] = best_of(lambda: diagnose(log, forward=False),
                                                SLOW_REPEATS)
    exp = run_experiment("prototype", duration=60.0, seed=1).experiment
    t["one replay's MuJoCo steps alone"] = best_of(
        lambda: replay_steps(exp.model, log), SLOW_REPEATS)
    ident = identify(log, "joint-motor")
    w, c, rw, rc = debias_times(log, ident)
    t["debias 8"], t["its 8 replays"] = (w, c), (rw, rc)
    print(f"60 s prototype log, {len(log)} samples; least of {REPEATS} calls "
          f"({SLOW_REPEATS} for diagnose and the corrections one at a time, 1 for debias)")
    print(f"{'':>40}  {'wall':>10}  {'CPU':>10}")
    for name, (wall, cpu) in t.items():
        print(f"{name:>40}  {1e3 * wall:7.1f} ms  {1e3 * cpu:7.1f} ms")
    pairs = {"joint-motor / plain": ("joint-motor", "plain joint-motor"),
             "motor-only / plain motor-only": ("motor-only", "plain motor-only"),
             "plain / five sosfiltfilt": ("plain joint-motor", "five sosfiltfilt"),
             "diagnose / plain": ("diagnose (forward view included)", "plain joint-motor"),
             "debias 8 / its 8 experiments": ("debias 8", "its 8 replays")}
    print()
    print("| ratio | CPU | wall | target | met (CPU) |")
    print("| --- | --- | --- | --- | --- |")
    for name, (a, b) in pairs.items():
        rw, rc = t[a][0] / t[b][0], t[a][1] / t[b][1]
        met = "yes" if rc <= TARGETS[name] else "**no**"
        print(f"| {name} | {rc:.1f}x | {rw:.1f}x | <= {TARGETS[name]:g}x | {met} |")
    cpu = {k: v[1] for k, v in t.items()}
    filtering = cpu["the plain chain's filtering"]
    share = cpu["first mode alone"] / cpu["plain joint-motor"]
    print(f"\nfloors (CPU): the first mode is {100 * share:.0f} % of the plain chain; the plain "
          f"chain with f1 given is "
          f"{cpu['plain joint-motor, f1 given'] / cpu['five sosfiltfilt']:.1f}x five sosfiltfilt, "
          f"its filtering alone {filtering / cpu['five sosfiltfilt']:.1f}x")
    replays = cpu["diagnose (forward view included)"] - cpu["diagnose, inverse view alone"]
    print(f"diagnose's forward view (its MuJoCo replays of the log) alone is "
          f"{replays / cpu['plain joint-motor']:.1f}x the plain chain; its inverse view "
          f"{cpu['diagnose, inverse view alone'] / cpu['plain joint-motor']:.1f}x")
    physics = cpu["one replay's MuJoCo steps alone"]
    print(f"the physics floor under the forward view: one replay's MuJoCo steps alone "
          f"({len(log)} samples x {plant_substeps(log)} substeps, the log's plant) are "
          f"{physics / cpu['plain joint-motor']:.1f}x the "
          f"plain chain (the diagnose target: <= {TARGETS['diagnose / plain']:g}x)")


if __name__ == "__main__":
    main()
