"""Reading a jointbench log (docs/log-format.md): parse, validate, stream, size limits.

Errors are `LogError`, which names the file, the line and the column at fault. Reading
streams the file line by line (`read_log`): it never loads an arbitrary amount of data
blindly. A file over `max_bytes` (default 512 MiB, `DEFAULT_MAX_BYTES`; the environment
variable JOINTBENCH_MAX_LOG_BYTES or the `max_bytes` argument changes it, e.g. `2G`) and a
line over `MAX_LINE_BYTES` are refused with the line they reach, as are binary files (a NUL
byte, or bytes that are not UTF-8).
"""

from __future__ import annotations

import array
import difflib
import math
import os
import stat
from pathlib import Path
from typing import Callable, Iterable, Iterator, TypeVar

import numpy as np

from jointbench.identification.log.schema import (BOOLEAN_META, FORMAT_KEY, FORMAT_VERSION,
                                                  NONNEGATIVE_META, NUMERIC_META,
                                                  OPTIONAL_COLUMNS,
                                                  REQUIRED_COLUMNS, Log, LogError, is_number,
                                                  meta_boolean, meta_number, shown)

T = TypeVar("T")
JITTER_TOLERANCE = 0.01  # docs/log-format.md: jitter under 1 % of the period
RATE_TOLERANCE = 0.01    # a metadata rate off the rate of `t` by more is refused ...
RATE_WARNING = 5e-4      # ... by more than this (0.05 %) gets a warning: `t` is used
# A drive log is sampled between these rates; outside them `t` is in the wrong unit (ms, us,
# ns since an epoch) and every rate-dependent estimate would be off by powers of 1000.
MIN_RATE_HZ, MAX_RATE_HZ = 10.0, 1e6
# Largest magnitude of a position or torque sample: beyond it a value is a corrupted cell
# (1e300 overflows the filters' fourth derivatives), not a measurement.
MAX_ABS_VALUE = 1e12
ANALYSED_COLUMNS = ("q_m", "q", "tau_m", "q_ref")
DEFAULT_MAX_BYTES = 512 * 2**20  # a 60 s log at the paper's rate is about 2 MB
MAX_BYTES_ENV = "JOINTBENCH_MAX_LOG_BYTES"
MAX_LINE_BYTES = 2**16  # one metadata line or data row
# A revolute position that spans more than a turn, or lies more than two turns from zero,
# looks like degrees (an identification experiment moves a joint by a fraction of a turn).
DEGREES_SPAN_RAD = 2 * math.pi


def _parse_metadata(lines: list[tuple[int, str]], path) -> tuple[dict[str, str], dict[str, int]]:
    """`# key: value` lines -> (meta, line of each key). The keys the analyses read as
    numbers or booleans are checked here, so that a bad value is reported with its line."""
    meta: dict[str, str] = {}
    where: dict[str, int] = {}
    for lineno, raw in lines:
        body = raw[1:].strip()
        if not body:
            continue
        if ":" not in body:
            raise LogError(f"metadata line must read '# key: value', got '{shown(raw.strip())}'",
                           path, lineno)
        key, value = (part.strip() for part in body.split(":", 1))
        if not key:
            raise LogError(f"metadata line has no key before ':': '{shown(raw.strip())}'",
                           path, lineno)
        if key in meta and meta[key] != value:
            raise LogError(f"metadata '{shown(key)}' given twice with different values "
                           f"(line {where[key]}: '{shown(meta[key])}', here: '{shown(value)}')",
                           path, lineno)
        meta[key] = value
        where[key] = lineno
        if key in NUMERIC_META or key in NONNEGATIVE_META:
            meta_number(key, value, path, lineno)
        elif key in BOOLEAN_META:
            meta_boolean(key, value, path, lineno)
        elif key == FORMAT_KEY and value not in (FORMAT_VERSION, FORMAT_VERSION + ".0"):
            raise LogError(f"format version '{shown(value)}' is not supported (this reader "
                           f"knows version {FORMAT_VERSION})", path, lineno)
    return meta, where


