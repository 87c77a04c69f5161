"""`jointbench identify FILE`: the axis parameters from a log (docs/cli.md), optionally
refined by closed-loop output error (--refine) and bias-corrected (--debias B)."""

from __future__ import annotations

import argparse
import json
import sys

from jointbench.bench.cli.common import UsageError, positive
from jointbench.identification.corrections import CORRECTIONS

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.bench.api",)


def add_arguments(i: argparse.ArgumentParser) -> None:
    """The options of `identify`."""
    i.add_argument("file", nargs="+",
                   help="log file (docs/log-format.md); several: runs of one axis, each "
                        "identified, then pooled (the run-to-run spread beside each run's sigma)")
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
                        "(identification/cross_validation.py)")
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
    i.add_argument("--plain", action="store_true",
                   help="the paper's chain alone: eqs. (26)-(29) design, eq. (22) central "
                        "differences, eq. (13) or (18)-(20), least squares; no correction "
                        "beyond it (docs/method.md)")
    i.add_argument("--corrections", metavar="NAME,...",
                   help="the corrections beyond the paper's chain to apply, separated by "
                        "commas, or none (default: all of them: " + ", ".join(CORRECTIONS) +
                        "; docs/method.md)")
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
    if args.plain and args.corrections is not None:
        raise UsageError("give --plain or --corrections, not both")
    if args.corrections is not None:
        names = [n.strip() for n in args.corrections.split(",")]
        unknown = [n for n in names if n not in CORRECTIONS and n != "none"]
        if unknown or ("none" in names and len(names) > 1):
            raise UsageError(f"--corrections {args.corrections}: names are none or "
                             f"{', '.join(CORRECTIONS)}, separated by commas")
    if args.stencil == 5 and (args.plain or (args.corrections is not None and "stencil5" not in
                                              args.corrections.split(","))):
        raise UsageError("--stencil 5 is the stencil5 correction, which --plain or "
                         "--corrections switches off")
    if args.debias is not None and args.debias < 2:
        raise UsageError(f"--debias needs at least 2 replicas, got {args.debias}")


MAX_ORDER = 20  # a Butterworth of higher order is numerically meaningless here


def _check_filter_options(args: argparse.Namespace) -> None:
    """UsageError naming the option: the frequency given twice, a decimation, order or skip
    out of range (the band against the log: `jointbench.identify`)."""
    if args.wn is not None and args.fc is not None:
        raise UsageError("give the Butterworth frequency once: --wn (rad/s) or --fc (Hz)")
    if args.decimate is not None and args.decimate < 1:
        raise UsageError(f"--decimate {args.decimate}: must be >= 1")
    if not 1 <= args.order <= MAX_ORDER:
        raise UsageError(f"--order {args.order}: must lie in [1, {MAX_ORDER}]")
    if args.skip < 0:
        raise UsageError(f"--skip {args.skip}: must be >= 0")


def _corrections(args: argparse.Namespace) -> tuple[str, ...] | None:
    """The `corrections` of `jointbench.identify`: () with --plain, the names given, None
    (all) by default."""
    if args.plain:
        return ()
    if args.corrections is None:
        return None
    return tuple(n.strip() for n in args.corrections.split(",") if n.strip() != "none")


def _debias_progress():
    """The replica bar on stderr (a terminal only), made at the first replica's report and
    closed at the last."""
    from jointbench.bench.cli.progress import bar

    state: dict = {}

    def at(done: int, total: int) -> None:
        if "bar" not in state:
            state["bar"] = bar("identify: bias correction", total, "replica")
        b = state["bar"]
        b.update(max(0, done - b.n))
        if done >= total:
            b.close()
    return at


def _refine_progress(msg: str) -> None:
    print(f"identify: {msg}", file=sys.stderr, flush=True)


def _warn(text: str) -> None:
    print(f"jointbench identify: warning: {text}", file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    """Parse, `jointbench.identify` (identify, refine, bias-correct, validate as asked),
    print the text or the JSON object."""
    from jointbench.bench.api import identify

    _check_options(args)
    _check_filter_options(args)
    files = args.file[0] if len(args.file) == 1 else list(args.file)
    fit = identify(files, args.model, wn=args.wn, fc_hz=args.fc, order=args.order,
                   Nd=args.decimate, skip=args.skip, zoh=not args.no_zoh,
                   filter_torque=not args.no_torque_filter, stencil=args.stencil,
                   f1_hz=args.f1, refine=args.refine, refine_max_nfev=args.refine_max_nfev,
                   debias=args.debias, friction_timeconst=args.friction_timeconst,
                   validate=args.validate, corrections=_corrections(args),
                   progress=None if args.json else _refine_progress,
                   replica_progress=None if args.json else _debias_progress(), warn=_warn)
    if args.json:
        print(json.dumps(fit.to_json(), allow_nan=False, default=float))
    else:
        print(fit.table())
    return 0
