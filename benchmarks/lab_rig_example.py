"""The README's lab-rig example: two runs of the independent simulator's lab-rig family
(jointbench.testing.simulate_lab_rig, springs with their own damping D = 0.0025 N m s/rad)
written as the lab stores them, MATLAB files with the servo angle theta, the spring
deflection alpha, the voltage u and the reference r.

    .venv/bin/python benchmarks/lab_rig_example.py OUT_DIR

then, in OUT_DIR, the README's `jointbench import`, `identify` and `diagnose` commands.
"""

from __future__ import annotations

import sys
from pathlib import Path

import scipy.io as sio

from jointbench.testing import simulate_lab_rig

RUNS = (("run40", 40.0, 40), ("run80", 80.0, 80))   # name, duration [s], seed


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print(__doc__)
        return 2
    out = Path(argv[0])
    out.mkdir(parents=True, exist_ok=True)
    for name, duration, seed in RUNS:
        log = simulate_lab_rig(seed=seed, duration=duration, effects="spring_damping=0.0025")
        sio.savemat(out / f"{name}.mat",
                    {"time": log.t[:, None], "theta": log.extra["theta"][:, None],
                     "alpha": log.extra["alpha"][:, None], "u": log.extra["u"][:, None],
                     "r": log.q_ref[:, None]})
        print(f"wrote {out / name}.mat ({duration:g} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
