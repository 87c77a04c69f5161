"""`jointbench survey`: every axis of a robot in turn (the others locked), the chirp
experiment and its identification with the defaults, one table against the truth, one figure
and the logs (bench.campaign.survey; docs/cli.md)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from jointbench.bench.cli.common import EXIT_FAILURE, UsageError, positive, seed

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.bench.campaign.survey", "jointbench.bench.present.survey")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of `survey`."""
    p.add_argument("--model", default="arm6",
                   help="arm6 (default), prototype or an MJCF file following the axis "
                        "convention (README)")
    p.add_argument("--joints", help="the axes to survey, by name or index from 1, e.g. "
                                    "axis1,axis4 (default: every axis)")
    p.add_argument("--duration", type=positive, default=60.0,
                   help="chirp experiment per axis, seconds (default 60)")
    p.add_argument("--seed", type=seed, default=0,
                   help="noise seed, the same for every axis (default 0): axis J's log is "
                        "`simulate --model M --joint J --seed N`'s")
    p.add_argument("--out", default="survey_out",
                   help="folder for survey.csv, survey.png and logs/AXIS.csv "
                        "(default survey_out)")
    p.add_argument("--workers", type=int, default=None,
                   help="processes, one axis each at a time (default: every core, at most "
                        "one per axis; 1: in this process)")
    p.add_argument("--json", action="store_true", help="print the JSON object of docs/cli.md")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def _progress(args: argparse.Namespace):
    """A line on stderr per finished axis, or nothing with --json or --quiet."""
    if args.json or args.quiet:
        return None

    def say(j, done: int, total: int) -> None:
        k = j.estimates.get("K")
        what = "failed" if j.status != "ok" else j.model + (
            f", K {k.error_pct:+.2f} %" if k is not None and k.error_pct is not None else "")
        print(f"survey: {j.joint} done ({done}/{total}): {what}", file=sys.stderr, flush=True)
    return say


def _check_memory(axes: int, duration: float, rate_hz: float, workers: int | None) -> None:
    """Before any run: this process holds every axis's log and, with workers (as many as
    run_survey starts: at most one per axis), each worker also holds one axis's experiment
    and identification beside its own interpreter (bench.cli.resources' figures per sample
    and per process). UsageError over the limit, in MB."""
    import os

    from jointbench.bench.cli.resources import (BASE_MB, BYTES_PER_SAMPLE, MEMORY_ENV,
                                                check_memory, memory_limit_mb)

    samples = duration * rate_hz
    what = f"--duration {duration:g} s on {axes} axes"
    used = max(1, min(workers or os.cpu_count() or 1, axes))
    if used == 1:
        check_memory(axes * samples, what)
        return
    mb = samples * BYTES_PER_SAMPLE / 2**20            # one axis's samples
    need = BASE_MB + axes * mb + used * (BASE_MB + mb)
    limit = memory_limit_mb()
    if not need <= limit:
        raise UsageError(f"{what} with {used} workers: about {need:,.0f} MB of memory "
                         f"({BASE_MB + axes * mb:,.0f} MB here and {BASE_MB + mb:,.0f} MB per "
                         f"worker), over the {limit:,.0f} MB limit (set {MEMORY_ENV} to raise "
                         "it, or give fewer --workers)")


def run(args: argparse.Namespace) -> int:
    """Survey the axes into --out (checked first, written all or nothing); print the text
    or the JSON object. Exit 1 when an axis failed (its reason in the table)."""
    from jointbench.bench.campaign.spec import MIN_DURATION_S
    from jointbench.bench.campaign.survey import run_survey, survey_axes
    from jointbench.bench.output import OutputFolder
    from jointbench.bench.present.survey import FILES, survey_json, survey_text, write_survey
    from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ

    if args.duration < MIN_DURATION_S:
        raise UsageError(f"--duration {args.duration:g}: must be at least {MIN_DURATION_S:g} s "
                         "(the chirp fades in and out over 2 s each)")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers {args.workers}: must be >= 1")
    joints = [j.strip() for j in args.joints.split(",")] if args.joints else None
    if joints is not None and not all(joints):
        raise UsageError(f"--joints {args.joints!r}: an empty axis name")
    _, names = survey_axes(args.model, joints)       # ModelStructureError: exit 2, before work
    out = Path(args.out)
    folder = OutputFolder(out, FILES)
    _check_memory(len(names), args.duration, SAMPLE_RATE_HZ, args.workers)
    sv = run_survey(args.model, joints, duration=args.duration, seed=args.seed,
                    workers=args.workers, progress=_progress(args))
    with folder.writing() as path:
        write_survey(sv, path)
    if args.json:
        print(json.dumps(survey_json(sv, out), allow_nan=False))
    else:
        print(survey_text(sv, out))
    for j in sv.failed:
        print(f"jointbench survey: error: {j.joint}: {j.reason}", file=sys.stderr)
    return EXIT_FAILURE if sv.failed else 0
