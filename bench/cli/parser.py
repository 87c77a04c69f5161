"""The argparse tree of `jointbench`: the top level and one sub-parser per command.

argparse and the standard library only. A command's own options are added by its module's
`add_arguments(p)`, and that module is imported only when the command is parsed (run or asked
for its --help): `jointbench --help` loads no command module.
"""

from __future__ import annotations

import argparse
import importlib
from typing import NamedTuple

import jointbench


class Command(NamedTuple):
    module: str   # jointbench.bench.cli.<module>: add_arguments(p), run(args) -> int
    help: str


COMMANDS: dict[str, Command] = {
    "demo": Command("demo", "the paper-prototype virtual experiment, both models, tables and "
                            "figures"),
    "simulate": Command("simulate", "run one virtual experiment and write its log"),
    "identify": Command("identify", "identify the axis parameters from a log"),
    "import": Command("import_log", "convert a measured file (own columns, units, motor side, "
                                    "current) into a jointbench log"),
    "design-filter": Command("design_filter", "the bandpass design of eqs. (26)-(29)"),
    "diagnose": Command("diagnose", "what the simulation gets wrong on a log, the named cause, "
                                    "the extended model and the gain"),
    "campaign": Command("campaign", "N virtual experiments identified, a table row per run, "
                                    "bias, spread and sigma coverage (local cores or a Dask "
                                    "cluster)"),
    "survey": Command("survey", "every axis of a robot in turn: chirp experiment, identification "
                                "with the defaults, one table against the truth, a figure"),
    "flexify": Command("flexify", "a rigid MJCF arm (hinges driven by gear motors) made "
                                  "flexible in the axis convention: rotor, spring, motor"),
    "tune-filter": Command("tune_filter", "search wn and Nd minimising the error against truth "
                                          "over a campaign, beside the eq. (28)-(29) values"),
}


def command_module(name: str):
    """The module of command `name` (imported now)."""
    return importlib.import_module(f"jointbench.bench.cli.{COMMANDS[name].module}")


class _CommandParser(argparse.ArgumentParser):
    """A command's sub-parser: its options are added from the command's module the first
    time it parses or formats its help."""

    def __init__(self, *args, command: str | None = None, **kwargs):
        super().__init__(*args, **kwargs)
        self._command = command

    def _load(self) -> None:
        if self._command is not None:
            name, self._command = self._command, None
            command_module(name).add_arguments(self)

    def parse_known_args(self, args=None, namespace=None):
        self._load()
        return super().parse_known_args(args, namespace)

    def format_help(self) -> str:
        self._load()
        return super().format_help()

    def format_usage(self) -> str:
        self._load()
        return super().format_usage()


def build_parser() -> argparse.ArgumentParser:
    """The `jointbench` parser: `--version` and the COMMANDS."""
    p = argparse.ArgumentParser(prog="jointbench", description=(
        "Virtual testbench and identification of joint stiffness "
        "(Pham, Gautier, Poignet, ICRA 2001)."))
    p.add_argument("--version", action="version", version=f"jointbench {jointbench.__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_CommandParser)
    for name, command in COMMANDS.items():
        sub.add_parser(name, help=command.help, command=name)
    return p
