"""The hidden-effect battery of `diagnose`, printed as a confusion table.

    .venv/bin/python benchmarks/diagnose_battery.py [--per-effect 5] [--clean 10] [--seed 2026] [--forward]

For every case: a seeded virtual experiment hides one effect (or none) at a random strength
(bench.battery), only the log goes to diagnose, and the named cause, the identified parameter
against the hidden one and the gain (error metric before / after in the view the effect
perturbs) are recorded.
"""

from __future__ import annotations

import argparse
import sys
import time

from jointbench.bench.campaign.battery import cases, confusion, run_case
from jointbench.bench.analysis.diagnose import diagnose
from jointbench.identification.effects import EFFECTS, NONE


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-effect", type=int, default=5)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--clean", type=int, default=10, help="clean cases (default 10)")
    ap.add_argument("--forward", action="store_true", help="also replay (forward view)")
    ap.add_argument("--duration", type=float, default=40.0)
    args = ap.parse_args(argv)
    battery = cases(args.per_effect, args.seed, clean=args.clean)
    results, bad = [], []
    t0 = time.perf_counter()
    print(f"{'case':44s} {'named':20s} {'param':>10s} {'hidden':>10s} {'err %':>7s} "
          f"{'gain':>6s}")
    for c in battery:
        log = run_case(c, args.duration)
        d = diagnose(log, forward=args.forward)
        named = d.named_cause
        results.append((c.effect, named))
        err = gain = float("nan")
        value = float("nan")
        if c.effect != NONE and named == c.effect:
            value = d.extended_parameters[EFFECTS[c.effect].parameter]
            err = 100 * (value - c.strength) / abs(c.strength)
            before, after = d.inverse_before_after
            gain = before / after
        ok = named == c.effect and (c.effect == NONE or (abs(err) <= 20 and gain >= 2))
        if not ok:
            bad.append(c.label)
        print(f"{c.label:44s} {named:20s} {value:10.4g} {c.strength:10.4g} {err:7.1f} "
              f"{gain:6.2f} {'' if ok else '  <-- miss'}", flush=True)
    wall = time.perf_counter() - t0
    labels, M = confusion(results)
    print(f"\nconfusion (rows: hidden, columns: named), {len(battery)} cases, {wall:.0f} s")
    short = [lab[:8] for lab in labels]
    print(f"{'':20s}" + "".join(f"{s:>9s}" for s in short))
    for lab, row in zip(labels, M):
        print(f"{lab:20s}" + "".join(f"{v:9d}" for v in row))
    right = sum(h == n for h, n in results)
    print(f"\ncauses named right: {right}/{len(results)} ({100 * right / len(results):.1f} %); "
          f"all criteria met: {len(results) - len(bad)}/{len(results)}")
    clean = [n for h, n in results if h == NONE]
    print(f"clean cases answered none: {clean.count(NONE)}/{len(clean)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
