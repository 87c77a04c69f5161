"""`jointbench diagnose FILE`: what the simulation gets wrong on a log, the named causes, the
extended model and its gain (docs/cli.md), optionally cross-validated on another log. With
`--model ROBOT.xml` the user's MJCF is the nominal (bench.analysis.diagnose.against_model)."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Callable

from jointbench.bench.cli.common import UsageError, finite, parse_config

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.bench.api", "jointbench.bench.analysis.diagnose.forward",
           "jointbench.bench.analysis.diagnose.run")
AGAINST_MODEL = ("jointbench.bench.analysis.diagnose.against_model",
                 "jointbench.bench.analysis.diagnose.model_report")


def library(args: argparse.Namespace) -> tuple[str, ...]:
    """The modules `run` imports for these arguments."""
    return LIBRARY + (AGAINST_MODEL if getattr(args, "model", None) else ())


def add_arguments(g: argparse.ArgumentParser) -> None:
    """The options of `diagnose`."""
    g.add_argument("file", nargs="+",
                   help="log file (docs/log-format.md); several: runs of one axis, each "
                        "diagnosed and cross-validated on the next, a cause named only where "
                        "every run names it")
    g.add_argument("--out", help="folder for figures, report.md, nominal.xml, extended.xml "
                                 "(with --model: corrected.xml, extended.xml, report.md)")
    g.add_argument("--model", metavar="ROBOT.xml",
                   help="compare with this MJCF (axis convention; prototype, arm6 or a file): "
                        "its parameter errors, corrected.xml and extended.xml")
    g.add_argument("--joint", help="--model: the axis the log moves, by name or index from 1 "
                                   "(default: the log's joint metadata, else the first)")
    g.add_argument("--config", help="--model: locked angles of the other axes, e.g. "
                                    "axis2=-0.5,axis3=1.0 (default: the log's locked_config)")
    g.add_argument("--json", action="store_true", help="print the JSON object of docs/cli.md")
    g.add_argument("--no-forward", action="store_true",
                   help="skip the closed-loop replay (forward view)")
    g.add_argument("--quiet", action="store_true", help="no progress messages")
    g.add_argument("--validate", metavar="OTHER.csv",
                   help="cross-validation: evaluate the nominal and extended models, identified "
                        "on FILE, on this other log (inverse and forward views)")
    g.add_argument("--disturbance-column", metavar="COL",
                   help="a column of the --validate log applied as a disturbance in its replay")
    g.add_argument("--disturbance-gain", type=finite, default=1.0,
                   help="scale of the disturbance column (default 1; EMPS pulses are volts: "
                        "35.15065188 N/V)")
    g.add_argument("--disturbance-at", choices=("link", "motor"), default="link",
                   help="where the disturbance acts: on the link/carriage or added to the motor "
                        "command (default link)")


def _progress(args: argparse.Namespace) -> Callable[[str], None]:
    """Progress lines on stderr, or nothing with --json or --quiet."""
    if args.json or args.quiet:
        return lambda msg: None
    return lambda msg: print(f"diagnose: {msg}", file=sys.stderr, flush=True)


def _warn(text: str) -> None:
    print(f"jointbench diagnose: warning: {text}", file=sys.stderr)


def _check_options(args: argparse.Namespace) -> None:
    """UsageError for options that apply only with another one."""
    if args.model:
        if args.disturbance_column:
            raise UsageError("--disturbance-column does not apply with --model")
    elif args.joint or args.config:
        raise UsageError("--joint and --config apply with --model")
    elif args.disturbance_column and not args.validate:
        raise UsageError("--disturbance-column applies to the --validate log")


def run(args: argparse.Namespace) -> int:
    """Parse, `jointbench.diagnose` (cross-validated, against --model, written to --out as
    asked), print the summary or the JSON object."""
    from jointbench.bench.api import diagnose

    _check_options(args)
    if len(args.file) > 1:
        if args.model or args.validate or args.out:
            raise UsageError("several files: each run is cross-validated on the next; "
                             "--model, --validate and --out apply to one file")
        runs = diagnose(list(args.file), forward=not args.no_forward,
                        progress=_progress(args), warn=_warn)
        print(json.dumps(runs.to_json(), allow_nan=False) if args.json else runs.table())
        return 0
    d = diagnose(args.file[0], forward=not args.no_forward, progress=_progress(args),
                 model=args.model, joint=args.joint, config=parse_config(args.config),
                 validate=args.validate, disturbance_column=args.disturbance_column,
                 disturbance_gain=args.disturbance_gain, disturbance_at=args.disturbance_at,
                 out=args.out, warn=_warn)
    if args.json:
        print(json.dumps(d.to_json(), allow_nan=False))
    else:
        print(d.table())
    return 0
