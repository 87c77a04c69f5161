"""`jointbench`: the command line of CONTRACT section 3. Each command is a thin wrapper.

Exit status: 0 success, 2 bad input (one message on stderr naming the file, line or column),
1 anything else. With --json a command prints exactly one JSON object on stdout.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import threading
from pathlib import Path

import numpy as np

from jointbench.identification.log import LogError


class UsageError(ValueError):
    """Bad command-line input (exit status 2)."""


class Terminated(BaseException):
    """SIGTERM (or SIGHUP) received: unwinds like KeyboardInterrupt, so that atomic writes
    remove their temporary file, and ends the command with status 128 + signal number."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _trap_signals():
    """Turn SIGTERM and SIGHUP into Terminated for the duration of a command (main thread
    only); returns a function that restores the previous handlers."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handler(signum, frame):
        raise Terminated(signum)

    previous = {}
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            previous[getattr(signal, name)] = signal.signal(getattr(signal, name), handler)

    def restore():
        for signum, old in previous.items():
            signal.signal(signum, old)
    return restore


def _check_output_file(out: Path, flag: str = "--out") -> None:
    """Refuse an output path whose folder is missing, that is a folder, or that is an existing
    non-empty file not written by jointbench (a measured log, say): outputs replace only
    jointbench's own files, and always atomically (identification.log.atomic_write_text)."""
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(f"{flag} {out}: folder {parent} does not exist")
    if out.is_dir():
        raise UsageError(f"{flag} {out}: is a directory")
    if out.exists() and out.stat().st_size > 0:
        try:
            with open(out, "rb") as handle:
                head = handle.read(8192).decode("utf-8", "replace")
        except OSError as err:
            raise UsageError(f"{flag} {out}: cannot read the existing file: {err.strerror}") \
                from None
        if "\n# source: jointbench " not in head:
            raise UsageError(f"{flag} {out}: refusing to overwrite an existing file that "
                             "jointbench did not write (no '# source: jointbench ...' metadata); "
                             "remove it or choose another name")


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


def cmd_replay(args: argparse.Namespace) -> int:
    """`simulate --replay LOG`: the logged experiment again in closed loop (bench/replay.py)."""
    from jointbench.bench.sim.replay import format_report, replay_log_file, report_json, simulated_log
    from jointbench.identification.log import write_log

    for flag, given in (("--effect", args.effect), ("--amplitude", args.amplitude),
                        ("--ideal-sensors", args.ideal_sensors)):
        if given:
            raise UsageError(f"{flag} does not apply to --replay (the log gives the reference "
                             "and the replay measures without noise)")
    src = Path(args.replay)
    out = Path(args.out) if args.out else None
    if out is not None:
        if out.suffix.lower() == ".xml":
            raise UsageError(f"--out {out}: refusing to write a log over an .xml file")
        if out.exists() and (out.is_dir() or (src.exists() and out.resolve() == src.resolve())):
            raise UsageError(f"--out {out}: is a directory or the replayed log itself")
    if args.save_model and args.model:
        raise UsageError("--save-model writes the nominal axis identified from the log: "
                         "leave out --model")
    if args.save_model and Path(args.save_model).suffix.lower() != ".xml":
        raise UsageError(f"--save-model {args.save_model}: give an .xml file name")
    rep = replay_log_file(src, model=args.model, joint=args.joint,
                          config=_parse_config(args.config), lock=args.lock,
                          substeps=args.substeps, tau0=args.tau0, skip=args.skip)
    if args.save_model:
        from jointbench.bench.sim.nominal import write_xml

        write_xml(rep.spec, args.save_model)
    if out is not None:
        write_log(simulated_log(rep.log, rep.result,
                                f"jointbench replay of {src.name} on {rep.model}"), out)
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        from jointbench.bench.sim.replay import plot_replay
        from jointbench.identification.plots import save_figure_atomic

        save_figure_atomic(plot_replay(rep.log, rep.result, f"replay of {src.name}"), args.plot)
    if args.json:
        obj = report_json(rep)
        obj["out"] = None if out is None else str(out)
        print(json.dumps(obj, allow_nan=False, default=float))
    else:
        print(format_report(rep))
        if out is not None:
            print(f"wrote {out}")
    return 0


