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
    """Refuse an output path whose folder is missing, that is a folder, or that is an existing
    non-empty file not written by jointbench (a measured log, say): outputs replace only
    jointbench's own files, and always atomically (identification.log.atomic_write_text)."""
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(f"{flag} {out}: folder {parent} does not exist")
    if out.is_dir():
        raise UsageError(f"{flag} {out}: is a directory")
    if out.exists() and out.stat().st_size > 0:
        try:
            with open(out, "rb") as handle:
                head = handle.read(8192).decode("utf-8", "replace")
        except OSError as err:
            raise UsageError(f"{flag} {out}: cannot read the existing file: {err.strerror}") \
                from None
        if "\n# source: jointbench " not in head:
            raise UsageError(f"{flag} {out}: refusing to overwrite an existing file that "
                             "jointbench did not write (no '# source: jointbench ...' metadata); "
                             "remove it or choose another name")


def parse_key_values(text: str | None, flag: str, form: str, what: str = "value"
                     ) -> dict[str, float]:
    """`KEY=NUMBER,KEY=NUMBER` as a dict; UsageError naming `flag` and the expected `form`
    (e.g. "AXIS=ANGLE (e.g. axis2=-0.5,axis3=1.0)") for an item without `=`, and `what` the
    value is for one that is not a number."""
    if not text:
        return {}
    return key_numbers(text.split(","),
                       lambda item: UsageError(f"{flag}: '{item}' must read {form}"),
                       lambda key, value: UsageError(f"{flag}: {what} '{value}' of {key} is "
                                                     "not a number"))


def parse_config(text: str | None) -> dict[str, float]:
    """--config: the locked angles of the other axes, AXIS=ANGLE,... [rad]."""
    return parse_key_values(text, "--config", "AXIS=ANGLE (e.g. axis2=-0.5,axis3=1.0)",
                            "angle")


def finite(value: str) -> float:
    """Argument type: a finite float."""
    x = float(value)
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"{value} is not a finite number")
    return x


def positive(value: str) -> float:
    """Argument type: a finite float > 0."""
    x = finite(value)
    if x <= 0:
        raise argparse.ArgumentTypeError(f"{value} must be positive")
    return x


def one_line(err: BaseException) -> str:
    """The error's message on one line (MuJoCo's parser messages span several)."""
    return "; ".join(line.strip() for line in str(err).splitlines() if line.strip())


def is_simulation_error(err: Exception) -> bool:
    """A diverging or unstable virtual experiment (bench.sim.experiment.SimulationError, loaded
    only by the commands that simulate): bad input (gains, timestep, model), status 2."""
    experiment = sys.modules.get("jointbench.bench.sim.experiment")
    return experiment is not None and isinstance(err, experiment.SimulationError)
