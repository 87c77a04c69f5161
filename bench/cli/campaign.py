"""`jointbench campaign`: N virtual experiments identified, the table and the Monte Carlo
summary. A shim over bench.campaign.run until its argument code moves here."""

from __future__ import annotations

import argparse

from jointbench.bench.campaign import run as _campaign

LIBRARY: tuple[str, ...] = ()  # imported above


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of `campaign` (bench.campaign.run.add_arguments)."""
    _campaign.add_arguments(p)


def run(args: argparse.Namespace) -> int:
    """Run the campaign (bench.campaign.run.main)."""
    return _campaign.main(args)
