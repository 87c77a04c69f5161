"""The memory a command needs, estimated before it starts, and the limit it must stay under.

Every command holds a handful of arrays per log sample: the simulated signals and the log's
text (`simulate`: about 360 bytes a sample), the filtered signals, their
derivatives and the regressor (`identify`: about 480 bytes a sample; `diagnose` without the
forward view about 180). `BYTES_PER_SAMPLE` rounds the largest up to 1 KiB. A command that
would need more than the limit is refused with the number (exit status 2) instead of
swapping the machine to a halt or dying with MemoryError. The limit is the environment
variable JOINTBENCH_MAX_MEMORY_MB when set, else half of the physical memory.

Standard library only.
"""

from __future__ import annotations

import math
import os

from jointbench.bench.cli.common import UsageError

BYTES_PER_SAMPLE = 1024
MEMORY_ENV = "JOINTBENCH_MAX_MEMORY_MB"
BASE_MB = 200.0   # the interpreter, numpy, scipy, MuJoCo and a model (about 130-180 MB measured)


def memory_limit_mb(environ: dict[str, str] | None = None) -> float:
    """JOINTBENCH_MAX_MEMORY_MB, else half of the physical memory (4096 MB when unknown).
    UsageError when the variable is not a positive number."""
    environ = os.environ if environ is None else environ
    text = environ.get(MEMORY_ENV, "").strip()
    if text:
        try:
            value = float(text) if "_" not in text else math.nan
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise UsageError(f"{MEMORY_ENV}={text!r}: give a positive number of MB")
        return value
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2 / 2**20
    except (ValueError, OSError, AttributeError):
        return 4096.0


def check_memory(samples: float, what: str, copies: int = 1) -> float:
    """UsageError when `copies` (workers) of a command holding `samples` log samples would need
    more than the limit; returns the estimate in MB. `what` says where the samples come from
    (e.g. "--duration 1e+06 s at 1000 Hz")."""
    need = copies * (BASE_MB + samples * BYTES_PER_SAMPLE / 2**20)
    limit = memory_limit_mb()
    if not need <= limit:
        per = f" ({copies} workers)" if copies > 1 else ""
        raise UsageError(f"{what}: {samples:.3g} samples need about {need:,.0f} MB of memory"
                         f"{per}, over the {limit:,.0f} MB limit (set {MEMORY_ENV} to raise it)")
    return need
