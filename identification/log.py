"""The jointbench log: read, validate and write the CSV of CONTRACT section 1.

One source of truth for the log schema. A `Log` holds the sampled signals as numpy arrays
and the metadata as strings; typed accessors convert the keys the analyses use.
Errors are `LogError`, which names the file, the line and the column at fault.
"""

from __future__ import annotations

import io
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

FORMAT_KEY = "jointbench-log"
FORMAT_VERSION = "1"
REQUIRED_COLUMNS = ("t", "q_m", "tau_m")
OPTIONAL_COLUMNS = ("q", "q_ref")
JITTER_TOLERANCE = 0.01  # CONTRACT: jitter under 1 % of the period


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
    `meta` the metadata as written (strings). Prismatic axes use m and N.
    """

    t: np.ndarray
    q_m: np.ndarray
    tau_m: np.ndarray
    q: np.ndarray | None = None
    q_ref: np.ndarray | None = None
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    meta: dict[str, str] = field(default_factory=dict)
    path: str | None = None

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
        text = self.meta[key].split()[0] if self.meta[key].split() else ""
        try:
            value = float(text)
        except ValueError:
            raise LogError(f"metadata '{key}' must be a number, got '{self.meta[key]}'",
                           self.path) from None
        if not math.isfinite(value):
            raise LogError(f"metadata '{key}' must be finite, got '{self.meta[key]}'", self.path)
        return value

    def meta_bool(self, key: str, default: bool) -> bool:
        if key not in self.meta:
            return default
        text = self.meta[key].strip().lower()
        if text in ("true", "1", "yes"):
            return True
        if text in ("false", "0", "no"):
            return False
        raise LogError(f"metadata '{key}' must be true or false, got '{self.meta[key]}'", self.path)

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


def _parse_metadata(lines: list[tuple[int, str]], path) -> dict[str, str]:
    meta: dict[str, str] = {}
    for lineno, raw in lines:
        body = raw[1:].strip()
        if not body:
            continue
        if ":" not in body:
            raise LogError(f"metadata line must read '# key: value', got '{raw.strip()}'",
                           path, lineno)
        key, value = body.split(":", 1)
        meta[key.strip()] = value.strip()
    return meta


def parse_log(text: str, path: str | os.PathLike | None = None) -> Log:
    """Parse the text of a log (CONTRACT section 1). Raises LogError naming line and column."""
    path = None if path is None else str(path)
    if "\x00" in text:
        raise LogError("binary file, not a CSV log", path)
    lines = text.splitlines()
    if not any(line.strip() for line in lines):
        raise LogError("empty file", path)
    meta_lines: list[tuple[int, str]] = []
    index = 0
    while index < len(lines) and (lines[index].startswith("#") or not lines[index].strip()):
        if lines[index].startswith("#"):
            meta_lines.append((index + 1, lines[index]))
        index += 1
    meta = _parse_metadata(meta_lines, path)
    if index >= len(lines):
        raise LogError("no header row after the metadata", path)
    header_line = index + 1
    header = [name.strip() for name in lines[index].split(",")]
    for name in header:
        if not name:
            raise LogError("empty column name in the header", path, header_line)
    if len(set(header)) != len(header):
        dup = next(n for n in header if header.count(n) > 1)
        raise LogError("duplicate column", path, header_line, dup)
    for name in REQUIRED_COLUMNS:
        if name not in header:
            raise LogError(f"required column missing (header has {', '.join(header)})",
                           path, header_line, name)
    body = [(i + 1, line) for i, line in enumerate(lines[index + 1:], start=index + 1)
            if line.strip()]
    data = np.empty((len(body), len(header)))
    for row, (lineno, line) in enumerate(body):
        cells = line.split(",")
        if len(cells) != len(header):
            raise LogError(f"expected {len(header)} cells, found {len(cells)}", path, lineno)
        for col, cell in enumerate(cells):
            try:
                value = float(cell)
            except ValueError:
                raise LogError(f"not a number: '{cell.strip()}'", path, lineno,
                               header[col]) from None
            if not math.isfinite(value):
                raise LogError(f"non-finite value '{cell.strip()}'", path, lineno, header[col])
            data[row, col] = value
    cols = {name: data[:, i].copy() for i, name in enumerate(header)}
    log = Log(t=cols.pop("t"), q_m=cols.pop("q_m"), tau_m=cols.pop("tau_m"),
              q=cols.pop("q", None), q_ref=cols.pop("q_ref", None), extra=cols, meta=meta,
              path=path)
    validate(log, first_data_line=header_line + 1)
    return log


def validate(log: Log, first_data_line: int | None = None) -> None:
    """Check sampling: at least 3 samples, `t` strictly increasing, uniform within 1 %, and a
    metadata rate that agrees with `t`. Raises LogError."""
    line = (lambda k: None if first_data_line is None else first_data_line + k)
    n = len(log.t)
    if n < 3:
        raise LogError(f"only {n} samples, at least 3 are needed", log.path)
    dt = np.diff(log.t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise LogError(f"t is not strictly increasing ({log.t[k - 1]!r} then {log.t[k]!r})",
                       log.path, line(k), "t")
    period = float(np.median(dt))
    jitter = np.abs(dt - period) / period
    bad = np.flatnonzero(jitter > JITTER_TOLERANCE)
    if bad.size:
        k = int(bad[0]) + 1
        raise LogError(f"irregular sampling: step {dt[k - 1]:.6g} s against the median "
                       f"{period:.6g} s (jitter over 1 %)", log.path, line(k), "t")
    rate = log.meta_float("sample_rate_hz")
    if rate is not None:
        if rate <= 0 or abs(rate * period - 1.0) > JITTER_TOLERANCE:
            raise LogError(f"metadata sample_rate_hz {rate:g} contradicts t "
                           f"({1.0 / period:.6g} Hz)", log.path)


def read_log(path: str | os.PathLike) -> Log:
    """Read a log file. Raises LogError (file, line, column, what) on any malformed input."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise LogError("no such file", path) from None
    except IsADirectoryError:
        raise LogError("is a directory, not a log file", path) from None
    except OSError as err:
        raise LogError(f"cannot read: {err.strerror}", path) from None
    if b"\x00" in raw[:65536]:
        raise LogError("binary file, not a CSV log", path)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise LogError(f"not UTF-8 text (byte {err.start})", path) from None
    return parse_log(text, path)


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
    an interrupted write never leaves a half-written file."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as handle:
            handle.write(text)
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