def _check_header(header: list[str], raw: str, path, lineno: int) -> None:
    if any(header) and all(is_number(name) for name in header if name):
        raise LogError("the first row after the metadata must be the header (for example "
                       f"t,q_m,q,tau_m,q_ref), found numbers: '{shown(raw)}'", path, lineno)
    for sep in (";", "\t", "|"):
        if len(header) == 1 and sep in raw:
            raise LogError(f"the header is separated by {sep!r}; the format uses ',' "
                           "(docs/log-format.md)", path, lineno)
    for name in header:
        if not name:
            raise LogError("empty column name in the header", path, lineno)
    seen: set[str] = set()
    for name in header:
        if name in seen:
            raise LogError("duplicate column", path, lineno, shown(name))
        seen.add(name)
    for name in REQUIRED_COLUMNS:
        if name in header:
            continue
        hint = ""
        others = [h for h in header if h not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS]
        close = [h for h in others if h.strip('"\' ').lower() == name]
        close = close or difflib.get_close_matches(name, others, n=1, cutoff=0.6)
        if close:
            hint = f"; is '{shown(close[0])}' meant to be '{name}'?"
        raise LogError(f"required column missing (header has {shown(', '.join(header), 120)})"
                       f"{hint}", path, lineno, name)


def _bad_cell(cells: list[str], header: list[str], path, lineno: int) -> LogError:
    for col, cell in enumerate(cells):
        if not is_number(cell):
            what = "empty cell" if not cell.strip() else f"not a number: '{shown(cell.strip())}'"
            return LogError(what, path, lineno, header[col])
    return LogError("unreadable row", path, lineno)  # pragma: no cover - float() failed above


def _parse_lines(lines: Iterable[tuple[int, str]], path) -> Log:
    """The parser behind `parse_log` and `read_log`: numbered lines (no line ends) -> Log."""
    meta_lines: list[tuple[int, str]] = []
    meta: dict[str, str] = {}
    meta_where: dict[str, int] = {}
    header: list[str] | None = None
    header_line = 0
    ncols = 0
    values = array.array("d")
    row_lines = array.array("q")
    seen_text = False
    for lineno, line in lines:
        if header is None:
            if line.startswith("#"):
                meta_lines.append((lineno, line))
                seen_text = True
                continue
            if not line.strip():
                continue
            seen_text = True
            meta, meta_where = _parse_metadata(meta_lines, path)
            header = [name.strip() for name in line.split(",")]
            header_line = lineno
            _check_header(header, line, path, lineno)
            ncols = len(header)
            continue
        if not line.strip():
            continue
        cells = line.split(",")
        if len(cells) != ncols:
            raise LogError(f"expected {ncols} cells, found {len(cells)}", path, lineno)
        if "_" in line or not line.isascii():  # float() reads 1_000 and non-ASCII digits
            raise _bad_cell(cells, header, path, lineno)
        try:
            values.extend([float(cell) for cell in cells])
        except ValueError:
            raise _bad_cell(cells, header, path, lineno) from None
        row_lines.append(lineno)
    if not seen_text:
        raise LogError("empty file", path)
    if header is None:
        _parse_metadata(meta_lines, path)
        raise LogError("no header row after the metadata", path)
    n = len(row_lines)
    if n == 0:
        raise LogError("no data rows after the header", path, header_line)
    data = np.frombuffer(values, dtype=float).reshape(n, ncols)
    finite = np.isfinite(data)
    if not finite.all():
        row, col = divmod(int(np.argmin(finite.ravel())), ncols)
        raise LogError(f"non-finite value '{float(data[row, col])!r}'", path, int(row_lines[row]),
                       header[col])
    for col, name in enumerate(header):
        if name in ANALYSED_COLUMNS:
            big = np.flatnonzero(np.abs(data[:, col]) > MAX_ABS_VALUE)
            if big.size:
                raise LogError(f"value {data[big[0], col]:.6g} is out of range (over "
                               f"{MAX_ABS_VALUE:g} in magnitude): a corrupted cell, not a "
                               "measurement", path, int(row_lines[big[0]]), name)
    cols = {name: data[:, i].copy() for i, name in enumerate(header)}
    log = Log(t=cols.pop("t"), q_m=cols.pop("q_m"), tau_m=cols.pop("tau_m"),
              q=cols.pop("q", None), q_ref=cols.pop("q_ref", None), extra=cols, meta=meta,
              path=path, meta_lines=meta_where)
    validate(log, row_lines=np.frombuffer(row_lines, dtype=np.int64))
    return log


