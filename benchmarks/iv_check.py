"""How often the instruments' check (identification/iv_check.py) fires on clean logs, and that it
fires where the instruments go wrong.

    .venv/bin/python benchmarks/iv_check.py [--seeds 1-3] [--duration 60]

Clean logs, joint-motor model, defaults: the bench's prototype and the six-axis arm's axes 2
and 4 (MuJoCo), with the bench's torque noise and without it; the independent simulator's
families balanced, soft, wrist, pendulum and heavy_link (jointbench.testing.IndepRunner, their
default frictions), with and without velocity feed-forward, torque noise on and off. Then
the case the check is for: heavy_link and pendulum without link Coulomb friction (FS = 0),
without feed-forward, ideal sensors. Printed per group: the fits tested (one per band
fitted), how many passed the first test's threshold z* (3.59: a false-alarm rate of 1e-3 per
fit when both estimates are consistent), the largest z, and what was kept. Logs that only
the noise's seed tells apart (noise off) are identical across seeds and counted once.
"""

from __future__ import annotations

import argparse
import hashlib
from dataclasses import replace

import numpy as np

import jointbench.identification.identify as identify_module
from jointbench.identification.identify import identify
from jointbench.identification.iv_check import z_threshold
from jointbench.identification.log import Log


def _seeds(text: str) -> list[int]:
    a, _, b = text.partition("-")
    return list(range(int(a), int(b or a) + 1))


class Spy:
    """Records every `compare` that identify makes (the first test of each band's fit, and
    the restart's when the first fires)."""

    def __init__(self):
        self.calls: list = []
        self._orig = identify_module.compare

    def __enter__(self):
        def spy(a, b, *args, **kwargs):
            gap = self._orig(a, b, *args, **kwargs)
            self.calls.append(gap)
            return gap
        identify_module.compare = spy
        return self

    def __exit__(self, *exc):
        identify_module.compare = self._orig


def _digest(log: Log) -> str:
    return hashlib.sha1(np.ascontiguousarray(log.tau_m).tobytes()
                        + np.ascontiguousarray(log.q_m).tobytes()).hexdigest()


def measure(log: Log) -> dict:
    """One log: the first tests' z (one per band fitted), fired or not, and what was kept."""
    with Spy() as spy:
        result = identify(log, "joint-motor")
    truth = log.truth()
    firsts, z_star = [], z_threshold()
    i = 0
    while i < len(spy.calls):   # a fired first test is followed by its restart's test
        gap = spy.calls[i]
        firsts.append(gap)
        i += 2 if gap is not None and gap.fired and i + 1 < len(spy.calls) else 1
    rejected = any(w.startswith("instruments from q_ref rejected") for w in result.warnings)
    kept = any(w.startswith("instruments and least squares disagree") for w in result.warnings)
    return {"z": [g.z for g in firsts if g is not None],
            "fired": sum(g is not None and g.z > z_star for g in firsts),
            "outcome": "rejected" if rejected else "kept, warned" if kept else "",
            "err": {p: 100 * (result.physical[p] / truth[p] - 1) for p in ("K", "Jm", "JL")}}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1-3")
    ap.add_argument("--duration", type=float, default=60.0)
    args = ap.parse_args(argv)
    from jointbench.bench.campaign.battery import Place
    from jointbench.bench.sim.experiment import run_experiment
    from jointbench.bench.sim.sensors import Sensors
    from jointbench.testing import BATTERY_FAMILIES, IndepRunner, simulate

    groups: dict[str, list[dict]] = {}
    seen: set[str] = set()

    def add(group: str, log: Log) -> None:
        key = _digest(log)
        if key in seen:
            return
        seen.add(key)
        row = measure(log)
        groups.setdefault(group, []).append(row)
        print(f"  {group}: z {', '.join(f'{z:.2f}' for z in row['z'])} {row['outcome']}",
              flush=True)

    seeds = _seeds(args.seeds)
    for seed in seeds:
        for model, joint in (("prototype", None), ("arm6", "axis2"), ("arm6", "axis4")):
            noisy = run_experiment(model, joint, duration=args.duration, seed=seed).log
            add(f"{model}{'/' + joint if joint else ''}, noise on", noisy)
            quiet = replace(Sensors.from_log(noisy), torque_noise_std=0.0)
            add(f"{model}{'/' + joint if joint else ''}, noise off",
                run_experiment(model, joint, duration=args.duration, seed=seed,
                               sensors=quiet).log)
    runner = IndepRunner(args.duration)
    for seed in seeds:
        for ff in (True, False):
            for noise in (True, False):
                for fam in ("balanced", "soft", "wrist", "pendulum", "heavy_link"):
                    place = Place("indep", fam, gravity=fam == "pendulum")
                    add(f"indep {fam}, {'ff' if ff else 'no ff'}, noise "
                        f"{'on' if noise else 'off'}", runner.log(place, (), seed, ff, noise))
    for fam in ("heavy_link", "pendulum"):
        add(f"indep {fam}, FS = 0, no ff, ideal sensors",
            simulate(replace(BATTERY_FAMILIES[fam], FS=0.0), seed=1, duration=args.duration,
                     feedforward=False, ideal_sensors=True))
    print(f"\n| logs | distinct logs | fits tested | first test fired (z > {z_threshold():.2f}) "
          "| max z | outcome | max abs K, Jm, JL error % |")
    print("|---|---|---|---|---|---|---|")
    for group, rows in groups.items():
        zs = [z for r in rows for z in r["z"]]
        outcomes = sorted({r["outcome"] for r in rows if r["outcome"]}) or ["instruments"]
        worst = [max(abs(r["err"][p]) for r in rows) for p in ("K", "Jm", "JL")]
        print(f"| {group} | {len(rows)} | {len(zs)} | {sum(r['fired'] for r in rows)} | "
              f"{max(zs, default=float('nan')):.2f} | {', '.join(outcomes)} | "
              f"{', '.join(f'{w:.2f}' for w in worst)} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
