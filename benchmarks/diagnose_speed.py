"""`diagnose` time per log (issue 14: under 10 s per 60 s log), on cases of the discrepancy
battery (benchmarks/battery.py): each case's log is made by the battery's runner (strength by
visibility), then `diagnose(log)` is timed alone in this process, wall and CPU.

    .venv/bin/python benchmarks/diagnose_speed.py [--duration 60] [--seed 2026] [CASE ...]

Default cases: a clean log, single effects and the slowest two-effect kinds of the seed-2026
run (indices of `benchmarks/battery.py`'s plan).
"""

from __future__ import annotations

import argparse
import sys
import time

import battery

from jointbench.bench.campaign.battery import plan, run_spec

CASES = (0, 60, 65, 89, 93, 96, 100, 102)


def specs_of(cases: list[int], seed: int) -> list:
    """The battery plan's specs of `cases` (indices of benchmarks/battery.py's plan with
    `seed`); a ValueError naming the first index outside the plan."""
    specs = plan(battery.PLACES, 8, 24, 20, seed)
    bad = [i for i in cases if not 0 <= i < len(specs)]
    if bad:
        raise ValueError(f"case {bad[0]}: no such case (0-{len(specs) - 1})")
    return [specs[i] for i in cases]


def add_case_args(ap: argparse.ArgumentParser) -> None:
    """The arguments both diagnose-speed benchmarks take: the cases, the log length, the seed."""
    ap.add_argument("cases", type=int, nargs="*", default=list(CASES))
    ap.add_argument("--duration", type=float, default=60.0, help="log length [s] (default 60)")
    ap.add_argument("--seed", type=int, default=2026)


def case_specs(args: argparse.Namespace) -> list | None:
    """The specs of `args.cases` with the battery set up for `args.duration`; None, after
    printing why to stderr, when an index is outside the plan."""
    try:
        specs = specs_of(args.cases, args.seed)
    except ValueError as e:
        print(e, file=sys.stderr)
        return None
    battery._init(args.duration)
    return specs


def make_log(spec):
    """The case's log, made by the battery's runner (its strength by visibility)."""
    return run_spec(spec, battery._RUNNERS[spec.place.source], battery._CACHE).log


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_case_args(ap)
    args = ap.parse_args(argv)
    from jointbench.bench.analysis.diagnose import diagnose

    specs = case_specs(args)
    if specs is None:
        return 2
    print(f"diagnose on {args.duration:g} s logs (battery seed {args.seed})")
    worst = 0.0
    for i, s in zip(args.cases, specs):
        log = make_log(s)
        w0, c0 = time.perf_counter(), time.process_time()
        d = diagnose(log)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        worst = max(worst, wall)
        what = "+".join(s.effects) or "clean"
        named = ",".join(battery.named_causes(d)) or "none"
        print(f"#{i:3d} {s.place.family:16s} {what:30s} -> {named:28s} wall {wall:5.1f} s, "
              f"CPU {cpu:5.1f} s")
    print(f"slowest: {worst:.1f} s per {args.duration:g} s log")
    return 0


if __name__ == "__main__":
    sys.exit(main())