def parse_log(text: str, path: str | os.PathLike | None = None) -> Log:
    """Parse the text of a log (docs/log-format.md). Raises LogError naming line and column."""
    path = None if path is None else str(path)
    if "\x00" in text:
        lineno = text.count("\n", 0, text.index("\x00")) + 1
        raise LogError("binary file (NUL byte), not a CSV log", path, lineno)
    if text.startswith("\ufeff"):
        text = text[1:]
    return _parse_lines(enumerate(text.splitlines(), start=1), path)


def sampling_jitter(dt: np.ndarray) -> tuple[float, np.ndarray, int | None]:
    """(median step, |step - median| / median of every step, the index in t of the first
    sample whose step is off by more than JITTER_TOLERANCE, or None) of the steps `dt`."""
    period = float(np.median(dt))
    jitter = np.abs(dt - period) / period
    bad = np.flatnonzero(~(jitter <= JITTER_TOLERANCE))
    return period, jitter, (int(bad[0]) + 1 if bad.size else None)


def validate(log: Log, first_data_line: int | None = None,
             row_lines: np.ndarray | None = None) -> None:
    """Check sampling: at least 3 samples, `t` strictly increasing, uniform within 1 %, and a
    metadata rate that agrees with `t`. `row_lines` (or `first_data_line`, when the rows
    follow each other without blank lines) gives the file line of each sample for the
    messages. Raises LogError."""
    def line(k: int) -> int | None:
        if row_lines is not None:
            return int(row_lines[k])
        return None if first_data_line is None else first_data_line + k

    n = len(log.t)
    if n < 3:
        raise LogError(f"only {n} samples, at least 3 are needed", log.path)
    dt = np.diff(log.t)
    bad = np.flatnonzero(~(dt > 0))
    if bad.size:
        k = int(bad[0]) + 1
        raise LogError(f"t is not strictly increasing ({float(log.t[k - 1])!r} then "
                       f"{float(log.t[k])!r})",
                       log.path, line(k), "t")
    period, jitter, k = sampling_jitter(dt)
    if k is not None:
        raise LogError(f"irregular sampling: step {dt[k - 1]:.6g} s against the median "
                       f"{period:.6g} s (jitter over 1 %)", log.path, line(k), "t")
    from_t = float(log.rate_from_t)
    if not MIN_RATE_HZ <= from_t <= MAX_RATE_HZ:
        raise LogError(f"t advances {period:.6g} per sample ({from_t:.4g} Hz): not a drive "
                       f"log's rate ({MIN_RATE_HZ:g} Hz to {MAX_RATE_HZ:g} Hz); t must be in "
                       "seconds" + (" (from milliseconds: divide by 1000)"
                                    if from_t < MIN_RATE_HZ else ""), log.path, line(1), "t")
    rate = log.meta_float("sample_rate_hz")
    if rate is not None and abs(rate / from_t - 1.0) > RATE_TOLERANCE:
        raise LogError(f"metadata sample_rate_hz {rate:g} contradicts t "
                       f"({from_t:.6g} Hz from the time stamps, over 1 % apart)", log.path,
                       log.meta_lines.get("sample_rate_hz"))


def rate_warnings(log: Log) -> list[str]:
    """A warning when the metadata rate and the rate of `t` differ by over 0.05 % (under
    1 %, or the reader refuses the log): the analyses use the rate of `t`."""
    rate, from_t = log.meta_float("sample_rate_hz"), log.rate_from_t
    if rate is None or from_t is None or abs(rate / from_t - 1.0) <= RATE_WARNING:
        return []
    where = f"{log.path or '<log>'}" + (f":{log.meta_lines['sample_rate_hz']}"
                                        if "sample_rate_hz" in log.meta_lines else "")
    return [f"{where}: metadata sample_rate_hz {rate:g} differs from the rate of t "
            f"({from_t:.6g} Hz) by {100 * (rate / from_t - 1):+.3g} %; the rate of t is used"]


