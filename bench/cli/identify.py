"""`jointbench identify FILE`: the axis parameters from a log (docs/cli.md), optionally
refined by closed-loop output error (--refine) and bias-corrected (--debias B)."""

from __future__ import annotations

import argparse
import json
import math
import sys

from jointbench.bench.cli.common import UsageError, positive

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.bench.present.identify",)


def add_arguments(i: argparse.ArgumentParser) -> None:
    """The options of `identify`."""
    i.add_argument("file", help="log file (docs/log-format.md)")
    i.add_argument("--model", default="auto",
                   choices=("joint-motor", "motor-only", "motor-only-printed", "rigid", "auto"))
    i.add_argument("--wn", type=positive, help="Butterworth frequency in rad/s")
    i.add_argument("--fc", type=positive, help="Butterworth frequency in Hz (instead of --wn)")
    i.add_argument("--skip", type=int, default=0,
                   help="drop the first N samples after filtering, before decimation (default 0)")
    i.add_argument("--no-zoh", action="store_true",
                   help="rigid model: pair the logged torque with the positions as is, without "
                        "the zero-order-hold alignment (the EMPS reference chain)")
    i.add_argument("--no-torque-filter", action="store_true",
                   help="rigid model: the torque goes only through the decimation filter, not "
                        "the Butterworth (the EMPS reference chain)")
    i.add_argument("--stencil", type=int, default=None, choices=(3, 5),
                   help="central-difference points: 3, the paper's eq. (22) (default), or 5 "
                        "(fourth order: no sinc distortion of the derivatives)")
    i.add_argument("--order", type=int, default=4, help="Butterworth order m (default 4)")
    i.add_argument("--decimate", type=int, help="decimation factor Nd")
    i.add_argument("--f1", type=positive, help="first mode in Hz (to derive wn and Nd)")
    i.add_argument("--json", action="store_true", help="print the JSON object of docs/cli.md")
    i.add_argument("--validate", metavar="OTHER.csv",
                   help="predict another log's torque with the identified model (inverse "
                        "view, that log's own filter) and report the error beside the fit's "
                        "(identification/validate.py)")
    i.add_argument("--refine", action="store_true",
                   help="continue from the least-squares estimate by closed-loop output error "
                        "(DIDIM-style): replay the log in MuJoCo under its controller on the "
                        "two-mass axis and fit the torque (and q); needs q_ref and the gains "
                        "(bench/analysis/refine.py)")
    i.add_argument("--refine-max-nfev", type=int, default=None, metavar="N",
                   help="--refine: residual evaluations allowed (each one replay; default 40)")
    i.add_argument("--debias", type=int, default=None, metavar="B",
                   help="bias-correct the least-squares estimate by B closed-loop replicas of "
                        "the experiment on the nominal axis with the log's sensors (parametric "
                        "bootstrap; 8 is a good start; needs q_ref, the gains and the sensor "
                        "metadata; bench/analysis/debias.py)")
    i.add_argument("--friction-timeconst", type=positive, default=None, metavar="S",
                   help="--debias: Coulomb friction time constant of the nominal axis in s "
                        "(MuJoCo solreffriction; default: the log's friction_timeconst_s, which "
                        "jointbench logs carry, else 0.002 with a note)")


def _check_options(args: argparse.Namespace) -> None:
    """UsageError for options that apply only with another one."""
    if args.refine_max_nfev is not None and not args.refine:
        raise UsageError("--refine-max-nfev applies to --refine")
    if args.friction_timeconst is not None and args.debias is None:
        raise UsageError("--friction-timeconst applies to --debias")
    if args.debias is not None and args.debias < 2:
        raise UsageError(f"--debias needs at least 2 replicas, got {args.debias}")


MAX_ORDER = 20  # a Butterworth of higher order is numerically meaningless here


def _check_filter_options(args: argparse.Namespace, wn: float | None, log) -> None:
    """UsageError naming the option: a band the log cannot hold (below one cycle over the
    log, at or over the Nyquist frequency), a decimation, order or skip out of range."""
    if wn is not None:
        flag = "--wn" if args.wn is not None else "--fc"
        value = args.wn if args.wn is not None else args.fc
        duration = float(log.t[-1] - log.t[0])
        lo, hi = 2 * math.pi / duration, math.pi * log.sample_rate_hz
        if not lo <= wn < hi:
            raise UsageError(f"{flag} {value:g}: the Butterworth frequency must lie in "
                             f"[{lo:.3g}, {hi:.4g}) rad/s: at least one cycle over the "
                             f"{duration:.3g} s log, below the Nyquist frequency")
    if args.decimate is not None and args.decimate < 1:
        raise UsageError(f"--decimate {args.decimate}: must be >= 1")
    if not 1 <= args.order <= MAX_ORDER:
        raise UsageError(f"--order {args.order}: must lie in [1, {MAX_ORDER}]")
    if args.skip < 0:
        raise UsageError(f"--skip {args.skip}: must be >= 0")


