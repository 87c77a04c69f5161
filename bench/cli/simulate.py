"""`jointbench simulate`: one virtual experiment written as a log (docs/log-format.md), or with
--replay LOG the logged experiment again in closed loop and its comparison with the log."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from jointbench.bench.cli.common import (UsageError, check_output_file, finite, parse_config,
                                         positive, seed)
from jointbench.bench.cli.resources import check_memory
from jointbench.bench.sim.defaults import (MIN_SUBSTEPS, PAPER_RATE_HZ, PHYSICS_STEP,
                                          amplitude_help)

# The library `run` imports, loaded by the dispatcher before it traps the signals: a virtual
# experiment needs no scipy (start-up, README "Speed"); the replay identifies and does.
LIBRARY = ("jointbench.bench.present.experiment",)
REPLAY_LIBRARY = LIBRARY + ("jointbench.bench.present.replay",)


def library(args: argparse.Namespace) -> tuple[str, ...]:
    """The modules `run(args)` imports (the dispatcher loads them first)."""
    return REPLAY_LIBRARY if args.replay else LIBRARY


def _rate(value: str) -> float | str:
    """--rate: a positive number of Hz, or `auto`."""
    if value.strip().lower() == "auto":
        return "auto"
    try:
        return positive(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{value}' is neither a rate in Hz nor 'auto'") from None


def add_arguments(s: argparse.ArgumentParser) -> None:
    """The options of `simulate` and of its replay mode."""
    s.add_argument("--model", default=None,
                   help="prototype, arm6 or an MJCF file following the axis convention")
    s.add_argument("--joint", help="axis to move, by name or index from 1 (default: the first)")
    s.add_argument("--duration", type=positive, default=60.0, help="seconds (default 60)")
    s.add_argument("--seed", type=seed, default=0, help="noise seed (default 0)")
    s.add_argument("--out", help="log file to write (default MODEL_JOINT_seedN.csv)")
    s.add_argument("--effect", help="hide an effect: NAME=STRENGTH[:OPTION=VALUE...], e.g. "
                                    "backlash=0.002; several separated by commas, e.g. "
                                    "backlash=0.002,offset=20 (docs/effects.md)")
    s.add_argument("--lock", choices=("rigid", "brake"), default="rigid",
                   help="how the other axes are held (default rigid)")
    s.add_argument("--config", help="locked angles of the other axes, e.g. axis2=-0.5,axis3=1.0; "
                                    "an entry for the moving axis centres its chirp (default: "
                                    "its rest position)")
    s.add_argument("--amplitude", type=positive, help=amplitude_help())
    s.add_argument("--substeps", type=int, default=None,
                   help=f"physics steps per control tick (default: the fewest that keep the "
                        f"step within {1e3 * PHYSICS_STEP:g} ms, at least {MIN_SUBSTEPS}; with "
                        "--replay: the log's own, else 1)")
    s.add_argument("--rate", type=_rate, default=None, metavar="HZ|auto",
                   help=f"sample (control and log) rate in Hz (default {PAPER_RATE_HZ:g}, the "
                        "paper's); "
                        "auto: twice the Fs of eq. (29) for the axis' first mode, about 105 f1")
    s.add_argument("--ideal-sensors", action="store_true", help="no quantisation, no torque noise")
    s.add_argument("--json", action="store_true", help="print a JSON summary")
    s.add_argument("--quiet", action="store_true", help="no progress indicator")
    s.add_argument("--replay", metavar="LOG",
                   help="replay LOG in closed loop (its q_ref and controller gains) on --model, "
                        "or without --model on the nominal axis identified from LOG, and "
                        "compare with the measured position and torque")
    s.add_argument("--tau0", type=finite,
                   help="--replay: the integrator's initial state (default tau_m[0], docs/controller.md)")
    s.add_argument("--skip", type=int, default=0,
                   help="--replay: samples left out of the comparison at the start (default 0)")
    s.add_argument("--plot", metavar="PNG", help="--replay: figure of measured and replayed signals")
    s.add_argument("--save-model", metavar="XML",
                   help="--replay without --model: write the nominal axis identified from the "
                        "log (MJCF, axis convention; runs with --model XML)")


def _output_file(args: argparse.Namespace) -> Path:
    """The log to write: --out, or MODEL_JOINT_seedN.csv; never over the model file."""
    model = Path(str(args.model))
    out = Path(args.out) if args.out else Path(f"{model.stem}_{args.joint or 'axis1'}_seed{args.seed}.csv")
    if out.suffix.lower() == ".xml" or (model.exists() and out.resolve() == model.resolve()):
        raise UsageError(f"--out {out}: refusing to overwrite the model file")
    check_output_file(out)
    return out


def _require_mode(f1_hz: float, axis: str) -> None:
    """--rate auto needs the axis' first mode."""
    if not (math.isfinite(f1_hz) and f1_hz > 0):
        raise UsageError(f"--rate auto: axis {axis} has no first mode (rigid axis); "
                         "give --rate HZ")


MAX_SUBSTEPS = 1000  # physics steps per tick: beyond, a 60 s run takes hours


