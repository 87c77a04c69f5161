"""`jointbench`: the command line of CONTRACT section 3. Each command is a thin wrapper.

Exit status: 0 success, 2 bad input (one message on stderr naming the file, line or column),
1 anything else. With --json a command prints exactly one JSON object on stdout.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from identification.log import LogError


class UsageError(ValueError):
    """Bad command-line input (exit status 2)."""


def _parse_config(text: str | None) -> dict[str, float]:
    if not text:
        return {}
    out = {}
    for item in text.split(","):
        if "=" not in item:
            raise UsageError(f"--config: '{item}' must read AXIS=ANGLE (e.g. axis2=-0.5,axis3=1.0)")
        key, value = item.split("=", 1)
        try:
            out[key.strip()] = float(value)
        except ValueError:
            raise UsageError(f"--config: angle '{value}' of {key} is not a number") from None
    return out


def _finite(value: str) -> float:
    x = float(value)
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"{value} is not a finite number")
    return x


def _positive(value: str) -> float:
    x = _finite(value)
    if x <= 0:
        raise argparse.ArgumentTypeError(f"{value} must be positive")
    return x


def cmd_simulate(args: argparse.Namespace) -> int:
    from bench.effects import parse_effect
    from bench.experiment import run_experiment, stderr_progress
    from bench.sensors import Sensors
    from identification.log import write_log

    effect = parse_effect(args.effect) if args.effect else None
    out = Path(args.out) if args.out else Path(f"{Path(str(args.model)).stem}_{args.joint or 'axis1'}_seed{args.seed}.csv")
    if out.suffix.lower() == ".xml" or (Path(str(args.model)).exists() and
                                        out.resolve() == Path(str(args.model)).resolve()):
        raise UsageError(f"--out {out}: refusing to overwrite the model file")
    if out.exists() and out.is_dir():
        raise UsageError(f"--out {out}: is a directory")
    progress = None if args.quiet or not sys.stderr.isatty() else stderr_progress("simulate")
    result = run_experiment(args.model, args.joint, duration=args.duration, seed=args.seed,
                            amplitude=args.amplitude, config=_parse_config(args.config),
                            lock=args.lock, effect=effect,
                            sensors=Sensors.ideal() if args.ideal_sensors else None,
                            substeps=args.substeps, progress=progress)
    write_log(result.log, out)
    log = result.log
    summary = {"out": str(out), "samples": len(log), "duration_s": float(log.t[-1]),
               "joint": log.meta["joint"], "f1_hz": float(log.meta["truth_f1_hz"]),
               "saturated_samples": result.saturated,
               "effect": log.meta.get("truth_effect", "none")}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"wrote {out}: {len(log)} samples over {log.t[-1]:.2f} s at "
              f"{log.sample_rate_hz:g} Hz, joint {summary['joint']} "
              f"(f1 = {summary['f1_hz']:.3f} Hz), saturated samples: {result.saturated}, "
              f"effect: {summary['effect']}")
    return 0


def _settings_from_args(args, log):
    from identification.filtering import FilterSettings, default_settings

    if args.wn is None and args.decimate is None:
        return default_settings(log.sample_rate_hz, args.f1)
    base = None
    try:
        base = default_settings(log.sample_rate_hz, args.f1)
    except ValueError:
        if args.wn is None or args.decimate is None:
            raise
    return FilterSettings(wn=args.wn if args.wn is not None else base.wn, m=args.order,
                          Nd=args.decimate if args.decimate is not None else base.Nd, ts=log.ts)


def cmd_identify(args: argparse.Namespace) -> int:
    from identification.identify import identify
    from identification.log import read_log
    from identification.report import parameter_table, physical_table, to_json

    log = read_log(args.file)
    result = identify(log, args.model, _settings_from_args(args, log), f1_hz=args.f1)
    truth = log.truth() or None
    if args.json:
        print(json.dumps(to_json(result, truth), allow_nan=False, default=float))
        return 0
    s = result.settings
    print(f"{args.file}: model {result.model}, {len(log)} samples at {log.sample_rate_hz:g} Hz; "
          f"filter wn = {s.wn:g} rad/s (order {s.m}), Nd = {s.Nd} "
          f"(decimated cutoff {s.decimated_cutoff_hz:.2f} Hz); {result.ls.r} equations, "
          f"condition number {result.ls.cond:.3g}")
    print()
    print(parameter_table(result, truth))
    if result.model.startswith("motor-only"):
        print()
        print(physical_table(result, truth, "Physical parameters"))
    print()
    print(f"direct validation: relative error {result.relative_error_pct:.2f} %, "
          f"residual rms {result.ls.rms:.4g}")
    for note in result.notes:
        print(f"note: {note}")
    return 0


def cmd_design_filter(args: argparse.Namespace) -> int:
    from identification.design import design_bandpass

    d = design_bandpass(args.f1, nd=args.nd, m=args.m, ac=args.ac, rc=args.rc, ratio=args.ratio)
    if args.json:
        print(json.dumps({"wc_rad_s": d.wc_rad_s, "wn_rad_s": d.wn_rad_s, "fs_hz": d.fs_hz,
                          "ts_s": d.ts_s, "xc": d.xc}))
    else:
        print(f"f1 = {args.f1:g} Hz, nd = {args.nd}, m = {args.m}, Ac = {args.ac:.4g}, "
              f"rc = {args.rc:g}, wc = {args.ratio:g} w1")
        print(f"wc = {d.wc_rad_s:.2f} rad/s")
        print(f"wn = {d.wn_rad_s:.2f} rad/s   (eq. 28)")
        print(f"xc = {d.xc:.5f}, Fs = {d.fs_hz:.2f} Hz, Ts = {1000 * d.ts_s:.4f} ms   (eq. 29)")
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    from bench.demo import run_demo

    return run_demo(Path(args.out), duration=args.duration, seed=args.seed)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="jointbench", description=(
        "Virtual testbench and identification of joint stiffness "
        "(Pham, Gautier, Poignet, ICRA 2001)."))
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    d = sub.add_parser("demo", help="the paper-prototype virtual experiment, both models, "
                                    "tables and figures")
    d.add_argument("--out", default="demo_out", help="folder for figures and tables (default demo_out)")
    d.add_argument("--duration", type=_positive, default=60.0, help="experiment length in s (default 60)")
    d.add_argument("--seed", type=int, default=1, help="noise seed (default 1)")
    d.set_defaults(func=cmd_demo)

    s = sub.add_parser("simulate", help="run one virtual experiment and write its log")
    s.add_argument("--model", default="prototype",
                   help="prototype, arm6 or an MJCF file following the axis convention")
    s.add_argument("--joint", help="axis to move (default: the first)")
    s.add_argument("--duration", type=_positive, default=60.0, help="seconds (default 60)")
    s.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    s.add_argument("--out", help="log file to write (default MODEL_JOINT_seedN.csv)")
    s.add_argument("--effect", help="hide an effect: NAME=STRENGTH[:OPTION=VALUE...], e.g. "
                                    "backlash=0.002 (CONTRACT section 4)")
    s.add_argument("--lock", choices=("rigid", "brake"), default="rigid",
                   help="how the other axes are held (default rigid)")
    s.add_argument("--config", help="locked angles of the other axes, e.g. axis2=-0.5,axis3=1.0")
    s.add_argument("--amplitude", type=_positive, help="chirp amplitude in rad (default 0.05)")
    s.add_argument("--substeps", type=int, default=1, help="physics steps per control tick (default 1)")
    s.add_argument("--ideal-sensors", action="store_true", help="no quantisation, no torque noise")
    s.add_argument("--json", action="store_true", help="print a JSON summary")
    s.add_argument("--quiet", action="store_true", help="no progress indicator")
    s.set_defaults(func=cmd_simulate)

    i = sub.add_parser("identify", help="identify the axis parameters from a log")
    i.add_argument("file", help="log file (CONTRACT section 1)")
    i.add_argument("--model", default="auto",
                   choices=("joint-motor", "motor-only", "motor-only-printed", "rigid", "auto"))
    i.add_argument("--wn", type=_positive, help="Butterworth frequency in rad/s")
    i.add_argument("--order", type=int, default=4, help="Butterworth order m (default 4)")
    i.add_argument("--decimate", type=int, help="decimation factor Nd")
    i.add_argument("--f1", type=_positive, help="first mode in Hz (to derive wn and Nd)")
    i.add_argument("--json", action="store_true", help="print the CONTRACT JSON object")
    i.set_defaults(func=cmd_identify)

    f = sub.add_parser("design-filter", help="the bandpass design of eqs. (26)-(29)")
    f.add_argument("--f1", type=_positive, required=True, help="first mode in Hz")
    f.add_argument("--nd", type=int, required=True, help="highest derivative order")
    f.add_argument("--m", type=int, required=True, help="Butterworth order")
    f.add_argument("--ac", type=_finite, default=math.sqrt(2) / 2, help="distortion bound Ac (default sqrt(2)/2)")
    f.add_argument("--rc", type=_finite, default=1.0, help="distortion ratio rc (default 1)")
    f.add_argument("--ratio", type=_positive, default=6.0, help="wc / w1 (default 6)")
    f.add_argument("--json", action="store_true", help="print the CONTRACT JSON object")
    f.set_defaults(func=cmd_design_filter)
    return p


def main(argv: list[str] | None = None) -> int:
    from identification.estimate import NotIdentifiable
    from identification.physical import InversionError
    from models import ModelStructureError

    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        return args.func(args)
    except (LogError, ModelStructureError, UsageError, NotIdentifiable, InversionError,
            ValueError) as err:
        print(f"jointbench {args.command}: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"jointbench {args.command}: interrupted", file=sys.stderr)
        return 130
    except Exception as err:  # the contract: never a traceback
        print(f"jointbench {args.command}: internal error: {type(err).__name__}: {err}",
              file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
