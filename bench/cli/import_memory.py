"""`import` under the memory limit (JOINTBENCH_MAX_MEMORY_MB, bench.cli.resources): a raw
table is held as 8-byte floats, and its conversion, the log written block by block and read
back hold a fixed number of arrays of its size, `BYTES_PER_VALUE` bytes per raw value in
all. A regular file is refused before it is read when its size, over the bytes per value of
its first rows, says it would need more than the limit; any input (a pipe too) is refused
as soon as the values read pass what the limit allows.

Standard library only at import (the reader loads numpy when called).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from jointbench.bench.cli.common import UsageError
from jointbench.bench.cli.resources import MEMORY_ENV, memory_limit_mb

# Peak memory of `import` per raw value, the interpreter's BASE_MB left out: the raw table
# (8 B), the converted columns and their temporaries, the log's arrays, the written text's
# blocks and the read-back's arrays (measured with 1 M rows of 5 columns: 40 B a value over
# the 40 MB the command takes with an empty table; rounded up).
BYTES_PER_VALUE = 64
# The command with an empty table: the interpreter, numpy and the reader (36-40 MB measured;
# no MuJoCo, unlike resources.BASE_MB).
BASE_MB = 64.0
SAMPLE_BYTES = 1 << 16   # the head of a file read to estimate its bytes per value
DELIMITERS = (",", ";", "\t", "|")


def budget_values(limit_mb: float) -> int:
    """The raw values `import` may hold under `limit_mb`."""
    return max(int((limit_mb - BASE_MB) * 2**20 / BYTES_PER_VALUE), 0)


def estimated_values(path: Path, delimiter: str | None) -> float | None:
    """The values of the regular file `path`, from its size and the bytes per value of its
    first rows; None for a file that is not regular or whose head holds under 2 rows."""
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):
            return None
        with open(path, "rb") as f:
            head = f.read(SAMPLE_BYTES)
    except OSError:
        return None
    lines = head.split(b"\n")
    if len(head) == SAMPLE_BYTES:
        lines = lines[:-1]          # a partial last line
    rows = [ln for ln in lines if ln.strip() and not ln.lstrip().startswith(b"#")][1:]
    if len(rows) < 2:
        return None
    text = [r.decode("utf-8", "replace") for r in rows]
    sep = delimiter or max(DELIMITERS, key=text[0].count)
    cells = sum(t.count(sep) + 1 for t in text)
    size = sum(len(r) + 1 for r in rows)
    return info.st_size * cells / size


def _refusal(src: Path, text: str, limit: float) -> UsageError:
    return UsageError(f"{src}: {text}, over the {limit:,.0f} MB memory limit (set "
                      f"{MEMORY_ENV} to raise it, or import a shorter excerpt)")


def read_within_memory(src: Path, delimiter: str | None):
    """The RawTable of `src` (log_import.read_raw), or UsageError before the table would
    need more than the memory limit (module docstring)."""
    from jointbench.identification.log.raw import TooLarge, read_raw

    limit = memory_limit_mb()
    budget = budget_values(limit)
    estimate = estimated_values(src, delimiter)
    if estimate is not None and estimate > budget:
        size = os.path.getsize(src) / 2**20
        need = BASE_MB + estimate * BYTES_PER_VALUE / 2**20
        raise _refusal(src, f"the file ({size:,.1f} MB) holds about {estimate:.3g} values, "
                       f"which need about {need:,.0f} MB of memory to import", limit)
    try:
        return read_raw(src, delimiter, max_values=budget)
    except TooLarge as err:
        raise _refusal(src, f"line {err.line}: the input passes {budget:,} values, the most "
                       f"that import holds ({BYTES_PER_VALUE} bytes each)", limit) from None