def _filter_options(args: argparse.Namespace, log) -> tuple[float | None, dict] | None:
    """(wn in rad/s or None, the chain options) of the filter options, or None when they are
    all at their defaults (identify then chooses: identification.defaults.settings_for)."""
    if args.wn is not None and args.fc is not None:
        raise UsageError("give the Butterworth frequency once: --wn (rad/s) or --fc (Hz)")
    wn = args.wn if args.wn is not None else (
        2 * math.pi * args.fc if args.fc is not None else None)
    _check_filter_options(args, wn, log)
    chain = {"zoh": not args.no_zoh, "filter_torque": not args.no_torque_filter,
             "skip": args.skip, "stencil": args.stencil}
    if wn is None and args.decimate is None and args.order == 4 and \
            chain == {"zoh": True, "filter_torque": True, "skip": 0, "stencil": None}:
        return None
    return wn, chain


def _debias_progress(done: int, total: int) -> None:
    """The replica counter on stderr (rewritten in place on a terminal)."""
    if sys.stderr.isatty() or done == total:
        print(f"\ridentify: bias correction, replica {done}/{total}",
              end="" if done < total else "\n", file=sys.stderr, flush=True)


def _refine_progress(msg: str) -> None:
    print(f"identify: {msg}", file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    """Identify, refine, bias-correct as asked; print the text or the JSON object."""
    from jointbench.bench.analysis.debias import DebiasError, debias
    from jointbench.bench.analysis.refine import refine, require_replayable
    from jointbench.bench.present.identify import identify_json, identify_text
    from jointbench.bench.present.validate import forward_text, forward_validation
    from jointbench.bench.sim.sensors import Sensors
    from jointbench.identification.checks import estimate_flags
    from jointbench.identification.defaults import choose_filter
    from jointbench.identification.filtering import FilterSettings
    from jointbench.identification.identify import identify
    from jointbench.identification.log import read_log, unit_warnings
    from jointbench.identification.parameters import units
    from jointbench.identification.output import finite_json
    from jointbench.identification.saturation import clipping_warnings
    from jointbench.identification.sanity import sanity_warnings
    from jointbench.identification.physical import InversionError
    from jointbench.identification.validate import validate_on

    log = read_log(args.file)
    other = None if args.validate is None else read_log(args.validate)
    warnings = unit_warnings(log) + clipping_warnings(log)
    for text in warnings:
        print(f"jointbench identify: warning: {text}", file=sys.stderr)
    _check_options(args)
    if args.refine or args.debias is not None:
        require_replayable(log)  # before the least squares: no half answer
    if args.debias is not None and Sensors.from_log(log) is None:
        raise DebiasError(f"{args.file}: --debias replays the experiment with the log's "
                          "sensors: the metadata needs motor_encoder_resolution_rad, "
                          "link_encoder_resolution_rad and torque_noise_std")
    settings, mode = None, None
    options = _filter_options(args, log)
    if options is not None:
        wn, chain = options
        choice = choose_filter(log, args.f1)   # what the options override, and the first mode
        base, mode = choice.settings, choice.first_mode
        chain["stencil"] = chain["stencil"] or base.stencil
        settings = FilterSettings(wn=wn if wn is not None else base.wn, m=args.order,
                                  Nd=args.decimate if args.decimate is not None else base.Nd,
                                  ts=log.ts, **chain)
    try:
        result = identify(log, args.model, settings, f1_hz=args.f1, first_mode=mode)
    except InversionError as err:
        raise InversionError(f"{args.file}: {err}") from None
    truth = log.truth() or None
    flags = estimate_flags(result.physical, result.physical_sigma, log.prismatic)
    refined = None if not args.refine else refine(
        log, result, max_nfev=args.refine_max_nfev,
        progress=None if args.json else _refine_progress)
    debiased = None if args.debias is None else debias(
        log, result, replicas=args.debias, progress=None if args.json else _debias_progress,
        friction_timeconst=args.friction_timeconst)
    validation = None if other is None else validate_on(result, other, args.f1)
    forward = None if other is None else forward_validation(result, log, other)
    for text in sanity_warnings(result, log):   # mislabelled, too short, explains too little
        print(f"jointbench identify: warning: {text}", file=sys.stderr)
        warnings.append(text)
    if args.json:
        answer = identify_json(result, truth, flags, warnings, refined, debiased)
        if validation is not None:
            answer["validation"] = {**validation.to_json(), "forward": forward}
        print(json.dumps(finite_json(answer), allow_nan=False, default=float))
    else:
        print(identify_text(args.file, log, result, truth, flags, refined, debiased))
        if validation is not None:
            print(validation.text(units(log.prismatic)["offset"]))  # a torque (force)
            print(forward_text(forward, args.validate))
    return 0
