"""The memory limit every command and API call stays under: JOINTBENCH_MAX_MEMORY_MB when set,
else half of the physical memory; and what a log sample costs (bench.cli.resources has the
measurements and the command line's refusal, bench.api_args the API's).

Standard library only.
"""

from __future__ import annotations

import math
import os

BYTES_PER_SAMPLE = 1024
MEMORY_ENV = "JOINTBENCH_MAX_MEMORY_MB"
BASE_MB = 200.0   # the interpreter, numpy, scipy, MuJoCo and a model (about 130-180 MB measured)


def memory_limit_mb(environ: dict[str, str] | None = None) -> float:
    """JOINTBENCH_MAX_MEMORY_MB, else half of the physical memory (4096 MB when unknown).
    ValueError when the variable is not a positive number."""
    environ = os.environ if environ is None else environ
    text = environ.get(MEMORY_ENV, "").strip()
    if text:
        try:
            value = float(text) if "_" not in text else math.nan
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{MEMORY_ENV}={text!r}: give a positive number of MB")
        return value
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2 / 2**20
    except (ValueError, OSError, AttributeError):
        return 4096.0


def samples_mb(samples: float, copies: int = 1) -> float:
    """The memory [MB] `copies` processes holding `samples` log samples each need."""
    return copies * (BASE_MB + samples * BYTES_PER_SAMPLE / 2**20)
