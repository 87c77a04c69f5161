"""`jointbench diagnose FILE`: what the simulation gets wrong on a log, the named causes, the
extended model and its gain (docs/cli.md), optionally cross-validated on another log. With
`--model ROBOT.xml` the user's MJCF is the nominal (bench.analysis.diagnose.against_model)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Callable

from jointbench.bench.cli.common import UsageError, finite, parse_config

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.bench.analysis.diagnose.forward",
           "jointbench.bench.analysis.diagnose.run")
AGAINST_MODEL = ("jointbench.bench.analysis.diagnose.against_model",
                 "jointbench.bench.analysis.diagnose.model_report")


def library(args: argparse.Namespace) -> tuple[str, ...]:
    """The modules `run` imports for these arguments."""
    return LIBRARY + (AGAINST_MODEL if getattr(args, "model", None) else ())


def add_arguments(g: argparse.ArgumentParser) -> None:
    """The options of `diagnose`."""
    g.add_argument("file", help="log file (docs/log-format.md)")
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


def _output_folder(args: argparse.Namespace) -> Path | None:
    """--out, checked before any computation (bench.output: a folder, writable, no file in
    it that jointbench would replace and did not write)."""
    from jointbench.bench.analysis.diagnose.report import output_folder

    out = Path(args.out) if args.out else None
    if out is not None:
        output_folder(out)
    return out


def _cross_validation_text(args: argparse.Namespace, xval: dict) -> str:
    """The cross-validation errors, one line per view and model."""
    lines = [f"\ncross-validation on {args.validate} (models identified and extended on "
             f"{args.file}, unchanged):"]
    for view, rows in xval.items():
        for label, vals in rows.items():
            lines.append(f"  {view:8s} {label:9s} " + ", ".join(
                f"{k} {v:.4g}" for k, v in vals.items()))
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Diagnose the log (and cross-validate); print the summary or the JSON object; with
    --out the report files."""
    from jointbench.bench.analysis.diagnose import cross_validate, diagnose, summary_text
    from jointbench.bench.analysis.diagnose.report import write
    from jointbench.bench.analysis.diagnose.run import diagnosis_settings
    from jointbench.identification.log import LogError, read_log
    from jointbench.identification.output import finite_json
    from jointbench.identification.saturation import clipping_warnings

    log = read_log(args.file)
    clipping_warnings(log)   # LogError over a third, before any computation
    if args.model:
        return run_model(args, log)
    if args.joint or args.config:
        raise UsageError("--joint and --config apply with --model")
    say = _progress(args)
    out = _output_folder(args)
    other = read_log(args.validate) if args.validate else None
    if other is not None and Path(args.validate).resolve() == Path(args.file).resolve():
        raise UsageError("--validate must name another log than FILE (cross-validation)")
    dist = None
    if args.disturbance_column:
        if other is None:
            raise UsageError("--disturbance-column applies to the --validate log")
        if args.disturbance_column not in other.extra:
            raise LogError(f"no column '{args.disturbance_column}' (columns: "
                           f"{', '.join(['t', 'q_m', 'tau_m', *other.extra])})", other.path,
                           column=args.disturbance_column)
        dist = args.disturbance_gain * other.extra[args.disturbance_column]
    d = diagnose(log, forward=not args.no_forward, progress=say)
    for text in d.warnings:   # units, clipped torque (left out of the fits)
        print(f"jointbench diagnose: warning: {text}", file=sys.stderr)
    xval = None
    if other is not None:
        say(f"cross-validation on {args.validate} (its own band)")
        xval = cross_validate(d, other, dist, args.disturbance_at, diagnosis_settings(other)[0])
    if out is not None:
        extra = {} if xval is None else {"cross_validation.json": json.dumps(
            finite_json({"file": str(args.validate), **xval}), indent=2, allow_nan=False) + "\n"}
        d = write(d, out, say, extra)
    if args.json:
        doc = d.to_json()
        if xval is not None:
            doc["cross_validation"] = {"file": str(args.validate), **xval}
        print(json.dumps(finite_json(doc), allow_nan=False))
    else:
        print(summary_text(d))
        if xval is not None:
            print(_cross_validation_text(args, xval))
    return 0


def run_model(args: argparse.Namespace, log) -> int:
    """`diagnose FILE --model ROBOT.xml`: the log against the user's MJCF."""
    from jointbench.bench.analysis.diagnose.against_model import diagnose_against_model
    from jointbench.bench.analysis.diagnose.model_report import (output_folder, summary_text,
                                                                 to_json, write)
    from jointbench.identification.log import read_log
    from jointbench.identification.output import finite_json

    if args.disturbance_column:
        raise UsageError("--disturbance-column does not apply with --model")
    say = _progress(args)
    out = Path(args.out) if args.out else None
    if out is not None:
        output_folder(out)
    other = read_log(args.validate) if args.validate else None
    if other is not None and Path(args.validate).resolve() == Path(args.file).resolve():
        raise UsageError("--validate must name another log than FILE (cross-validation)")
    md = diagnose_against_model(log, args.model, args.joint, parse_config(args.config),
                                forward=not args.no_forward, validate=other, progress=say)
    if out is not None:
        md = write(md, out, say)
    if args.json:
        print(json.dumps(finite_json(to_json(md)), allow_nan=False))
    else:
        print(summary_text(md))
    return 0
