"""`jointbench tune-filter`: search wn and Nd minimising the error against truth over a small
campaign, beside the eq. (28)-(29) values (the search itself: bench.campaign.tuning).

Light at import (argparse, the standard library and the parameter table): `run` imports the
numerical modules when the command runs.
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Callable

from jointbench.bench.cli.common import seed
from jointbench.identification.parameters import FRICTIONS, STIFFNESS_AND_INERTIAS

DEFAULT_ND = (4, 8, 13, 20, 26, 30, 34, 38, 42, 46, 52)
OBJECTIVE_PARAMS = STIFFNESS_AND_INERTIAS + FRICTIONS   # what --params may name

# Imported by the dispatcher before it traps signals (see bench/cli/__init__.py).
LIBRARY = ("jointbench.bench.campaign.run", "jointbench.bench.campaign.tuning")


def _grid(text: str, kind: type, spaced: Callable[[float, float, int], tuple]) -> tuple:
    """'LO:HI:N' (N values from LO to HI spaced by `spaced`: bench.campaign.tuning's geometric
    wn or linear Nd) or a comma list V1,V2,... of `kind`; ValueError says what is wrong."""
    try:
        if ":" in text:
            lo, hi, n = text.split(":")
            return spaced(kind(lo), kind(hi), int(n))
        return tuple(kind(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"grid '{text}': expected LO:HI:N or V1,V2,... of "
                         f"{'numbers' if kind is float else 'integers'}") from None


def add_arguments(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    p.add_argument("--model", default="prototype", help="prototype, arm6 or an MJCF file")
    p.add_argument("--joint", help="axis to move (default: the first)")
    p.add_argument("--seeds", type=int, default=6,
                   help="search experiments; as many fresh ones validate (default 6)")
    p.add_argument("--seed", type=seed, default=0, help="campaign seed (default 0)")
    p.add_argument("--duration", type=float, default=60.0, help="experiment length in s")
    p.add_argument("--wn", default="60:1000:9",
                   help="wn grid [rad/s]: LO:HI:N geometric, or V1,V2,... (default 60:1000:9)")
    p.add_argument("--nd", default=",".join(map(str, DEFAULT_ND)),
                   help="Nd grid: LO:HI:N or V1,V2,... (default " + ",".join(map(str, DEFAULT_ND)) + ")")
    p.add_argument("--id-model", default="joint-motor", choices=("joint-motor", "motor-only"))
    p.add_argument("--params", default=",".join(STIFFNESS_AND_INERTIAS),
                   help=f"parameters in the objective (default {','.join(STIFFNESS_AND_INERTIAS)})")
    p.add_argument("--workers", type=int, help="local worker processes (default: all cores)")
    p.add_argument("--scheduler", help="an existing Dask cluster: tcp://HOST:PORT")
    p.add_argument("--json", action="store_true", help="print the result as one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def _check_grid(duration: float, wn_grid: tuple, Nd_grid: tuple, workers: int | None) -> None:
    """Before any experiment, every grid value a run can use (the campaign's checks,
    bench.campaign.spec.check_settings, naming the option and the value) and the memory."""
    import os

    from jointbench.bench.campaign.settings import RunSettings
    from jointbench.bench.campaign.spec import check_settings
    from jointbench.bench.cli.resources import check_memory
    from jointbench.identification.filter_choice import PAPER_RATE

    check_settings(RunSettings(duration=duration))
    for w in wn_grid:
        check_settings(RunSettings(duration=duration, wn=w), f"--wn grid value {w:g}")
    for n in Nd_grid:
        check_settings(RunSettings(duration=duration, Nd=n), f"--nd grid value {n}")
    check_memory(duration * PAPER_RATE, f"--duration {duration:g} s",
                 copies=workers or os.cpu_count() or 1)


def _first_failure(args: argparse.Namespace, wn: float, Nd: int) -> str:
    """The root cause behind a grid where nothing identified: the first search experiment
    and the first pair, run here, and the error they raise."""
    from jointbench.bench.campaign.tuning import _seeds
    from jointbench.bench.sim.experiment import run_experiment
    from jointbench.identification.filtering import FilterSettings
    from jointbench.identification.identify import identify

    seed = _seeds(args.seed, 0, 1)[0]
    try:
        log = run_experiment(args.model, args.joint, duration=args.duration, seed=seed).log
    except Exception as err:  # noqa: BLE001 - reported as the cause
        return f"the first experiment fails: {err}"
    try:
        identify(log, args.id_model, FilterSettings(wn=float(wn), m=4, Nd=int(Nd), ts=log.ts))
    except Exception as err:  # noqa: BLE001 - reported as the cause
        return f"the first experiment with wn = {wn:g}, Nd = {Nd}: {err}"
    return "the first experiment identifies with the first pair; a later one fails"


MAX_SEEDS = 10_000  # the tasks are built up front


def run(args: argparse.Namespace) -> int:
    """`jointbench tune-filter`: the grid search and its validation, printed as tables or JSON.
    Raises ValueError for bad options (exit status 2)."""
    from jointbench.bench.campaign.executors import make_executor
    from jointbench.bench.cli.progress import bar, runs
    from jointbench.bench.campaign.tuning import geometric_wn, linear_nd, result_text, tune_filter
    from jointbench.identification.output_values import finite_json

    if not 1 <= args.seeds <= MAX_SEEDS:
        raise ValueError(f"--seeds {args.seeds}: must lie in [1, {MAX_SEEDS}]")
    if args.seed < 0:
        raise ValueError(f"--seed must be >= 0, got {args.seed}")
    if not (math.isfinite(args.duration) and args.duration > 0):
        raise ValueError(f"--duration must be positive, got {args.duration}")
    wn_grid = _grid(args.wn, float, geometric_wn)
    Nd_grid = _grid(args.nd, int, linear_nd)
    if any(not (math.isfinite(w) and w > 0) for w in wn_grid) or any(n < 1 for n in Nd_grid):
        raise ValueError("grid values must be positive (wn) and >= 1 (Nd)")
    _check_grid(args.duration, wn_grid, Nd_grid, args.workers)
    params = tuple(p.strip() for p in args.params.split(",") if p.strip())
    if not params or any(p not in OBJECTIVE_PARAMS for p in params):
        raise ValueError(f"--params: choose among {', '.join(OBJECTIVE_PARAMS)}")
    executor = make_executor(args.workers, args.scheduler)
    try:
        with bar("tune-filter", 2 * args.seeds, "run", quiet=args.quiet) as b:
            r = tune_filter(args.model, args.joint, wn_grid, Nd_grid, args.seeds, executor,
                            duration=args.duration, seed=args.seed, id_model=args.id_model,
                            params=params, progress=runs(b))
    except ValueError as err:
        if "no (wn, Nd) pair" not in str(err):
            raise
        raise ValueError(f"{err}; {_first_failure(args, wn_grid[0], Nd_grid[0])}") from None
    finally:
        executor.close()
    if args.json:
        print(json.dumps(finite_json(r.as_dict()), allow_nan=False))
    else:
        print(result_text(r))
    return 0
