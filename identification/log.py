"""The jointbench log: read, validate and write the CSV of CONTRACT section 1.

One source of truth for the log schema. A `Log` holds the sampled signals as numpy arrays
and the metadata as strings; typed accessors convert the keys the analyses use.
Errors are `LogError`, which names the file, the line and the column at fault.

Reading streams the file line by line (`read_log`): it never loads an arbitrary amount of
data blindly. A file over `max_bytes` (default 512 MiB, `DEFAULT_MAX_BYTES`; the environment
variable JOINTBENCH_MAX_LOG_BYTES or the `max_bytes` argument changes it, e.g. `2G`) and a
line over `MAX_LINE_BYTES` are refused with the line they reach, as are binary files (a NUL
byte, or bytes that are not UTF-8).
"""

from __future__ import annotations

import array
import difflib
import io
import math
import os
import stat
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np

FORMAT_KEY = "jointbench-log"
FORMAT_VERSION = "1"
REQUIRED_COLUMNS = ("t", "q_m", "tau_m")
OPTIONAL_COLUMNS = ("q", "q_ref")
JITTER_TOLERANCE = 0.01  # CONTRACT: jitter under 1 % of the period
DEFAULT_MAX_BYTES = 512 * 2**20  # a 60 s log at 350.87 Hz is about 2 MB
MAX_BYTES_ENV = "JOINTBENCH_MAX_LOG_BYTES"
MAX_LINE_BYTES = 2**16  # one metadata line or data row
# Metadata the analyses read as numbers: key -> must the value be positive?
NUMERIC_META = {"sample_rate_hz": True, "gravity": False, "kp": False, "kv": False,
                "ki": False, "tau_max": True, "gear_ratio": True}
BOOLEAN_META = ("velocity_feedforward",)
# A revolute position that spans more than a turn, or lies more than two turns from zero,
# looks like degrees (an identification experiment moves a joint by a fraction of a turn).
DEGREES_SPAN_RAD = 2 * math.pi


class LogError(ValueError):
    """A log that does not follow CONTRACT section 1.

    `str(err)` reads ``FILE:LINE: column 'c': what is wrong``; the parts that do not apply are
    left out.
    """

    def __init__(self, message: str, path: str | os.PathLike | None = None,
                 line: int | None = None, column: str | None = None):
        self.message = message
        self.path = None if path is None else str(path)
        self.line = line
        self.column = column
        where = self.path or "<log>"
        if line is not None:
            where += f":{line}"
        col = f" column '{column}':" if column is not None else ""
        super().__init__(f"{where}:{col} {message}")


@dataclass(frozen=True)
class Log:
    """A sampled experiment (CONTRACT section 1).

    Attributes are arrays of equal length: `t` [s], `q_m` motor position referred to the joint
    side [rad], `tau_m` motor torque referred to the joint side [N m], optional `q` link
    position [rad] and `q_ref` the tracked reference [rad]. `extra` holds any other column,
    `meta` the metadata as written (strings), `meta_lines` the line of each metadata key in
    the file it was read from (for error messages). Prismatic axes use m and N.
    """

    t: np.ndarray
    q_m: np.ndarray
    tau_m: np.ndarray
    q: np.ndarray | None = None
    q_ref: np.ndarray | None = None
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    meta: dict[str, str] = field(default_factory=dict)
    path: str | None = None
    meta_lines: dict[str, int] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.t)

    @property
    def sample_rate_hz(self) -> float:
        """The metadata's rate when given, else the one inferred from `t`."""
        value = self.meta_float("sample_rate_hz")
        return value if value is not None else 1.0 / float(np.median(np.diff(self.t)))

    @property
    def ts(self) -> float:
        """Sample period [s]."""
        return 1.0 / self.sample_rate_hz

    @property
    def gravity(self) -> float:
        value = self.meta_float("gravity")
        return 9.81 if value is None else value

    @property
    def prismatic(self) -> bool:
        return self.meta.get("axis", "").strip().lower().startswith("prismatic")

    def meta_float(self, key: str) -> float | None:
        """Metadata `key` as a float, None when absent; LogError when not a number."""
        if key not in self.meta:
            return None
        return _meta_number(key, self.meta[key], self.path, self.meta_lines.get(key))

    def meta_bool(self, key: str, default: bool) -> bool:
        if key not in self.meta:
            return default
        return _meta_boolean(key, self.meta[key], self.path, self.meta_lines.get(key))

    def truth(self) -> dict[str, float]:
        """Ground truth carried by a virtual log: metadata keys `truth_<name>` as floats."""
        out = {}
        for key in self.meta:
            if key.startswith("truth_"):
                try:
                    out[key[len("truth_"):]] = float(self.meta[key])
                except ValueError:
                    continue  # descriptive truth (an effect name) is not a number
        return out

    def columns(self) -> dict[str, np.ndarray]:
        """All columns in file order: required, optional present, then extras."""
        cols = {"t": self.t, "q_m": self.q_m}
        if self.q is not None:
            cols["q"] = self.q
        cols["tau_m"] = self.tau_m
        if self.q_ref is not None:
            cols["q_ref"] = self.q_ref
        cols.update(self.extra)
        return cols