def parse_size(text: str) -> int:
    """A byte count such as `1048576`, `64M`, `2G` (binary units); ValueError otherwise."""
    units = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
    body = text.strip().upper().removesuffix("IB").removesuffix("B")
    unit = body[-1:] if body[-1:] in units and body[-1:] else ""
    try:
        value = float(body[: len(body) - len(unit)])
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{text!r} is not a size in bytes (for example 1048576, 64M, 2G)")
    return int(value * units[unit])


def max_log_bytes(environ: dict[str, str] | None = None) -> int:
    """The read limit: JOINTBENCH_MAX_LOG_BYTES from `environ` (default os.environ) when set,
    else DEFAULT_MAX_BYTES. ValueError when the variable is not a size."""
    environ = os.environ if environ is None else environ
    text = environ.get(MAX_BYTES_ENV)
    if text is None or not text.strip():
        return DEFAULT_MAX_BYTES
    try:
        return parse_size(text)
    except ValueError as err:
        raise ValueError(f"{MAX_BYTES_ENV}: {err}") from None


def _size(n: int) -> str:
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n} bytes"


def _stream_lines(handle, path: str, max_bytes: int) -> Iterator[tuple[int, str]]:
    """Numbered text lines of a binary stream, read one line at a time (at most
    MAX_LINE_BYTES each); LogError for binary content, over-long lines, or past max_bytes."""
    total = 0
    lineno = 0
    while True:
        raw = handle.readline(MAX_LINE_BYTES + 1)
        if not raw:
            return
        lineno += 1
        total += len(raw)
        if b"\x00" in raw:
            at = raw.index(b"\x00") + 1
            raise LogError(f"binary file (NUL byte at byte {at} of the line), not a CSV log",
                           path, lineno)
        if total > max_bytes:
            raise LogError(f"the file is larger than the {_size(max_bytes)} limit for a log "
                           f"(set {MAX_BYTES_ENV}, e.g. 2G, to read it)", path, lineno)
        if len(raw) > MAX_LINE_BYTES and not raw.endswith(b"\n"):
            raise LogError(f"line longer than {_size(MAX_LINE_BYTES)}: not a CSV log", path,
                           lineno)
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as err:
            raise LogError(f"not UTF-8 text (byte {err.start + 1} of the line): a binary file "
                           "or another encoding", path, lineno) from None
        if lineno == 1 and text.startswith("\ufeff"):
            text = text[1:]
        yield lineno, text.rstrip("\r\n")


def read_lines(path: str | os.PathLike, parse: Callable[[Iterator[tuple[int, str]], str], T],
               max_bytes: int | None = None) -> T:
    """`parse(lines, name)` on the numbered text lines of the file at `path`, streamed with
    the reader's checks: LogError for a missing file or a folder, a file over `max_bytes`
    (default `max_log_bytes()`), binary content, over-long lines and read errors. Shared by
    `read_log` and the import of measured files (identification/log/raw.py)."""
    limit = max_log_bytes() if max_bytes is None else int(max_bytes)
    path = Path(path)
    name = str(path)
    try:
        handle = open(path, "rb")
    except FileNotFoundError:
        raise LogError("no such file", name) from None
    except IsADirectoryError:
        raise LogError("is a directory, not a log file", name) from None
    except OSError as err:
        raise LogError(f"cannot read: {err.strerror}", name) from None
    with handle:
        try:
            info = os.fstat(handle.fileno())
            if stat.S_ISDIR(info.st_mode):
                raise LogError("is a directory, not a log file", name)
            if stat.S_ISREG(info.st_mode) and info.st_size > limit:
                raise LogError(f"the file is {_size(info.st_size)}, over the {_size(limit)} "
                               f"limit for a log (set {MAX_BYTES_ENV}, e.g. 2G, to read it)",
                               name)
            return parse(_stream_lines(handle, name, limit), name)
        except OSError as err:
            raise LogError(f"cannot read: {err.strerror}", name) from None


