"""`jointbench demo`: the paper-prototype virtual experiment, both identification models,
tables against truth and the paper, figures (bench.demo.run_demo)."""

from __future__ import annotations

import argparse
from pathlib import Path

from jointbench.bench.cli.common import UsageError, positive, seed
from jointbench.bench.cli.resources import check_memory

# The library `run` imports, loaded by the dispatcher before it traps the signals.
LIBRARY = ("jointbench.bench.demo",)


def add_arguments(d: argparse.ArgumentParser) -> None:
    """The options of `demo`."""
    d.add_argument("--out", default="demo_out", help="folder for figures and tables (default demo_out)")
    d.add_argument("--duration", type=positive, default=60.0, help="experiment length in s (default 60)")
    d.add_argument("--seed", type=seed, default=1, help="noise seed (default 1)")


# Every file the demo may write in --out (bench.output_files.OutputFolder).
FILES = ("prototype.csv", "report.md", "figure1.png", "figure2.png", "figure2_joint_motor.png",
         "frequency_response.png", "discrepancy/*")


def run(args: argparse.Namespace) -> int:
    """Run the demo into --out (checked first; written all or nothing)."""
    from jointbench.bench.demo import run_demo
    from jointbench.bench.output_files import OutputFolder
    from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ

    from jointbench.bench.campaign.spec import MIN_DURATION_S

    if args.duration < MIN_DURATION_S:
        raise UsageError(f"--duration {args.duration:g}: must be at least {MIN_DURATION_S:g} s "
                         "(the chirp fades in and out over 2 s each)")
    folder = OutputFolder(Path(args.out), FILES)
    check_memory(args.duration * SAMPLE_RATE_HZ, f"--duration {args.duration:g} s")
    with folder.writing() as out:
        return run_demo(out, duration=args.duration, seed=args.seed)
