"""`jointbench import RAW.csv --out LOG.csv`: a measured file (own column names, units, motor
side, current) converted into a jointbench log (docs/log-format.md; identification/log/raw.py
does the conversion). Prints what it did and the checks it ran; exit 2 for what it cannot
convert, naming the file, line and column."""

from __future__ import annotations

import argparse
import json
import sys

from jointbench.bench.cli.common import UsageError, finite, positive

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.identification.log.raw", "jointbench.identification.log",
           "jointbench.identification.bag_import", "jointbench.identification.bag_survey")

# Metadata options: option destination -> metadata key (docs/log-format.md section 1.3).
META_OPTIONS = {"kp": "kp", "kv": "kv", "ki": "ki", "tau_max": "tau_max",
                "velocity_feedforward": "velocity_feedforward", "gravity": "gravity",
                "joint": "joint"}


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of `import`."""
    p.add_argument("file", nargs="+",
                   help="raw CSV file: a header row, then one row of numbers per sample (',' "
                        "';' tab or '|'; '#' lines skipped), a MATLAB .mat file (its vectors "
                        "are the columns), or a ROS bag (.db3, .mcap, a rosbag2 folder, .bag); "
                        "several files: all converted, then written to the --out folder as "
                        "STEM.csv")
    p.add_argument("--out", required=True, help="log file to write (never the input); with "
                                                "several files, a folder")
    p.add_argument("--map", metavar="COL=RAW,...",
                   help="log column = raw column or an expression of raw columns (+ - * / "
                        "and parentheses), e.g. t=time_ms,q_m=motor_counts,tau_m=current_A,"
                        "q=link_deg,q_ref=ref_counts or q=theta-alpha,tau_m=-cur (default: the "
                        "raw columns named t, q_m, q, tau_m, q_ref); unmapped columns are kept")
    p.add_argument("--units", metavar="COL=UNIT,...",
                   help="units of the raw columns: t in s|ms|us; q_m, q, q_ref in "
                        "rad|deg|rev|counts|m|mm|um; tau_m in Nm|N|A|V (default s, rad "
                        "(m for --prismatic), Nm)")
    p.add_argument("--gear-ratio", type=positive, metavar="N",
                   help="gear ratio: the --motor-side columns are referred to the joint side "
                        "(angles / N, torque x N); prismatic: motor rad per m (2 pi / lead); "
                        "lengths and forces are left as they are; --meta gear_ratio=N only "
                        "records it")
    p.add_argument("--motor-side", default="q_m,tau_m,q_ref", metavar="COLS",
                   help="columns measured on the motor shaft, converted with --gear-ratio "
                        "(default q_m,tau_m,q_ref)")
    p.add_argument("--counts-per-turn", type=positive, metavar="CPR",
                   help="motor encoder counts per turn of the motor shaft (--units ...=counts)")
    p.add_argument("--link-counts-per-turn", type=positive, metavar="CPR",
                   help="link encoder counts per turn (--units q=counts)")
    p.add_argument("--torque-constant", type=positive, metavar="KT",
                   help="torque constant in N m/A (N/A prismatic; or per V) for --units "
                        "tau_m=A or V")
    p.add_argument("--drive", metavar="Kt=..,R=..,Ke=..[,eta=..]",
                   help="a voltage drive's constants (N m/A, Ohm, V s/rad, efficiency) for "
                        "--units tau_m=V: tau_m = eta N Kt / R u; the back-EMF damping "
                        "eta N^2 Kt Ke / R stays in FVm and is written as back_emf_damping")
    p.add_argument("--rate", type=positive, metavar="HZ",
                   help="the drive's fixed sample rate: t rebuilt as k / rate (for rounded "
                        "time stamps), checked within half a period of the logged time")
    p.add_argument("--delimiter", help="column separator (default: found from the header)")
    meta = p.add_argument_group("metadata (docs/log-format.md section 1.3)")
    meta.add_argument("--kp", type=finite, help="position gain [1/s]")
    meta.add_argument("--kv", type=finite, help="velocity gain [N m s/rad]")
    meta.add_argument("--ki", type=finite, help="integral gain [N m/rad]")
    meta.add_argument("--tau-max", type=positive, help="torque limit [N m]")
    meta.add_argument("--velocity-feedforward", choices=("true", "false"),
                      help="the velocity feed-forward term of the controller (default true)")
    meta.add_argument("--gains-side", choices=("joint", "motor"), default="joint",
                      help="motor: kv, ki, tau_max are motor-side, multiplied by N^2, N^2, N "
                           "(default joint)")
    meta.add_argument("--gravity", type=finite, help="gravity acceleration [m/s^2] (default "
                                                     "9.81; 0 for a horizontal axis)")
    meta.add_argument("--joint", help="axis name (default axis1)")
    meta.add_argument("--prismatic", action="store_true",
                      help="a linear axis: positions in m, forces in N (metadata axis: prismatic)")
    meta.add_argument("--meta", action="append", default=[], metavar="KEY=VALUE",
                      help="any other metadata key, e.g. torque_noise_std=0.5 (repeatable)")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    from jointbench.bench.cli.import_bag import add_bag_arguments
    add_bag_arguments(p)


def _pairs(text: str | None, flag: str, form: str) -> dict[str, str]:
    """`KEY=VALUE,...` as a dict of strings; UsageError naming the flag."""
    out: dict[str, str] = {}
    for item in (text.split(",") if text else []):
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip() or "=" in value:
            raise UsageError(f"{flag}: '{item}' must read {form}")
        if key.strip() in out:
            raise UsageError(f"{flag}: '{key.strip()}' is given twice ('{out[key.strip()]}' "
                             f"and '{value.strip()}'); give each once")
        out[key.strip()] = value.strip()
    return out


def options(args: argparse.Namespace) -> dict:
    """The keyword arguments of `jointbench.import_log` of the options (columns None: the raw
    columns that already carry a log column's name)."""
    columns = _pairs(args.map, "--map", "COL=RAW (e.g. t=time_ms,q_m=motor_counts)") \
        if args.map else None
    units = _pairs(args.units, "--units", "COL=UNIT (e.g. t=ms,q_m=counts,tau_m=A)")
    meta: dict[str, str] = {}
    if args.prismatic:
        meta["axis"] = "prismatic"
    for dest, key in META_OPTIONS.items():
        if getattr(args, dest) is not None:
            meta[key] = str(getattr(args, dest))
    for item in args.meta:
        for key, value in _pairs(item, "--meta", "KEY=VALUE (e.g. torque_noise_std=0.5)"
                                 ).items():
            if key in meta and meta[key] != value:
                raise UsageError(f"--meta {key}={value}: '{key}' is already given as "
                                 f"'{meta[key]}' (by --meta or its own option)")
            meta[key] = value
    return dict(columns=columns, units=units, gear_ratio=args.gear_ratio,
                motor_side=tuple(c.strip() for c in args.motor_side.split(",") if c.strip()),
                counts_per_turn=args.counts_per_turn,
                link_counts_per_turn=args.link_counts_per_turn,
                torque_constant=args.torque_constant, rate_hz=args.rate, meta=meta,
                gains_side=args.gains_side, delimiter=args.delimiter,
                drive=_pairs(args.drive, "--drive", "KEY=VALUE (e.g. Kt=0.00768,R=2.6,Ke=0.00768)")
                if args.drive else None)


def spec_from_args(args: argparse.Namespace, header: tuple[str, ...]):
    """The ImportSpec of the options (a bag's conversion); the default mapping takes the raw
    columns that already carry a log column's name."""
    from jointbench.identification.log.raw import LOG_COLUMNS, ImportSpec

    kwargs = options(args)
    kwargs.pop("delimiter")
    if kwargs.pop("drive", None) is not None:
        raise UsageError("--drive applies to a table or a .mat file, not to a bag")
    if kwargs["columns"] is None:
        kwargs["columns"] = {c: c for c in LOG_COLUMNS if c in header}
    return ImportSpec(**kwargs)


def run(args: argparse.Namespace) -> int:
    """Parse, `jointbench.import_log` (read, convert, check, write atomically); print what
    was done."""
    from jointbench.bench.api import import_log
    from jointbench.identification.bag_import import is_bag

    if len(args.file) == 1 and is_bag(args.file[0]):
        from jointbench.bench.cli.import_bag import run_bag
        args.file = args.file[0]
        return run_bag(args, spec_from_args(args, ()))
    files = args.file[0] if len(args.file) == 1 else list(args.file)
    answer = import_log(files, args.out, **options(args))
    reports = answer if isinstance(answer, list) else [answer]
    for report in reports:
        for text in report.warnings:
            print(f"jointbench import: warning: {text}", file=sys.stderr)
    if args.json:
        print(json.dumps(reports[0].to_json() if len(reports) == 1 else
                         [r.to_json() for r in reports]))
    else:
        print("\n\n".join(r.table() for r in reports))
    return 0