def _show(text: str, limit: int = 40) -> str:
    """`text` for an error message: non-printable characters escaped, long text cut."""
    shown = text if text.isprintable() else text.encode("unicode_escape").decode("ascii")
    return shown if len(shown) <= limit else shown[:limit] + "..."


def _meta_number(key: str, value: str, path, line: int | None) -> float:
    """The first word of a metadata value as a number (a unit may follow: `9.81 m/s^2`)."""
    words = value.split()
    number = float(words[0]) if words and _is_number(words[0]) else None
    if number is None:
        raise LogError(f"metadata '{_show(key)}' must be a number, got '{_show(value)}'",
                       path, line)
    if not math.isfinite(number):
        raise LogError(f"metadata '{_show(key)}' must be finite, got '{_show(value)}'", path,
                       line)
    if NUMERIC_META.get(key) and number <= 0:
        raise LogError(f"metadata '{key}' must be positive, got '{_show(value)}'", path, line)
    return number


def _meta_boolean(key: str, value: str, path, line: int | None) -> bool:
    text = value.strip().lower()
    if text in ("true", "1", "yes"):
        return True
    if text in ("false", "0", "no"):
        return False
    raise LogError(f"metadata '{key}' must be true or false, got '{_show(value)}'", path, line)


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
            raise LogError(f"metadata line must read '# key: value', got '{_show(raw.strip())}'",
                           path, lineno)
        key, value = (part.strip() for part in body.split(":", 1))
        if not key:
            raise LogError(f"metadata line has no key before ':': '{_show(raw.strip())}'",
                           path, lineno)
        if key in meta and meta[key] != value:
            raise LogError(f"metadata '{_show(key)}' given twice with different values "
                           f"(line {where[key]}: '{_show(meta[key])}', here: '{_show(value)}')",
                           path, lineno)
        meta[key] = value
        where[key] = lineno
        if key in NUMERIC_META:
            _meta_number(key, value, path, lineno)
        elif key in BOOLEAN_META:
            _meta_boolean(key, value, path, lineno)
        elif key == FORMAT_KEY and value not in (FORMAT_VERSION, FORMAT_VERSION + ".0"):
            raise LogError(f"format version '{_show(value)}' is not supported (this reader "
                           f"knows version {FORMAT_VERSION})", path, lineno)
    return meta, where


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_header(header: list[str], raw: str, path, lineno: int) -> None:
    if any(header) and all(_is_number(name) for name in header if name):
        raise LogError("the first row after the metadata must be the header (for example "
                       f"t,q_m,q,tau_m,q_ref), found numbers: '{_show(raw)}'", path, lineno)
    for sep in (";", "\t", "|"):
        if len(header) == 1 and sep in raw:
            raise LogError(f"the header is separated by {sep!r}; the format uses ',' "
                           "(CONTRACT section 1)", path, lineno)
    for name in header:
        if not name:
            raise LogError("empty column name in the header", path, lineno)
    seen: set[str] = set()
    for name in header:
        if name in seen:
            raise LogError("duplicate column", path, lineno, _show(name))
        seen.add(name)
    for name in REQUIRED_COLUMNS:
        if name in header:
            continue
        hint = ""
        others = [h for h in header if h not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS]
        close = [h for h in others if h.strip('"\' ').lower() == name]
        close = close or difflib.get_close_matches(name, others, n=1, cutoff=0.6)
        if close:
            hint = f"; is '{_show(close[0])}' meant to be '{name}'?"
        raise LogError(f"required column missing (header has {_show(', '.join(header), 120)})"
                       f"{hint}", path, lineno, name)


