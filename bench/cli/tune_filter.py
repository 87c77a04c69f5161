"""`jointbench tune-filter`: search wn and Nd over a campaign. A shim over
bench.campaign.tuning until its argument code moves here."""

from __future__ import annotations

import argparse

from jointbench.bench.campaign import tuning as _tuning

LIBRARY: tuple[str, ...] = ()  # imported above


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of `tune-filter` (bench.campaign.tuning.add_arguments)."""
    _tuning.add_arguments(p)


def run(args: argparse.Namespace) -> int:
    """Run the search (bench.campaign.tuning.main)."""
    return _tuning.main(args)