def _rate(value: str) -> float | str:
    """--rate: a positive number of Hz, or `auto`."""
    if value.strip().lower() == "auto":
        return "auto"
    try:
        return _positive(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{value}' is neither a rate in Hz nor 'auto'") from None


def _sample_rate(args: argparse.Namespace, effect) -> float:
    """The acquisition rate of `simulate`: --rate HZ, or for `auto` twice the Fs of eq. (29)
    for the axis' first mode (identification.filtering.design_rate_hz)."""
    from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ

    if args.rate is None:
        return SAMPLE_RATE_HZ
    if args.rate != "auto":
        return float(args.rate)
    from jointbench.bench.sim.axes import build_experiment_model
    from jointbench.identification.defaults import design_rate_hz

    exp = build_experiment_model(args.model, args.joint, config=_parse_config(args.config),
                                 lock=args.lock, effect=effect)
    f1 = exp.truth.f1_hz
    if not (math.isfinite(f1) and f1 > 0):
        raise UsageError(f"--rate auto: axis {exp.axis.name} has no first mode (rigid axis); "
                         "give --rate HZ")
    return round(design_rate_hz(f1), 2)


def cmd_simulate(args: argparse.Namespace) -> int:
    from jointbench.bench.effects import parse_effect
    from jointbench.bench.sim.experiment import run_experiment, stderr_progress
    from jointbench.bench.sim.sensors import Sensors
    from jointbench.identification.log import write_log

    if args.replay:
        return cmd_replay(args)
    args.model = args.model or "prototype"
    effect = parse_effect(args.effect) if args.effect else None
    out = Path(args.out) if args.out else Path(f"{Path(str(args.model)).stem}_{args.joint or 'axis1'}_seed{args.seed}.csv")
    if out.suffix.lower() == ".xml" or (Path(str(args.model)).exists() and
                                        out.resolve() == Path(str(args.model)).resolve()):
        raise UsageError(f"--out {out}: refusing to overwrite the model file")
    _check_output_file(out)
    progress = None if args.quiet or not sys.stderr.isatty() else stderr_progress("simulate")
    rate = _sample_rate(args, effect)
    result = run_experiment(args.model, args.joint, duration=args.duration, seed=args.seed,
                            amplitude=args.amplitude, config=_parse_config(args.config),
                            lock=args.lock, effect=effect,
                            sensors=Sensors.ideal() if args.ideal_sensors else None,
                            substeps=args.substeps, progress=progress, sample_rate_hz=rate)
    write_log(result.log, out)
    log = result.log
    f1 = float(log.meta["truth_f1_hz"])
    summary = {"out": str(out), "samples": len(log), "duration_s": float(log.t[-1]),
               "joint": log.meta["joint"], "f1_hz": f1 if math.isfinite(f1) else None,
               "saturated_samples": result.saturated,
               "effect": log.meta.get("truth_effect", "none")}
    warnings = _saturation_warnings(result)
    for text in warnings:
        print(f"jointbench simulate: warning: {text}", file=sys.stderr)
    summary["warnings"] = warnings
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"wrote {out}: {len(log)} samples over {log.t[-1]:.2f} s at "
              f"{log.sample_rate_hz:g} Hz, joint {summary['joint']} "
              f"({f'f1 = {f1:.3f} Hz' if math.isfinite(f1) else 'rigid axis'}), "
              f"saturated samples: {result.saturated}, "
              f"effect: {summary['effect']}")
    return 0


