"""The jointbench log schema (docs/log-format.md): the `Log` record, its errors (`LogError`)
and the metadata keys the analyses read as numbers or booleans.

A `Log` holds the sampled signals as numpy arrays and the metadata as strings; typed
accessors convert the keys the analyses use. Reading is `identification.log.read`, writing
`identification.log.write`; `identification.log` exports all three.
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
                "ki": False, "tau_max": True, "gear_ratio": True,
                "pid_kp": False, "pid_ki": False, "pid_kd": False}
BOOLEAN_META = ("velocity_feedforward",)
# Metadata the replays read as numbers that cannot be negative (Sensors.from_log): a noise
# level and the encoders' steps (0: an ideal sensor).
NONNEGATIVE_META = ("torque_noise_std", "motor_encoder_resolution_rad",
                    "link_encoder_resolution_rad")
# The unit word a numeric key may carry after its number (docs/log-format.md), spaces, `*`
# and `.` between unit symbols ignored: SI on the joint side (a prismatic axis: N, m).
META_UNITS = {"sample_rate_hz": ("Hz",), "gravity": ("m/s^2", "m/s2", "m s^-2", "m/s²"),
              "kp": ("1/s", "s^-1"), "kv": ("N m s/rad", "N s/m"),
              "ki": ("N m/rad", "N/m"), "tau_max": ("N m", "N"), "gear_ratio": (),
              "pid_kp": ("N m/rad", "N/m"), "pid_ki": ("N m/(rad s)", "N m/rad/s", "N/(m s)"),
              "pid_kd": ("N m s/rad", "N s/m")}
# The metadata rate is used as it is when it agrees with `t` to this relative precision
# (the precision of the written time stamps); otherwise the rate comes from `t`.
RATE_AGREEMENT = 1e-6


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
    """A sampled experiment (docs/log-format.md). Prismatic axes use m and N in place of rad
    and N m.

    Parameters
    ----------
    t : ndarray
        Time [s].
    q_m : ndarray
        Motor position referred to the joint side [rad].
    tau_m : ndarray
        Motor torque referred to the joint side [N m].
    q : ndarray, optional
        Link position [rad].
    q_ref : ndarray, optional
        The tracked reference [rad].
    extra : dict of str to ndarray
        Any other column, by name.
    meta : dict of str to str
        The metadata as written.
    path : str, optional
        The file it was read from.
    meta_lines : dict of str to int
        The line of each metadata key in that file (for error messages).
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
    def rate_from_t(self) -> float | None:
        """(n - 1) / (t[-1] - t[0]) [Hz], the mean rate of the time stamps; None under 2
        samples."""
        n = len(self.t)
        if n < 2 or not self.t[-1] > self.t[0]:
            return None
        return (n - 1) / float(self.t[-1] - self.t[0])

    @property
    def sample_rate_hz(self) -> float:
        """The rate of `t` (`rate_from_t`); the metadata's value when it agrees with it to
        RATE_AGREEMENT (the same rate, written exactly) or when `t` has under 2 samples.
        The reader refuses a metadata rate off by over 1 % and warns over 0.05 %."""
        value = self.meta_float("sample_rate_hz")
        from_t = self.rate_from_t
        if from_t is None:
            return value if value is not None else float("nan")
        if value is not None and abs(value / from_t - 1.0) <= RATE_AGREEMENT:
            return value
        return from_t

    @property
    def ts(self) -> float:
        """Sample period [s]."""
        return 1.0 / self.sample_rate_hz

    @property
    def gravity(self) -> float:
        """Gravity acceleration [m/s^2] (metadata `gravity`, default 9.81)."""
        value = self.meta_float("gravity")
        return 9.81 if value is None else value

    @property
    def prismatic(self) -> bool:
        """A linear axis (metadata `axis: prismatic`): positions in m, forces in N."""
        return self.meta.get("axis", "").strip().lower().startswith("prismatic")

    def meta_float(self, key: str) -> float | None:
        """Metadata `key` as a float.

        Parameters
        ----------
        key : str
            The metadata key.

        Returns
        -------
        float or None
            Its value; None when absent.

        Raises
        ------
        LogError
            The value is not a number (names the file and line).
        """
        if key not in self.meta:
            return None
        return meta_number(key, self.meta[key], self.path, self.meta_lines.get(key))

    def meta_bool(self, key: str, default: bool) -> bool:
        """Metadata `key` as a boolean.

        Parameters
        ----------
        key : str
            The metadata key.
        default : bool
            The value when the key is absent.

        Returns
        -------
        bool
            true/false (or 1/0, yes/no) as written.

        Raises
        ------
        LogError
            The value is not a boolean (names the file and line).
        """
        if key not in self.meta:
            return default
        return meta_boolean(key, self.meta[key], self.path, self.meta_lines.get(key))

    def truth(self) -> dict[str, float]:
        """Ground truth carried by a virtual log.

        Returns
        -------
        dict of str to float
            The metadata keys `truth_<name>` as {name: value}; finite numbers only.
        """
        out = {}
        for key, value in self.meta.items():
            # descriptive truth (an effect name) is not a number; nan or inf is no truth
            if key.startswith("truth_") and is_number(value) and math.isfinite(float(value)):
                out[key[len("truth_"):]] = float(value)
        return out

    def columns(self) -> dict[str, np.ndarray]:
        """All columns in file order.

        Returns
        -------
        dict of str to ndarray
            The required columns, the optional ones present, then the extras.
        """
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