def _check_numbers(args: argparse.Namespace) -> None:
    """UsageError naming the option for a value no experiment or replay can use."""
    from dataclasses import fields

    from jointbench.bench.sim.reference import Chirp
    from jointbench.identification.log.read import MAX_RATE_HZ, MIN_RATE_HZ

    if args.substeps is not None and not 1 <= args.substeps <= MAX_SUBSTEPS:
        raise UsageError(f"--substeps {args.substeps}: must lie in [1, {MAX_SUBSTEPS}]")
    if args.skip < 0:
        raise UsageError(f"--skip {args.skip}: must be >= 0")
    if args.replay:
        return
    chirp = {f.name: f.default for f in fields(Chirp)}
    if args.duration < 2 * chirp["taper"]:
        raise UsageError(f"--duration {args.duration:g}: must be at least "
                         f"{2 * chirp['taper']:g} s (the chirp fades in and out over "
                         f"{chirp['taper']:g} s each)")
    if isinstance(args.rate, float) and not MIN_RATE_HZ <= args.rate <= MAX_RATE_HZ:
        raise UsageError(f"--rate {args.rate:g}: must lie in [{MIN_RATE_HZ:g}, "
                         f"{MAX_RATE_HZ:g}] Hz, the rates a log may have (docs/log-format.md)")


def run(args: argparse.Namespace) -> int:
    """Run the virtual experiment, write its log, print the summary (text or JSON)."""
    _check_numbers(args)
    if args.replay:
        return run_replay(args)
    from jointbench.bench.effects import parse_effects
    from jointbench.bench.present.experiment import (experiment_json, experiment_text,
                                                      saturation_warnings)
    from jointbench.bench.sim.axes import build_experiment_model
    from jointbench.bench.cli.progress import bar, fraction
    from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ, run_experiment
    from jointbench.bench.sim.sensors import Sensors
    from jointbench.identification.filter_choice import design_rate_hz
    from jointbench.identification.log import write_log
    from jointbench.identification.output_values import finite_json

    args.model = args.model or "prototype"
    effect = parse_effects(args.effect) if args.effect else None
    out = _output_file(args)
    if args.rate == "auto":  # twice the Fs of eq. (29) for the axis' first mode
        exp = build_experiment_model(args.model, args.joint, config=parse_config(args.config),
                                     lock=args.lock, effect=effect)
        _require_mode(exp.truth.f1_hz, exp.axis.name)
        rate = round(design_rate_hz(exp.truth.f1_hz), 2)
    else:
        rate = SAMPLE_RATE_HZ if args.rate is None else float(args.rate)
    check_memory(args.duration * rate, f"--duration {args.duration:g} s at {rate:g} Hz")
    with bar("simulate", 100, "%", quiet=args.quiet) as b:
        result = run_experiment(args.model, args.joint, duration=args.duration, seed=args.seed,
                                amplitude=args.amplitude, config=parse_config(args.config),
                                lock=args.lock, effect=effect,
                                sensors=Sensors.ideal() if args.ideal_sensors else None,
                                substeps=args.substeps,
                                progress=fraction(b), sample_rate_hz=rate)
    write_log(result.log, out)
    warnings = saturation_warnings(result)
    for text in warnings:
        print(f"jointbench simulate: warning: {text}", file=sys.stderr)
    if args.json:
        print(json.dumps(finite_json(experiment_json(result, out, warnings)), allow_nan=False))
    else:
        print(experiment_text(result, out))
    return 0


def _check_replay_options(args: argparse.Namespace, src: Path, out: Path | None) -> None:
    """UsageError for the simulate options that do not apply to --replay, and for outputs
    that would overwrite the model, the replayed log or a folder."""
    for flag, given in (("--effect", args.effect), ("--amplitude", args.amplitude),
                        ("--ideal-sensors", args.ideal_sensors)):
        if given:
            raise UsageError(f"{flag} does not apply to --replay (the log gives the reference "
                             "and the replay measures without noise)")
    if out is not None:
        if out.suffix.lower() == ".xml":
            raise UsageError(f"--out {out}: refusing to write a log over an .xml file")
        if out.exists() and (out.is_dir() or (src.exists() and out.resolve() == src.resolve())):
            raise UsageError(f"--out {out}: is a directory or the replayed log itself")
        check_output_file(out)
    if args.save_model and args.model:
        raise UsageError("--save-model writes the nominal axis identified from the log: "
                         "leave out --model")
    if args.save_model and Path(args.save_model).suffix.lower() != ".xml":
        raise UsageError(f"--save-model {args.save_model}: give an .xml file name")
    for flag, path in (("--save-model", args.save_model), ("--plot", args.plot)):
        if path:
            check_output_file(Path(path), flag)


def run_replay(args: argparse.Namespace) -> int:
    """`simulate --replay LOG`: the logged experiment again in closed loop
    (bench.present.replay.replay_log_file), the comparison printed as text or JSON."""
    src = Path(args.replay)
    out = Path(args.out) if args.out else None
    _check_replay_options(args, src, out)
    from jointbench.bench.output_files import record
    from jointbench.bench.present.replay import (format_report, plot_replay, replay_log_file,
                                                 report_json)
    from jointbench.bench.sim.nominal import write_xml
    from jointbench.bench.sim.replay import simulated_log
    from jointbench.identification.log import write_log
    from jointbench.identification.output_values import finite_json
    from jointbench.identification.plots import save_figure_atomic

    rep = replay_log_file(src, model=args.model, joint=args.joint,
                          config=parse_config(args.config), lock=args.lock,
                          substeps=args.substeps, tau0=args.tau0, skip=args.skip)
    if args.save_model:
        write_xml(rep.spec, args.save_model)
        record(args.save_model)
    if out is not None:
        write_log(simulated_log(rep.log, rep.result,
                                f"jointbench replay of {src.name} on {rep.model}"), out)
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        save_figure_atomic(plot_replay(rep.log, rep.result, f"replay of {src.name}"), args.plot)
        record(args.plot)
    if args.json:
        obj = report_json(rep)
        obj["out"] = None if out is None else str(out)
        print(json.dumps(finite_json(obj), allow_nan=False, default=float))
    else:
        print(format_report(rep))
        if out is not None:
            print(f"wrote {out}")
    return 0
