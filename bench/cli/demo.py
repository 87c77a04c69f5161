"""`jointbench demo`: the paper-prototype virtual experiment, both identification models,
tables against truth and the paper, figures (bench.demo.run_demo)."""

from __future__ import annotations

import argparse
from pathlib import Path

from jointbench.bench.cli.common import positive

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.bench.demo",)


def add_arguments(d: argparse.ArgumentParser) -> None:
    """The options of `demo`."""
    d.add_argument("--out", default="demo_out", help="folder for figures and tables (default demo_out)")
    d.add_argument("--duration", type=positive, default=60.0, help="experiment length in s (default 60)")
    d.add_argument("--seed", type=int, default=1, help="noise seed (default 1)")


def run(args: argparse.Namespace) -> int:
    """Run the demo into --out."""
    from jointbench.bench.demo import run_demo

    return run_demo(Path(args.out), duration=args.duration, seed=args.seed)
