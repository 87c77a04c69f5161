"""The lean estimator's cost, as ratios measured in one run (`make bench`).

On one 60 s prototype log (seed 1, the bench's defaults), best of N wall times
(time.perf_counter) in this process:
- `identify(log, "joint-motor")` with every default correction against the paper's chain
  alone (`corrections=()`, `identify --plain`): target <= 5x;
- `identify(log, "motor-only")` against its plain chain: target <= 8x;
- the plain joint-motor chain against five `scipy.signal.sosfiltfilt` passes of the paper's
  Butterworth (order 4, 176 rad/s) over the same log: target <= 3x.
The script prints figures and ratios; it asserts nothing (timings depend on the machine and
its load, and no unit test holds one).
"""

from __future__ import annotations

import time

import numpy as np
from scipy import signal

from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.filter_choice import PAPER_WN
from jointbench.identification.identify import identify

REPEATS = 5
TARGETS = {"joint-motor / plain": 5.0, "motor-only / plain": 8.0,
           "plain / five sosfiltfilt": 3.0}


def best_of(fn, repeats: int = REPEATS) -> float:
    """The least wall time [s] of `repeats` calls of fn()."""
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def five_passes(log) -> None:
    """Five zero-phase Butterworth passes over the log's columns (q_m, q, tau_m, q_ref, q_m)."""
    sos = signal.butter(4, PAPER_WN * log.ts / np.pi, output="sos")
    for x in (log.q_m, log.q, log.tau_m, log.q_ref, log.q_m):
        signal.sosfiltfilt(sos, x)


def main() -> None:
    log = run_experiment("prototype", duration=60.0, seed=1).log
    t = {"joint-motor": best_of(lambda: identify(log, "joint-motor")),
         "motor-only": best_of(lambda: identify(log, "motor-only")),
         "plain joint-motor": best_of(lambda: identify(log, "joint-motor", corrections=())),
         "plain motor-only": best_of(lambda: identify(log, "motor-only", corrections=())),
         "five sosfiltfilt": best_of(lambda: five_passes(log))}
    for name, wall in t.items():
        print(f"{name:>20}: {1e3 * wall:8.1f} ms (best of {REPEATS}, {len(log)} samples)")
    ratios = {"joint-motor / plain": t["joint-motor"] / t["plain joint-motor"],
              "motor-only / plain": t["motor-only"] / t["plain motor-only"],
              "plain / five sosfiltfilt": t["plain joint-motor"] / t["five sosfiltfilt"]}
    for name, r in ratios.items():
        print(f"{name:>26}: {r:6.1f}x (target <= {TARGETS[name]:g}x)")


if __name__ == "__main__":
    main()
