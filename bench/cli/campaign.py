"""`jointbench campaign`: N virtual experiments, each identified, one table row per run, and the
Monte Carlo summary (bias, empirical std, mean reported sigma, +-2 sigma coverage).

The spec (bench.campaign.spec), the runs (bench.campaign.run), the resumable table
(bench.campaign.table) and the summary (bench.campaign.summary) live in bench/campaign/.
Engines (bench.campaign.executors): all local cores by default, `--workers N`, or an existing
Dask cluster with `--scheduler tcp://HOST:PORT`. Plug-in estimators (`--method`,
bench.campaign.methods) run on every log beside the built-in models; accuracy gates
(`--require`, bench.campaign.gates) end the command with status 3 when one fails, and
`--junit` writes them as a JUnit report (bench.campaign.junit).

Light at import (argparse, the standard library and bench.campaign.settings): `run` imports
the numerical modules when the command runs.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Callable

from jointbench.bench.campaign.settings import SWEEPABLE, CampaignError, RunSettings
from jointbench.bench.cli.common import EXIT_GATES_FAILED, positive

# Imported by the dispatcher before it traps signals (see bench/cli/__init__.py).
LIBRARY = ("jointbench.bench.api", "jointbench.bench.campaign.run", "jointbench.bench.campaign.summary",
           "jointbench.bench.campaign.table", "jointbench.bench.campaign.gates",
           "jointbench.bench.campaign.junit", "jointbench.bench.effects")


def _parse_sweep(text: str) -> tuple[str, tuple[float, ...]]:
    """`NAME=V1,V2,...` -> (NAME, values of NAME's type); CampaignError says what is wrong."""
    if "=" not in text:
        raise CampaignError(f"--sweep '{text}': expected NAME=V1,V2,... "
                            f"(NAME one of {', '.join(SWEEPABLE)})")
    name, values = text.split("=", 1)
    name = name.strip()
    if name not in SWEEPABLE:
        raise CampaignError(f"--sweep: cannot sweep {name!r} (sweepable: {', '.join(SWEEPABLE)})")
    out = []
    for v in values.split(","):
        try:
            x = SWEEPABLE[name](v.strip())
        except ValueError:
            raise CampaignError(f"--sweep {name}: value {v!r} is not "
                                f"{'an integer' if SWEEPABLE[name] is int else 'a number'}") from None
        if not math.isfinite(x):
            raise CampaignError(f"--sweep {name}: value {v!r} is not finite")
        out.append(x)
    return name, tuple(out)


def _method_timeout(value: str) -> float:
    """Argument type of --method-timeout: a number of seconds in (0, 1e6]."""
    x = positive(value)
    if x > 1e6:
        raise argparse.ArgumentTypeError(f"{value} s is over the longest deadline, 1e6 s "
                                         "(give a number in (0, 1e6])")
    return x


def add_arguments(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    p.add_argument("--model", default="prototype",
                   help="prototype, arm6 or an MJCF file following the axis convention")
    p.add_argument("--joint", help="axis to move (default: the first)")
    p.add_argument("--runs", type=int, default=200,
                   help="runs (per sweep value with --sweep; default 200)")
    p.add_argument("--seed", type=int, default=0, help="campaign seed (default 0)")
    p.add_argument("--duration", type=float, default=60.0, help="experiment length in s (default 60)")
    p.add_argument("--amplitude", type=float, help="chirp amplitude in rad (default: automatic)")
    p.add_argument("--rate", type=float, default=None,
                   help="acquisition and control rate in Hz (default: the bench's, as simulate)")
    p.add_argument("--noise", type=float, default=1.0,
                   help="torque noise as a multiple of the default 1.25 %% of tau_max (default 1)")
    p.add_argument("--motor-bits", type=int, help="motor encoder bits per turn (default 17)")
    p.add_argument("--link-bits", type=int, help="link encoder bits per turn (default 20)")
    p.add_argument("--scatter", type=float, default=0.0,
                   help="relative (log-normal) scatter of K, Jm, JL, FVm, FSm, FV, FS around "
                        "the model, e.g. 0.1 (default 0)")
    p.add_argument("--wn", type=float, help="Butterworth frequency in rad/s (default: designed "
                                            "from the log's first mode, as identify does)")
    p.add_argument("--decimate", type=int, help="decimation factor Nd (default: as --wn)")
    p.add_argument("--stencil", type=int, choices=(3, 5),
                   help="central-difference points: 3, the paper's eq. (22), or 5 (default: "
                        "from f1 / Fs, as identify does)")
    p.add_argument("--effect", help="hidden effect(s) in every run: "
                                    "NAME=STRENGTH[:OPTION=VALUE][,NAME=STRENGTH...]")
    p.add_argument("--id-models", default="joint-motor,motor-only",
                   help="identification models, comma separated (default joint-motor,motor-only)")
    p.add_argument("--debias", type=int, default=0, metavar="B",
                   help="also bias-correct every two-mass estimate by B closed-loop replicas "
                        "(bench/analysis/debias.py; each run then costs about 1 + B experiments; "
                        "default 0: off)")
    p.add_argument("--sweep", help="sweep one setting: NAME=V1,V2,... with NAME one of "
                                   + ", ".join(SWEEPABLE))
    p.add_argument("--workers", type=int,
                   help="local worker processes (default: all cores; 1 runs in this process)")
    p.add_argument("--scheduler", help="run on an existing Dask cluster: tcp://HOST:PORT")
    p.add_argument("--out", default="campaign.csv",
                   help="table file; an existing one of the same campaign is resumed "
                        "(default campaign.csv)")
    p.add_argument("--method", action="append", metavar="[LABEL=]TARGET",
                   help="also run a plug-in estimator on every log: MODULE:FUNCTION (the "
                        "current folder is importable) or FILE.py:FUNCTION, a function of a "
                        "jointbench.Log returning {name: value} or {name: (value, sigma)} with "
                        "the paper's names; repeatable")
    p.add_argument("--method-timeout", type=_method_timeout, default=60.0, metavar="S",
                   help="deadline of one plug-in call (and of the import of its module) in "
                        "s, at most 1e6; past it the call is stopped and fails for that run "
                        "(default 60)")
    p.add_argument("--require", action="append", metavar="GATES",
                   help="accuracy gates, e.g. \"K.abs_bias_pct<0.5, Jm.coverage_pct>=90, "
                        "failed==0\" or \"mymethod:K.rmse_pct<1\"; exit status 3 when one "
                        "fails (grammar: docs/cli.md); repeatable")
    p.add_argument("--junit", metavar="FILE.xml", help="write the gates as a JUnit report")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def spec_arguments(args: argparse.Namespace, parse_effect: Callable[[str], object]) -> dict:
    """The CampaignSpec keyword arguments (base, runs, seed, sweep, values) of the command line.
    `parse_effect` (bench.effects', passed in: it imports MuJoCo) checks --effect. Raises
    CampaignError, or ValueError for a malformed --effect."""
    for name in ("duration", "noise", "scatter", "amplitude", "wn", "rate"):
        v = getattr(args, name)
        if v is not None and not math.isfinite(v):
            raise CampaignError(f"--{name}: {v} is not finite")
    if args.duration <= 0:
        raise CampaignError(f"--duration must be positive, got {args.duration:g}")
    if args.noise < 0:
        raise CampaignError(f"--noise must be >= 0, got {args.noise:g}")
    if args.rate is not None and not 10.0 <= args.rate <= 1e5:
        raise CampaignError(f"--rate must lie in 10 Hz to 100 kHz, got {args.rate:g}")
    if args.scatter < 0:
        raise CampaignError(f"--scatter must be >= 0, got {args.scatter:g}")
    if not 0 <= args.seed < 2**32:
        raise CampaignError(f"--seed must be >= 0 and below 2**32, got {args.seed}")
    if args.effect:
        parse_effect(args.effect)  # ValueError names what is wrong
    base = RunSettings(model=str(args.model), joint=args.joint, duration=args.duration,
                       amplitude=args.amplitude, noise=args.noise, motor_bits=args.motor_bits,
                       link_bits=args.link_bits, scatter=args.scatter, wn=args.wn,
                       Nd=args.decimate, stencil=args.stencil, effect=args.effect,
                       debias=args.debias, rate=args.rate,
                       id_models=tuple(m.strip() for m in args.id_models.split(",") if m.strip()))
    sweep, values = _parse_sweep(args.sweep) if args.sweep else (None, ())
    if not str(args.model) in ("prototype", "prototype_axis", "arm6") and not Path(args.model).is_file():
        raise CampaignError(f"--model {args.model}: no such model file")
    return dict(base=base, runs=args.runs, seed=args.seed, sweep=sweep, values=values)


def _progress(args: argparse.Namespace, out: Path):
    """The campaign's start line and progress bar on stderr (none with --quiet)."""
    from jointbench.bench.cli.progress import bar, runs

    def start(total: int, done: int, engine: str):
        if args.quiet:
            return None
        print(f"campaign: {total} runs ({done} already in {out}) on {engine}",
              file=sys.stderr)
        return runs(bar("campaign", total, "run", initial=done))
    return start


def run(args: argparse.Namespace) -> int:
    """Parse, `jointbench.campaign` (run or resume, the table and its summaries written),
    print. Exit status 3 when an accuracy gate failed, else 1 when no run succeeded."""
    from jointbench.bench.api import campaign
    from jointbench.bench.campaign.summary import summary_paths
    from jointbench.bench.effects import parse_effects

    spec = spec_arguments(args, parse_effects)
    base, out = spec["base"], Path(args.out)
    report = campaign(
        base.model, base.joint, runs=spec["runs"], seed=spec["seed"], duration=base.duration,
        methods=args.method or [], method_timeout=args.method_timeout, require=args.require,
        id_models=base.id_models,
        sweep=(spec["sweep"], spec["values"]) if spec["sweep"] else None,
        workers=args.workers, scheduler=args.scheduler, out=out, junit=args.junit,
        progress=_progress(args, out), amplitude=base.amplitude, noise=base.noise,
        motor_bits=base.motor_bits, link_bits=base.link_bits, scatter=base.scatter,
        wn=base.wn, Nd=base.Nd, stencil=base.stencil, effect=base.effect,
        debias=base.debias, rate=base.rate)
    if args.json:
        print(json.dumps(report.to_json(), allow_nan=False))
    else:
        json_path, md_path = summary_paths(out)
        print(f"table: {out}; summary: {json_path}, {md_path}")
        print(report.timing_line())
        print(report.table())
    failed = report.failed_gates
    if failed:
        print(f"jointbench campaign: {len(failed)} of {len(report.gates)} accuracy gates "
              "failed: " + "; ".join(f"{r.name} ({r.message})" for r in failed),
              file=sys.stderr)
        return EXIT_GATES_FAILED
    return 0 if report.summary["ok"] > 0 else 1