def _bad_cell(cells: list[str], header: list[str], path, lineno: int) -> LogError:
    for col, cell in enumerate(cells):
        if not _is_number(cell):
            what = "empty cell" if not cell.strip() else f"not a number: '{_show(cell.strip())}'"
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
    cols = {name: data[:, i].copy() for i, name in enumerate(header)}
    log = Log(t=cols.pop("t"), q_m=cols.pop("q_m"), tau_m=cols.pop("tau_m"),
              q=cols.pop("q", None), q_ref=cols.pop("q_ref", None), extra=cols, meta=meta,
              path=path, meta_lines=meta_where)
    validate(log, row_lines=np.frombuffer(row_lines, dtype=np.int64))
    return log


def parse_log(text: str, path: str | os.PathLike | None = None) -> Log:
    """Parse the text of a log (CONTRACT section 1). Raises LogError naming line and column."""
    path = None if path is None else str(path)
    if "\x00" in text:
        lineno = text.count("\n", 0, text.index("\x00")) + 1
        raise LogError("binary file (NUL byte), not a CSV log", path, lineno)
    if text.startswith("\ufeff"):
        text = text[1:]
    return _parse_lines(enumerate(text.splitlines(), start=1), path)


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
    period = float(np.median(dt))
    jitter = np.abs(dt - period) / period
    bad = np.flatnonzero(~(jitter <= JITTER_TOLERANCE))
    if bad.size:
        k = int(bad[0]) + 1
        raise LogError(f"irregular sampling: step {dt[k - 1]:.6g} s against the median "
                       f"{period:.6g} s (jitter over 1 %)", log.path, line(k), "t")
    rate = log.meta_float("sample_rate_hz")
    if rate is not None and abs(rate * period - 1.0) > JITTER_TOLERANCE:
        raise LogError(f"metadata sample_rate_hz {rate:g} contradicts t "
                       f"({1.0 / period:.6g} Hz from the median step)", log.path,
                       log.meta_lines.get("sample_rate_hz"))


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


def read_log(path: str | os.PathLike, max_bytes: int | None = None) -> Log:
    """Read a log file, streaming it line by line. Raises LogError (file, line, column, what)
    on any malformed input, and for files over `max_bytes` (default `max_log_bytes()`)."""
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
            return _parse_lines(_stream_lines(handle, name, limit), name)
        except OSError as err:
            raise LogError(f"cannot read: {err.strerror}", name) from None


def unit_warnings(log: Log) -> list[str]:
    """Warnings (not errors) about units: revolute positions that look like degrees, i.e. that
    span more than a turn or lie more than two turns from zero (CONTRACT: radians)."""
    if log.prismatic:
        return []
    odd = []
    for name in ("q_m", "q", "q_ref"):
        x = getattr(log, name)
        if x is None:
            continue
        span, peak = float(np.ptp(x)), float(np.max(np.abs(x)))
        if span > DEGREES_SPAN_RAD or peak > 2 * DEGREES_SPAN_RAD:
            odd.append(f"'{name}' spans {span:.4g} ({span / (2 * math.pi):.3g} turns in rad) "
                       f"and reaches {peak:.4g}")
    if not odd:
        return []
    return [f"{log.path or '<log>'}: {'; '.join(odd)}: the positions look like degrees; "
            "CONTRACT section 1 wants radians (multiply by pi/180), or `axis: prismatic` "
            "metadata for a linear axis"]


def format_log(log: Log, precision: int = 12) -> str:
    """The CSV text of `log` (CONTRACT section 1), metadata first."""
    out = io.StringIO()
    out.write(f"# {FORMAT_KEY}: {FORMAT_VERSION}\n")
    for key, value in log.meta.items():
        if key == FORMAT_KEY:
            continue
        out.write(f"# {key}: {value}\n")
    cols = log.columns()
    out.write(",".join(cols) + "\n")
    table = np.column_stack(list(cols.values()))
    np.savetxt(out, table, delimiter=",", fmt=f"%.{precision}g")
    return out.getvalue()


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write `text` to `path` through a temporary file in the same folder and a rename, so that
    an interrupted write (an exception, KeyboardInterrupt, a signal turned into one) never
    leaves a half-written file: either the old content or the new one, and no temporary."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def write_log(log: Log, path: str | os.PathLike) -> None:
    """Write `log` to `path` atomically."""
    atomic_write_text(path, format_log(log))
