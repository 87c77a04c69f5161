"""`jointbench import BAG --out LOG.csv --joint NAME`: a ROS 2 bag (.db3, .mcap or its folder)
or a ROS 1 .bag converted into a jointbench log (identification/bag_import.py); with
`--survey`, one log per moved joint into the --out folder. The options of `import` that are
not about CSV columns (--gear-ratio, the metadata) apply. Exit 2 naming the missing topic,
joint, field or the damaged file; nothing is written then."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

from jointbench.bench.cli.common import UsageError, check_output_file

# identification.bag_import's defaults, here so that parsing imports no numerics
DEFAULT_TOPIC = "/joint_states"
FIELDS = ("position", "velocity", "effort")
STAMPS = ("header", "receive")


def add_bag_arguments(p: argparse.ArgumentParser) -> None:
    """The options of `import` for a ROS bag."""
    g = p.add_argument_group("ROS bags (.db3, .mcap, a rosbag2 folder, .bag; needs "
                             "jointbench[ros]); --joint NAME names the axis, --motor-side "
                             "defaults to q_m,tau_m")
    g.add_argument("--topic", default=DEFAULT_TOPIC,
                   help=f"sensor_msgs/JointState topic of q (and of q_m, tau_m unless "
                        f"given) (default {DEFAULT_TOPIC})")
    g.add_argument("--link-name", metavar="NAME", help="joint name of the link angle q "
                                                       "(default: --joint)")
    g.add_argument("--motor-name", metavar="NAME", help="joint name of the motor angle q_m "
                                                        "(default: JOINT_motor)")
    g.add_argument("--motor-topic", metavar="TOPIC", help="topic of q_m (default --topic)")
    g.add_argument("--torque-name", metavar="NAME",
                   help="joint name of tau_m (default: the motor name)")
    g.add_argument("--torque-field", choices=FIELDS, default="effort",
                   help="field of tau_m (default effort)")
    g.add_argument("--torque-topic", metavar="TOPIC",
                   help="topic of tau_m, e.g. a torque sensor's JointState (default: the "
                        "motor topic)")
    g.add_argument("--reference-topic", metavar="TOPIC",
                   help="q_ref is the link joint's position on this topic")
    g.add_argument("--reference-name", metavar="NAME",
                   help="joint name of q_ref on --reference-topic (default: the link name)")
    g.add_argument("--stamp", choices=STAMPS, default="header",
                   help="time of a message: its header stamp (default) or the time the "
                        "recorder received it")
    g.add_argument("--survey", action="store_true",
                   help="a survey bag (each joint moved while the others are held): one log "
                        "per moved joint, --out is a folder (JOINT.csv)")


def _spec(args: argparse.Namespace):
    from jointbench.identification.bag_import import BagSpec

    return BagSpec(topic=args.topic, link=args.link_name, motor=args.motor_name,
                   motor_topic=args.motor_topic, torque=args.torque_name,
                   torque_field=args.torque_field, torque_topic=args.torque_topic,
                   reference_topic=args.reference_topic, reference=args.reference_name,
                   stamp=args.stamp)


def _report(out: Path, result, as_json: bool) -> dict | str:
    log = result.log
    if as_json:
        return {"out": str(out), "samples": len(log), "rate_hz": log.sample_rate_hz,
                "duration_s": float(log.t[-1]), "columns": list(log.columns()),
                "meta": log.meta, "steps": list(result.steps), "checks": list(result.checks),
                "warnings": list(result.warnings)}
    return "\n".join(["conversion:", *(f"  {s}" for s in result.steps), "checks:",
                      *(f"  {c}" for c in result.checks),
                      f"wrote {out}: {len(log)} samples over {log.t[-1]:.4g} s at "
                      f"{log.sample_rate_hz:.6g} Hz, columns {', '.join(log.columns())}"])


def _check(args: argparse.Namespace, src: Path, out: Path):
    """Refuse the CSV options and the survey's conflicts; check --out before any reading.
    The OutputFolder of a survey, else None."""
    from jointbench.bench.output_files import OutputFolder

    if args.map or args.units or args.rate or args.delimiter:
        raise UsageError("--map, --units, --rate and --delimiter are for CSV files; a bag "
                         "maps its columns with --topic, --motor-name, --torque-name ...")
    if not args.survey:
        if args.joint is None:
            raise UsageError(f"{src}: give --joint NAME (the axis to import), or --survey for "
                             "one log per moved joint")
        check_output_file(out)
        return None
    if args.joint is not None:
        raise UsageError("--survey finds the moved joints itself: leave out --joint")
    named = [f for f, v in (("--link-name", args.link_name), ("--motor-name", args.motor_name),
                            ("--torque-name", args.torque_name),
                            ("--reference-name", args.reference_name)) if v]
    if named:
        raise UsageError(f"--survey takes each axis' own names (NAME, NAME_motor): leave out "
                         f"{', '.join(named)}")
    return OutputFolder(out, ("*.csv",))


def run_bag(args: argparse.Namespace, spec_csv) -> int:
    """Read the bag, fit the time grid, convert, write (atomically; a survey's folder all or
    nothing); print what was done. `spec_csv`: the ImportSpec of the shared options."""
    from jointbench.identification.bag_import import (BAG_MOTOR_SIDE, bag_log, fit_grid,
                                                      read_bag, topics_needed)
    from jointbench.identification.log import write_log
    from jointbench.identification.log.raw import MOTOR_SIDE

    src, out = Path(args.file), Path(args.out)
    folder = _check(args, src, out)
    spec = _spec(args)
    if spec_csv.motor_side == MOTOR_SIDE:   # --motor-side not given: a bag's own default
        spec_csv = replace(spec_csv, motor_side=BAG_MOTOR_SIDE)
    bag = read_bag(src, topics_needed(spec, args.joint), spec.stamp)
    grid = fit_grid(bag.topic(spec.topic).stamps_ns, spec.topic, str(src))
    if folder is not None:
        return _survey(args, bag, spec, grid, spec_csv, folder)
    result = bag_log(bag, spec, args.joint, grid, spec_csv)
    write_log(result.log, out)
    for text in result.warnings:
        print(f"jointbench import: warning: {text}", file=sys.stderr)
    report = _report(out, result, args.json)
    print(json.dumps(report) if args.json else report)
    return 0


def _survey(args: argparse.Namespace, bag, spec, grid, spec_csv, folder) -> int:
    """One log per moved joint into the --out folder (all or nothing)."""
    from jointbench.identification.bag_import import bag_log
    from jointbench.identification.bag_survey import held_config, moved_windows
    from jointbench.identification.log import write_log

    out = Path(args.out)
    motions, moved = moved_windows(bag, spec, grid)
    by_joint = {m.joint: m for m in motions}
    results = {}
    for j in moved:
        m = by_joint[j]
        meta = {"locked_config": held_config(bag, spec, motions, m),
                "bag_window_s": f"{m.start * grid.period:.6f} {m.stop * grid.period:.6f}"}
        results[j] = bag_log(bag, spec, j, grid, spec_csv, (m.start, m.stop), meta)
    with folder.writing() as path:
        for j in moved:
            write_log(results[j].log, path / f"{j}.csv")
    for j in moved:
        for text in results[j].warnings:
            print(f"jointbench import: warning: {j}: {text}", file=sys.stderr)
    held = [m.joint for m in motions if not m.moved]
    if args.json:
        print(json.dumps({"out": str(out), "moved": moved, "held": held,
                          "time_grid": grid.describe(),
                          "logs": [_report(out / f"{j}.csv", results[j], True) for j in moved]}))
        return 0
    print(f"survey bag {args.file}: time {grid.describe()}")
    for j in moved:
        m = by_joint[j]
        print(f"{j}: moved from {m.start * grid.period:.3f} s to {m.stop * grid.period:.3f} s "
              f"(rolling sd peak {m.peak:.3g}, held level {m.held:.3g})")
    if held:
        print(f"held throughout: {', '.join(held)}")
    for j in moved:
        print(_report(out / f"{j}.csv", results[j], False))
    return 0
