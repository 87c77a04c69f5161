"""What every command shares: exit codes, UsageError, the signal trap, the output-file check,
the one KEY=VALUE parser and the argument types. Standard library only (imported by `--help`).
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
import threading
from pathlib import Path
from typing import Callable

from jointbench.bench.options import key_numbers
from jointbench.bench.output_files import check_file

# Exit status (docs/cli.md).
EXIT_OK = 0
EXIT_FAILURE = 1    # anything else (an internal error)
EXIT_BAD_INPUT = 2  # a message on stderr naming the file, line or column
EXIT_GATES_FAILED = 3  # `campaign --require`: an accuracy gate failed


class UsageError(ValueError):
    """Bad command-line input (exit status 2)."""


class Terminated(BaseException):
    """SIGTERM (or SIGHUP) received: unwinds like KeyboardInterrupt, so that atomic writes
    remove their temporary file, and ends the command with status 128 + signal number."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def trap_signals() -> Callable[[], None]:
    """Turn SIGTERM and SIGHUP into Terminated for the duration of a command (main thread
    only); returns a function that restores the previous handlers."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handler(signum, frame):
        raise Terminated(signum)

    previous = {}
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            previous[getattr(signal, name)] = signal.signal(getattr(signal, name), handler)

    def restore():
        for signum, old in previous.items():
            signal.signal(signum, old)
    return restore


def check_output_file(out: Path, flag: str = "--out") -> None:
    """Refuse, before any computation, an output path whose folder is missing or read-only,
    that is not a regular file (a device node, a FIFO, a folder), or that is an existing
    non-empty file jointbench did not write (bench.output_files: the one output layer)."""
    check_file(out, flag)


def parse_key_values(text: str | None, flag: str, form: str, what: str = "value"
                     ) -> dict[str, float]:
    """`KEY=NUMBER,KEY=NUMBER` as a dict; UsageError naming `flag` and the expected `form`
    (e.g. "AXIS=ANGLE (e.g. axis2=-0.5,axis3=1.0)") for an item without `=`, and `what` the
    value is for one that is not a number."""
    if not text:
        return {}

    def bad_number(key: str, value: str) -> UsageError:
        return UsageError(f"{flag}: {what} '{value.strip()}' of {key.strip()} is not a finite "
                          "number")

    items = text.split(",")
    for item in items:  # float() takes 1_000, nan and inf: none is a value here
        key, _, value = item.partition("=")
        if "_" in value:
            raise bad_number(key, value)
    out = key_numbers(items, lambda item: UsageError(f"{flag}: '{item}' must read {form}"),
                      bad_number)
    for key, value in out.items():
        if not math.isfinite(value):
            raise bad_number(key, str(value))
    return out


def parse_config(text: str | None) -> dict[str, float]:
    """--config: the locked angles of the other axes, AXIS=ANGLE,... [rad]."""
    return parse_key_values(text, "--config", "AXIS=ANGLE (e.g. axis2=-0.5,axis3=1.0)",
                            "angle")


def number(value: str) -> float:
    """A float as the command line writes it: no digit separators (float() reads 1_000)."""
    if "_" in value:
        raise ValueError(f"'{value}' is not a number")
    return float(value)


def finite(value: str) -> float:
    """Argument type: a finite float."""
    x = number(value)
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"{value} is not a finite number")
    return x


def positive(value: str) -> float:
    """Argument type: a finite float > 0."""
    x = finite(value)
    if x <= 0:
        raise argparse.ArgumentTypeError(f"{value} must be positive")
    return x


def seed(value: str) -> int:
    """Argument type: a seed, an integer in [0, 2**32) (numpy's SeedSequence range is wider,
    but a log's `seed` metadata and a campaign's derived seeds stay in it)."""
    try:
        x = int(value.replace("_", "x"))  # int() reads 1_000: refused here
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{value}' is not an integer") from None
    if not 0 <= x < 2**32:
        raise argparse.ArgumentTypeError(f"{value} must lie in [0, 2**32)")
    return x


def one_line(err: BaseException) -> str:
    """The error's message on one line (MuJoCo's parser messages span several)."""
    return "; ".join(line.strip() for line in str(err).splitlines() if line.strip())


def is_simulation_error(err: Exception) -> bool:
    """A diverging or unstable virtual experiment or replay (bench.sim.experiment's
    SimulationError, bench.sim.replay's ReplayError, loaded only by the commands that
    simulate): bad input (gains, timestep, model), status 2."""
    experiment = sys.modules.get("jointbench.bench.sim.experiment")
    replay = sys.modules.get("jointbench.bench.sim.replay")
    return (experiment is not None and isinstance(err, experiment.SimulationError)) or \
        (replay is not None and isinstance(err, replay.ReplayError))