def _unit_key(text: str) -> str:
    return "".join(c for c in text if c not in " *.\u00b7")


def meta_number(key: str, value: str, path, line: int | None,
                units: tuple[str, ...] | None = None, positive: bool | None = None) -> float:
    """The first word of a metadata value as a number; the key's SI unit may follow
    (`9.81 m/s^2`: `units`, by default META_UNITS'), nothing else (`3 kN m` is refused, not
    read as 3). `positive` (by default NUMERIC_META's) refuses a value <= 0."""
    words = value.split()
    number = float(words[0]) if words and is_number(words[0]) else None
    if number is None:
        raise LogError(f"metadata '{shown(key)}' must be a number, got '{shown(value)}'",
                       path, line)
    unit = _unit_key(" ".join(words[1:]))
    allowed = META_UNITS.get(key, (unit,)) if units is None else units
    if unit and unit not in [_unit_key(u) for u in allowed]:
        allowed = META_UNITS.get(key, ()) if units is None else units
        raise LogError(f"metadata '{shown(key)}' must be a plain number"
                       + (f" (optionally followed by its SI unit {allowed[0]})" if allowed
                          else "") + f", got '{shown(value)}'", path, line)
    if not math.isfinite(number):
        raise LogError(f"metadata '{shown(key)}' must be finite, got '{shown(value)}'", path,
                       line)
    if (NUMERIC_META.get(key) if positive is None else positive) and number <= 0:
        raise LogError(f"metadata '{key}' must be positive, got '{shown(value)}'", path, line)
    if key in NONNEGATIVE_META and number < 0:
        raise LogError(f"metadata '{key}' must be >= 0 (0: an ideal sensor), got "
                       f"'{shown(value)}'", path, line)
    return number


def meta_boolean(key: str, value: str, path, line: int | None) -> bool:
    text = value.strip().lower()
    if text in ("true", "1", "yes"):
        return True
    if text in ("false", "0", "no"):
        return False
    raise LogError(f"metadata '{key}' must be true or false, got '{shown(value)}'", path, line)


def is_number(text: str) -> bool:
    """A number as the log format writes it: ASCII, no digit separator (float() also reads
    `1_000` and non-ASCII digits)."""
    if not text.isascii() or "_" in text:
        return False
    try:
        float(text)
    except ValueError:
        return False
    return True
