"""`jointbench survey`: every axis of a robot in turn (the others locked), the chirp
experiment and its identification with the defaults, one table against the truth, one figure
and the logs (bench.campaign.robot_survey; docs/cli.md)."""

from __future__ import annotations

import argparse
import json
import sys

from jointbench.bench.cli.common import EXIT_FAILURE, UsageError, positive, seed

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.bench.api", "jointbench.bench.campaign.robot_survey", "jointbench.bench.present.survey")


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


def run(args: argparse.Namespace) -> int:
    """Parse, `jointbench.survey` into --out (checked first, written all or nothing); print
    the text or the JSON object. Exit 1 when an axis failed (its reason in the table)."""
    from jointbench.bench.api import survey
    from jointbench.bench.campaign.spec import MIN_DURATION_S

    if args.duration < MIN_DURATION_S:
        raise UsageError(f"--duration {args.duration:g}: must be at least {MIN_DURATION_S:g} s "
                         "(the chirp fades in and out over 2 s each)")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers {args.workers}: must be >= 1")
    joints = [j.strip() for j in args.joints.split(",")] if args.joints else None
    if joints is not None and not all(joints):
        raise UsageError(f"--joints {args.joints!r}: an empty axis name")
    sv = survey(args.model, joints, duration=args.duration, seed=args.seed,
                workers=args.workers, out=args.out, progress=_progress(args))
    if args.json:
        print(json.dumps(sv.to_json(), allow_nan=False))
    else:
        print(sv.table())
    for j in sv.failed:
        print(f"jointbench survey: error: {j.joint}: {j.reason}", file=sys.stderr)
    return EXIT_FAILURE if sv.failed else 0
