"""The log argument of the public API: a Log, or the path of its file."""

from __future__ import annotations

import os

from jointbench.bench.sim.plant_keys import check
from jointbench.identification.log import Log, read_log

LogLike = Log | str | os.PathLike


def as_log(log: LogLike) -> Log:
    """`log` itself, or the log read from that file; the simulated plant's keys checked
    (LogError naming the file and line)."""
    return check(log if isinstance(log, Log) else read_log(log))


def log_name(log: LogLike, loaded: Log) -> str:
    """The log's name in reports: the path as given, else the Log's own, else "log"."""
    return str(log) if not isinstance(log, Log) else str(loaded.path or "log")