def read_log(path: str | os.PathLike, max_bytes: int | None = None) -> Log:
    """Read a log file (docs/log-format.md), streaming it line by line.

    Parameters
    ----------
    path : str or PathLike
        The log file.
    max_bytes : int, optional
        The largest file read (default `max_log_bytes()`).

    Returns
    -------
    Log
        The validated log.

    Raises
    ------
    LogError
        Any malformed input (naming the file, line and column), or a file over `max_bytes`.
    """
    return read_lines(path, _parse_lines, max_bytes)


def position_quantum(x: np.ndarray) -> float | None:
    """The step of an encoder's position x: the q such that every nonzero sample difference
    is a whole number of steps (the 99th percentile of the distance to the nearest multiple
    under 2 % of q), fitted by least squares over all differences; None when x is not
    quantised that way or moves less than 50 times."""
    x = np.asarray(x, dtype=float)
    d = np.abs(np.diff(x))
    # differences under the text's precision (12 digits) are rounding, not a step
    d = d[np.isfinite(d) & (d > 1e-9 * max(1.0, float(np.nanmax(np.abs(x)))))]
    if len(d) < 50:
        return None
    k = np.round(d / d.min())
    if np.quantile(np.abs(d / d.min() - k), 0.99) > 0.02:
        return None
    return float(np.sum(d * k) / np.sum(k * k))


def _whole(c: float) -> bool:
    # a whole number of steps a turn, to the text's precision (12 digits, docs/log-format.md)
    return abs(c - round(c)) < 1e-3 + 1e-6 * c


def steps_per_turn(x: np.ndarray) -> tuple[str, float] | None:
    """("rad" or "deg", steps a turn) when the position's encoder step divides a turn in
    exactly one of the two units (2 pi / q or 360 / q whole, not both), else None: what the
    encoder says of the unit, whatever the position spans."""
    q = position_quantum(x)
    if q is None:
        return None
    rad, deg = _whole(2 * math.pi / q), _whole(360.0 / q)
    if rad == deg:
        return None
    return ("rad", 2 * math.pi / q) if rad else ("deg", 360.0 / q)


def unit_warnings(log: Log) -> list[str]:
    """Warnings (not errors) about units: a metadata rate that differs from the rate of `t`
    (`rate_warnings`), and revolute measured positions (q_m, q; not q_ref, which a low-gain
    position loop makes large by design) that look like degrees. The encoder decides first:
    a step that divides a turn in radians (4096 counts: 2 pi / 4096) is radians however far
    the axis turns, one that divides it in degrees only is degrees (`steps_per_turn`);
    otherwise a position that spans more than a turn or lies more than two turns from zero
    looks like degrees (docs/log-format.md: radians)."""
    if log.prismatic:
        return rate_warnings(log)
    odd = []
    for name in ("q_m", "q"):     # measured: a reference may span turns by design
        x = getattr(log, name)
        if x is None:
            continue
        steps = steps_per_turn(x)
        if steps is not None and steps[0] == "rad":
            continue
        span, peak = float(np.ptp(x)), float(np.max(np.abs(x)))
        if steps is not None:
            odd.append(f"'{name}' moves in steps of {360.0 / steps[1]:.6g}, 360 / "
                       f"{steps[1]:.6g}: an encoder's counts in degrees")
        elif span > DEGREES_SPAN_RAD or peak > 2 * DEGREES_SPAN_RAD:
            odd.append(f"'{name}' spans {span:.4g} ({span / (2 * math.pi):.3g} turns in rad) "
                       f"and reaches {peak:.4g}")
    if not odd:
        return rate_warnings(log)
    return rate_warnings(log) + [f"{log.path or '<log>'}: {'; '.join(odd)}: the positions look like degrees; "
            "docs/log-format.md wants radians (multiply by pi/180), or `axis: prismatic` "
            "metadata for a linear axis"]
