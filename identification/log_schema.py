"""The jointbench log schema (docs/log-format.md): the `Log` record, its errors (`LogError`)
and the metadata keys the analyses read as numbers or booleans.

A `Log` holds the sampled signals as numpy arrays and the metadata as strings; typed
accessors convert the keys the analyses use. Reading is `identification.log_read`, writing
`identification.log_write`; `identification.log` exports all three.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

FORMAT_KEY = "jointbench-log"
FORMAT_VERSION = "1"
REQUIRED_COLUMNS = ("t", "q_m", "tau_m")
OPTIONAL_COLUMNS = ("q", "q_ref")
# Metadata the analyses read as numbers: key -> must the value be positive?
NUMERIC_META = {"sample_rate_hz": True, "gravity": False, "kp": False, "kv": False,
                "ki": False, "tau_max": True, "gear_ratio": True}
BOOLEAN_META = ("velocity_feedforward",)


class LogError(ValueError):
    """A log that does not follow docs/log-format.md.

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
    """A sampled experiment (docs/log-format.md).

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
        return meta_number(key, self.meta[key], self.path, self.meta_lines.get(key))

    def meta_bool(self, key: str, default: bool) -> bool:
        if key not in self.meta:
            return default
        return meta_boolean(key, self.meta[key], self.path, self.meta_lines.get(key))

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


def shown(text: str, limit: int = 40) -> str:
    """`text` for an error message: non-printable characters escaped, long text cut."""
    shown = text if text.isprintable() else text.encode("unicode_escape").decode("ascii")
    return shown if len(shown) <= limit else shown[:limit] + "..."


def meta_number(key: str, value: str, path, line: int | None) -> float:
    """The first word of a metadata value as a number (a unit may follow: `9.81 m/s^2`)."""
    words = value.split()
    number = float(words[0]) if words and is_number(words[0]) else None
    if number is None:
        raise LogError(f"metadata '{shown(key)}' must be a number, got '{shown(value)}'",
                       path, line)
    if not math.isfinite(number):
        raise LogError(f"metadata '{shown(key)}' must be finite, got '{shown(value)}'", path,
                       line)
    if NUMERIC_META.get(key) and number <= 0:
        raise LogError(f"metadata '{key}' must be positive, got '{shown(value)}'", path, line)
    return number


def meta_boolean(key: str, value: str, path, line: int | None) -> bool:
    text = value.strip().lower()
    if text in ("true", "1", "yes"):
        return True
    if text in ("false", "0", "no"):
        return False
    raise LogError(f"metadata '{key}' must be true or false, got '{shown(value)}'", path, line)


def is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
