"""The wall time of every method on every log, beside a campaign's table: TABLE.times.csv,
`run,method,wall_s` (a built-in model, `MODEL+bc`, a plug-in label). Times are not in the
table itself, which stays the same byte for byte whatever the engine and the load; a resumed
campaign keeps the times of the runs it does not repeat."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from jointbench.identification.log import atomic_write_text

Times = dict[int, dict[str, float]]   # run -> method -> wall time [s]


def times_path(table: Path) -> Path:
    stem = table.with_suffix("") if table.suffix.lower() == ".csv" else table
    return Path(f"{stem}.times.csv")


def read_times(path: Path) -> Times:
    """The times file's content; {} when it is absent or unreadable (times are a by-product:
    never a reason to stop a campaign)."""
    out: Times = {}
    try:
        rows = list(csv.DictReader(io.StringIO(path.read_text(encoding="utf-8"))))
        for r in rows:
            out.setdefault(int(r["run"]), {})[r["method"]] = float(r["wall_s"])
    except (OSError, ValueError, KeyError, TypeError):
        return {}
    return out


def write_times(path: Path, times: Times) -> None:
    """Every run's times, sorted by run, written atomically."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["run", "method", "wall_s"])
    for run in sorted(times):
        for method, s in times[run].items():
            if math.isfinite(s):
                w.writerow([run, method, repr(float(s))])
    atomic_write_text(path, buf.getvalue())