def _settings_from_args(args, log):
    """FilterSettings from the identify options, or None for identify's own default
    (identification.identify.settings_for)."""
    from jointbench.identification.filtering import FilterSettings
    from jointbench.identification.defaults import settings_for

    if args.wn is not None and args.fc is not None:
        raise UsageError("give the Butterworth frequency once: --wn (rad/s) or --fc (Hz)")
    wn = args.wn if args.wn is not None else (
        2 * math.pi * args.fc if args.fc is not None else None)
    chain = {"zoh": not args.no_zoh, "filter_torque": not args.no_torque_filter,
             "skip": args.skip, "stencil": args.stencil}
    if wn is None and args.decimate is None and args.order == 4 and \
            chain == {"zoh": True, "filter_torque": True, "skip": 0, "stencil": 3}:
        return None
    base, _ = settings_for(log, args.f1)
    return FilterSettings(wn=wn if wn is not None else base.wn, m=args.order,
                          Nd=args.decimate if args.decimate is not None else base.Nd, ts=log.ts,
                          **chain)


def cmd_identify(args: argparse.Namespace) -> int:
    from jointbench.identification.identify import identify
    from jointbench.identification.log import read_log
    from jointbench.identification.report import parameter_table, physical_table, to_json

    from jointbench.identification.checks import estimate_flags
    from jointbench.identification.log import unit_warnings
    from jointbench.identification.physical import InversionError

    log = read_log(args.file)
    warnings = unit_warnings(log)
    for text in warnings:
        print(f"jointbench identify: warning: {text}", file=sys.stderr)
    if args.refine_max_nfev is not None and not args.refine:
        raise UsageError("--refine-max-nfev applies to --refine")
    if args.friction_timeconst is not None and args.debias is None:
        raise UsageError("--friction-timeconst applies to --debias")
    if args.debias is not None and args.debias < 2:
        raise UsageError(f"--debias needs at least 2 replicas, got {args.debias}")
    if args.refine or args.debias is not None:
        from jointbench.bench.analysis.refine import require_replayable

        require_replayable(log)  # before the least squares: no half answer
    if args.debias is not None:
        from jointbench.bench.analysis.debias import DebiasError
        from jointbench.bench.sim.sensors import Sensors

        if Sensors.from_log(log) is None:
            raise DebiasError(f"{args.file}: --debias replays the experiment with the log's "
                              "sensors: the metadata needs motor_encoder_resolution_rad, "
                              "link_encoder_resolution_rad and torque_noise_std")
    try:
        result = identify(log, args.model, _settings_from_args(args, log), f1_hz=args.f1)
    except InversionError as err:
        raise InversionError(f"{args.file}: {err}") from None
    truth = log.truth() or None
    flags = estimate_flags(result.physical, result.physical_sigma, log.prismatic)
    refined = None
    if args.refine:
        from jointbench.bench.analysis.refine import refine

        say = None if args.json else \
            (lambda msg: print(f"identify: {msg}", file=sys.stderr, flush=True))
        refined = refine(log, result, max_nfev=args.refine_max_nfev, progress=say)
    debiased = None
    if args.debias is not None:
        from jointbench.bench.analysis.debias import SOLREF_FRICTION, debias

        tty = sys.stderr.isatty()

        def tell(done: int, total: int) -> None:
            if tty or done == total:
                print(f"\ridentify: bias correction, replica {done}/{total}",
                      end="" if done < total else "\n", file=sys.stderr, flush=True)
        debiased = debias(log, result, replicas=args.debias,
                          progress=None if args.json else tell,
                          friction_timeconst=args.friction_timeconst or SOLREF_FRICTION[0])
    if args.json:
        answer = to_json(result, truth)
        answer["flags"] = flags
        answer["warnings"] = warnings
        if refined is not None:
            from jointbench.bench.analysis.refine import refined_json

            answer["refined"] = refined_json(refined, result, truth)
        if debiased is not None:
            from jointbench.bench.analysis.debias import debiased_json

            answer["debiased"] = debiased_json(debiased, truth)
        print(json.dumps(answer, allow_nan=False, default=float))
        return 0
    s = result.settings
    print(f"{args.file}: model {result.model}, {len(log)} samples at {log.sample_rate_hz:g} Hz; "
          f"filter wn = {s.wn:g} rad/s (order {s.m}), Nd = {s.Nd} "
          f"(decimated cutoff {s.decimated_cutoff_hz:.2f} Hz); {result.ls.r} equations, "
          f"condition number {result.ls.cond:.3g}")
    chain = [text for on, text in ((not s.zoh, "torque not ZOH-aligned"),
                                   (not s.filter_torque, "torque not Butterworth-filtered"),
                                   (s.skip, f"first {s.skip} samples dropped"),
                                   (s.stencil != 3, f"{s.stencil}-point central differences"))
             if on]
    if log.prismatic or chain:
        print("; ".join((["prismatic axis: positions in m, forces in N, masses in kg"]
                         if log.prismatic else []) + chain))
    print()
    print(parameter_table(result, truth))
    if result.model.startswith("motor-only"):
        print()
        print(physical_table(result, truth, "Physical parameters"))
    print()
    print(f"direct validation: relative error {result.relative_error_pct:.2f} %, "
          f"residual rms {result.ls.rms:.4g} {'N' if log.prismatic else 'N m'}")
    sc = result.physical_sigma_corrected
    if sc:
        print("2 sigma, autocorrelation-consistent (the paper's assumes white residuals): "
              + ", ".join(f"{n} {2 * sc[n]:.4g}" for n in ("K", "Jm", "JL", "J") if n in sc))
    for note in result.notes:
        print(f"note: {note}")
    for flag in flags:
        print(f"flag: {flag['message']}")
    if refined is not None:
        from jointbench.bench.analysis.refine import refinement_table

        print()
        print(refinement_table(refined, result, truth))
    if debiased is not None:
        from jointbench.bench.analysis.debias import debias_table

        print()
        print(debias_table(debiased, log.prismatic, truth))
    return 0


def cmd_design_filter(args: argparse.Namespace) -> int:
    from jointbench.identification.design import design_bandpass

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
    from jointbench.bench.demo import run_demo

    return run_demo(Path(args.out), duration=args.duration, seed=args.seed)


def cmd_campaign(args: argparse.Namespace) -> int:
    from jointbench.bench.cli.campaign import run as campaign_main

    return campaign_main(args)


def cmd_tune_filter(args: argparse.Namespace) -> int:
    from jointbench.bench.cli.tune_filter import run as tuning_main

    return tuning_main(args)


def cmd_diagnose(args: argparse.Namespace) -> int:
    from jointbench.bench.analysis.diagnose import diagnose, summary_text
    from jointbench.identification.log import atomic_write_text
    from jointbench.identification.log import read_log

    log = read_log(args.file)
    say = (lambda msg: None) if (args.json or args.quiet) else \
        (lambda msg: print(f"diagnose: {msg}", file=sys.stderr, flush=True))
    out = Path(args.out) if args.out else None
    if out is not None and out.exists() and not out.is_dir():
        raise UsageError(f"--out {out}: exists and is not a folder")
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
    d = diagnose(log, out_dir=out, forward=not args.no_forward, progress=say)
    xval = None
    if other is not None:
        from jointbench.bench.analysis.diagnose import cross_validate
        say(f"cross-validation on {args.validate}")
        xval = cross_validate(d, other, dist, args.disturbance_at)
    if args.json:
        doc = d.to_json()
        if xval is not None:
            doc["cross_validation"] = {"file": str(args.validate), **xval}
        print(json.dumps(doc))
    else:
        print(summary_text(d))
        if xval is not None:
            print(f"\ncross-validation on {args.validate} (models identified and extended on "
                  f"{args.file}, unchanged):")
            for view, rows in xval.items():
                for label, vals in rows.items():
                    print(f"  {view:8s} {label:9s} " + ", ".join(
                        f"{k} {v:.4g}" for k, v in vals.items()))
    if xval is not None and out is not None:
        atomic_write_text(out / "cross_validation.json",
                          json.dumps({"file": str(args.validate), **xval}, indent=2) + "\n")
    return 0


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
    s.add_argument("--model", default=None,
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
    s.add_argument("--rate", type=_rate, default=None, metavar="HZ|auto",
                   help="sample (control and log) rate in Hz (default 350.87, the paper's); "
                        "auto: twice the Fs of eq. (29) for the axis' first mode, about 105 f1")
    s.add_argument("--ideal-sensors", action="store_true", help="no quantisation, no torque noise")
    s.add_argument("--json", action="store_true", help="print a JSON summary")
    s.add_argument("--quiet", action="store_true", help="no progress indicator")
    s.add_argument("--replay", metavar="LOG",
                   help="replay LOG in closed loop (its q_ref and controller gains) on --model, "
                        "or without --model on the nominal axis identified from LOG, and "
                        "compare with the measured position and torque")
    s.add_argument("--tau0", type=_finite,
                   help="--replay: the integrator's initial state (default tau_m[0], CONTRACT "
                        "section 2)")
    s.add_argument("--skip", type=int, default=0,
                   help="--replay: samples left out of the comparison at the start (default 0)")
    s.add_argument("--plot", metavar="PNG", help="--replay: figure of measured and replayed signals")
    s.add_argument("--save-model", metavar="XML",
                   help="--replay without --model: write the nominal axis identified from the "
                        "log (MJCF, axis convention; runs with --model XML)")
    s.set_defaults(func=cmd_simulate)

    i = sub.add_parser("identify", help="identify the axis parameters from a log")
    i.add_argument("file", help="log file (CONTRACT section 1)")
    i.add_argument("--model", default="auto",
                   choices=("joint-motor", "motor-only", "motor-only-printed", "rigid", "auto"))
    i.add_argument("--wn", type=_positive, help="Butterworth frequency in rad/s")
    i.add_argument("--fc", type=_positive, help="Butterworth frequency in Hz (instead of --wn)")
    i.add_argument("--skip", type=int, default=0,
                   help="drop the first N samples after filtering, before decimation (default 0)")
    i.add_argument("--no-zoh", action="store_true",
                   help="rigid model: pair the logged torque with the positions as is, without "
                        "the zero-order-hold alignment (the EMPS reference chain)")
    i.add_argument("--no-torque-filter", action="store_true",
                   help="rigid model: the torque goes only through the decimation filter, not "
                        "the Butterworth (the EMPS reference chain)")
    i.add_argument("--stencil", type=int, default=3, choices=(3, 5),
                   help="central-difference points: 3, the paper's eq. (22) (default), or 5 "
                        "(fourth order: no sinc distortion of the derivatives)")
    i.add_argument("--order", type=int, default=4, help="Butterworth order m (default 4)")
    i.add_argument("--decimate", type=int, help="decimation factor Nd")
    i.add_argument("--f1", type=_positive, help="first mode in Hz (to derive wn and Nd)")
    i.add_argument("--json", action="store_true", help="print the CONTRACT JSON object")
    i.add_argument("--refine", action="store_true",
                   help="continue from the least-squares estimate by closed-loop output error "
                        "(DIDIM-style): replay the log in MuJoCo under its controller on the "
                        "two-mass axis and fit the torque (and q); needs q_ref and the gains "
                        "(bench/refine.py)")
    i.add_argument("--refine-max-nfev", type=int, default=None, metavar="N",
                   help="--refine: residual evaluations allowed (each one replay; default 40)")
    i.add_argument("--debias", type=int, default=None, metavar="B",
                   help="bias-correct the least-squares estimate by B closed-loop replicas of "
                        "the experiment on the nominal axis with the log's sensors (parametric "
                        "bootstrap; 8 is a good start; needs q_ref, the gains and the sensor "
                        "metadata; bench/debias.py)")
    i.add_argument("--friction-timeconst", type=_positive, default=None, metavar="S",
                   help="--debias: Coulomb friction time constant of the nominal axis in s "
                        "(MuJoCo solreffriction; default 0.002, models/arm6.xml uses 0.00025)")
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

    g = sub.add_parser("diagnose", help="what the simulation gets wrong on a log, the named "
                                        "cause, the extended model and the gain")
    g.add_argument("file", help="log file (CONTRACT section 1)")
    g.add_argument("--out", help="folder for figures, report.md, nominal.xml, extended.xml")
    g.add_argument("--json", action="store_true", help="print the CONTRACT JSON object")
    g.add_argument("--no-forward", action="store_true",
                   help="skip the closed-loop replay (forward view)")
    g.add_argument("--quiet", action="store_true", help="no progress messages")
    g.add_argument("--validate", metavar="OTHER.csv",
                   help="cross-validation: evaluate the nominal and extended models, identified "
                        "on FILE, on this other log (inverse and forward views)")
    g.add_argument("--disturbance-column", metavar="COL",
                   help="a column of the --validate log applied as a disturbance in its replay")
    g.add_argument("--disturbance-gain", type=_finite, default=1.0,
                   help="scale of the disturbance column (default 1; EMPS pulses are volts: "
                        "35.15065188 N/V)")
    g.add_argument("--disturbance-at", choices=("link", "motor"), default="link",
                   help="where the disturbance acts: on the link/carriage or added to the motor "
                        "command (default link)")
    g.set_defaults(func=cmd_diagnose)

    from jointbench.bench.cli import campaign, tune_filter as tuning  # light at import

    campaign.add_arguments(sub.add_parser(
        "campaign", help="N virtual experiments identified, a table row per run, bias, "
                         "spread and sigma coverage (local cores or a Dask cluster)")
    ).set_defaults(func=cmd_campaign)
    tuning.add_arguments(sub.add_parser(
        "tune-filter", help="search wn and Nd minimising the error against truth over a "
                            "campaign, beside the eq. (28)-(29) values")
    ).set_defaults(func=cmd_tune_filter)
    return p


def main(argv: list[str] | None = None) -> int:
    from jointbench.identification.estimate import NotIdentifiable
    from jointbench.identification.physical import InversionError
    from jointbench.models import ModelStructureError

    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    restore_signals = _trap_signals()
    try:
        return args.func(args)
    except (LogError, ModelStructureError, UsageError, NotIdentifiable, InversionError,
            ValueError) as err:
        print(f"jointbench {args.command}: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"jointbench {args.command}: interrupted", file=sys.stderr)
        return 130
    except Terminated as sig:
        print(f"jointbench {args.command}: terminated by {signal.Signals(sig.signum).name}",
              file=sys.stderr)
        return 128 + sig.signum
    except BrokenPipeError:
        # The reader of stdout went away (`| head`): nothing more to say, and no complaint
        # from the interpreter when it flushes stdout at exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 128 + 13
    except Exception as err:  # the contract: never a traceback
        if _is_simulation_error(err):
            print(f"jointbench {args.command}: error: {_one_line(err)}", file=sys.stderr)
            return 2
        print(f"jointbench {args.command}: internal error: {type(err).__name__}: {err}",
              file=sys.stderr)
        return 1
    finally:
        restore_signals()


def _one_line(err: Exception) -> str:
    """The error's message on one line (MuJoCo's parser messages span several)."""
    return "; ".join(line.strip() for line in str(err).splitlines() if line.strip())


def _is_simulation_error(err: Exception) -> bool:
    """A diverging or unstable virtual experiment (bench.experiment.SimulationError, loaded
    only by the commands that simulate): bad input (gains, timestep, model), status 2."""
    experiment = sys.modules.get("jointbench.bench.sim.experiment")
    return experiment is not None and isinstance(err, experiment.SimulationError)


def _saturation_warnings(result) -> list[str]:
    """Warnings about the torque limit in a virtual experiment (also in the log metadata:
    saturated_samples, actuator_clamped_samples)."""
    out = []
    n = len(result.log)
    if result.saturated:
        tau_max = result.log.meta_float("tau_max")
        hit = np.flatnonzero(np.abs(result.log.tau_m) >= (tau_max or np.inf))
        first = f", first at t = {result.log.t[hit[0]]:.4g} s" if hit.size else ""
        out.append(f"the torque command saturated at tau_max on {result.saturated} of {n} "
                   f"samples ({100 * result.saturated / n:.2g} %{first}); the logged tau_m is "
                   "the clipped command")
    if getattr(result, "clamped", 0):
        out.append(f"MuJoCo's actuator ctrlrange cut the applied torque (command plus noise) on "
                   f"{result.clamped} of {n} samples")
    return out


if __name__ == "__main__":
    sys.exit(main())
