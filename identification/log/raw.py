"""Importing a measured file into a jointbench log (docs/log-format.md, README "Your own data").

A raw file is a CSV table with its own column names and units, motor-side angles (encoder
counts, degrees) and a current instead of a torque. `convert` maps its columns onto the log's
(`t`, `q_m`, `q`, `tau_m`, `q_ref`), converts the units to SI and radians (m and N for a
prismatic axis), refers the motor side to the joint side with the gear ratio N (angles / N,
torque x N) and the current to a torque with the torque constant, checks the sampling and
returns the `Log` with the metadata given, plus the list of what it did and what it checked.
Pure numerics: no MuJoCo, no file writing (the command line writes with `write_log`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from jointbench.identification.log.read import (MAX_ABS_VALUE, MAX_RATE_HZ, MIN_RATE_HZ,
                                                sampling_jitter, unit_warnings, validate)
from jointbench.identification.log.schema import (BOOLEAN_META, NONNEGATIVE_META, NUMERIC_META,
                                                  OPTIONAL_COLUMNS, REQUIRED_COLUMNS, Log,
                                                  LogError, meta_boolean, meta_number)
from jointbench.identification.log.write import check_writable
# the raw table's reader, re-exported: the command line and the tests import it from here
from jointbench.identification.raw_table import RawTable, TooLarge, parse_raw, read_raw

LOG_COLUMNS = REQUIRED_COLUMNS + OPTIONAL_COLUMNS
POSITIONS = ("q_m", "q", "q_ref")
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
# Position units -> factor to rad (revolute) or m (prismatic); `counts` needs the encoder's
# counts per turn.
POSITION_UNITS = {"rad": 1.0, "deg": math.pi / 180, "rev": 2 * math.pi, "m": 1.0, "mm": 1e-3,
                  "um": 1e-6, "counts": None}
LENGTH_UNITS = ("m", "mm", "um")
# Torque units: N m (N for prismatic) as is; A or V times the torque constant.
TORQUE_UNITS = {"Nm": 1.0, "N": 1.0, "A": None, "V": None}
DEFAULT_UNITS = {"t": "s", "q_m": "rad", "q": "rad", "tau_m": "Nm", "q_ref": "rad"}
MOTOR_SIDE = ("q_m", "tau_m", "q_ref")  # measured on the motor shaft by default (with N)
GAIN_POWERS = {"kv": 2, "ki": 2, "tau_max": 1}  # motor-side gain x N^power = joint side
# Metadata an import checks against a drive's range (the reader checks only the sign the
# analyses need): key -> (lowest, highest). A gain is >= 0 (0: no such term); gravity is an
# acceleration magnitude, 0 for a horizontal axis, and no robot works under 100 m/s^2.
META_RANGES = {"kp": (0.0, math.inf), "kv": (0.0, math.inf), "ki": (0.0, math.inf),
               "gravity": (0.0, 100.0)}
# The fastest rate a drive logs its axis at (current loops run at 10-40 kHz, their logs at
# most at the loop's rate): above it, the time column's unit is the likely slip (seconds
# declared as ms gives 1000 times the rate).
MAX_DRIVE_RATE_HZ = 40e3


@dataclass(frozen=True)
class ImportSpec:
    """How to convert a raw table. `columns`: log column -> raw column name (`t`, `q_m`,
    `tau_m` required); `units`: log column -> unit (DEFAULT_UNITS otherwise); `gear_ratio` N
    (> 0) refers the `motor_side` columns to the joint side (angles / N, torque x N; for a
    prismatic axis N is motor rad per m); `counts_per_turn`, `link_counts_per_turn`: encoder
    counts per turn of the motor shaft and of the link; `torque_constant` [N m/A, or per V]
    for a torque column in A or V; `rate_hz`: the drive's fixed rate, t rebuilt as
    t0 + k / rate; `meta`: metadata keys of docs/log-format.md (strings); `gains_side`:
    `motor` when kv, ki, tau_max in `meta` are motor-side (x N^2, N^2, N)."""

    columns: dict[str, str]
    units: dict[str, str] = field(default_factory=dict)
    gear_ratio: float | None = None
    motor_side: tuple[str, ...] = MOTOR_SIDE
    counts_per_turn: float | None = None
    link_counts_per_turn: float | None = None
    torque_constant: float | None = None
    rate_hz: float | None = None
    meta: dict[str, str] = field(default_factory=dict)
    gains_side: str = "joint"


@dataclass(frozen=True)
class ImportResult:
    """The converted `log`, what was done (`steps`), the checks run and their outcome
    (`checks`), and warnings (not errors)."""

    log: Log
    steps: tuple[str, ...]
    checks: tuple[str, ...]
    warnings: tuple[str, ...]


def _check_spec(raw: RawTable, spec: ImportSpec) -> None:
    """LogError for a mapping or a unit that cannot be converted (the option is named)."""
    for col in REQUIRED_COLUMNS:
        if col not in spec.columns:
            raise LogError(f"--map gives no column for '{col}' (required: t, q_m, tau_m; "
                           f"the file has {', '.join(raw.header)})", raw.path)
    for col, name in spec.columns.items():
        if col not in LOG_COLUMNS:
            raise LogError(f"--map: '{col}' is not a log column ({', '.join(LOG_COLUMNS)})",
                           raw.path)
        if name not in raw.header:
            raise LogError(f"--map {col}={name}: no column '{name}' (the file has "
                           f"{', '.join(raw.header)})", raw.path, int(raw.lines[0]) - 1)
    taken: dict[str, str] = {}
    for col, name in spec.columns.items():
        if name in taken:
            raise LogError(f"--map {taken[name]}={name},{col}={name}: one raw column for two "
                           "log columns (each log column is its own measurement)", raw.path)
        taken[name] = col
    table = {"t": TIME_UNITS, "tau_m": TORQUE_UNITS}
    for col, unit in spec.units.items():
        known = table.get(col, POSITION_UNITS)
        if col not in LOG_COLUMNS or unit not in known:
            raise LogError(f"--units {col}={unit}: not a unit of {col} "
                           f"({', '.join(known)})", raw.path)
    for col in spec.motor_side:
        if col not in MOTOR_SIDE:
            raise LogError(f"--motor-side: '{col}' cannot be motor-side (q_m, tau_m, q_ref)",
                           raw.path)
    if spec.gains_side not in ("joint", "motor"):
        raise LogError(f"gains side must be joint or motor, got '{spec.gains_side}'", raw.path)
    for name, value in (("--gear-ratio", spec.gear_ratio), ("--rate", spec.rate_hz),
                        ("--counts-per-turn", spec.counts_per_turn),
                        ("--link-counts-per-turn", spec.link_counts_per_turn),
                        ("--torque-constant", spec.torque_constant)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise LogError(f"{name} must be a positive number, got {value}", raw.path)
    if spec.rate_hz is not None and not MIN_RATE_HZ <= spec.rate_hz <= MAX_RATE_HZ:
        raise LogError(f"--rate {spec.rate_hz:g}: must lie in [{MIN_RATE_HZ:g}, "
                       f"{MAX_RATE_HZ:g}] Hz, the rates a log may have (docs/log-format.md)",
                       raw.path)


def _time(raw: RawTable, spec: ImportSpec, steps: list, checks: list) -> np.ndarray:
    """t [s] from the raw time column, starting at 0; sampling checked (uniform within 1 %,
    or within half a period of t0 + k / rate_hz). LogError naming the row."""
    name = spec.columns["t"]
    unit = spec.units.get("t", "s")
    t = (raw.column(name) - raw.column(name)[0]) * TIME_UNITS[unit]
    steps.append(f"t <- {name} [{unit}]" + (f" x {TIME_UNITS[unit]:g}" if unit != "s" else "")
                 + f", shifted to start at 0 (first value {raw.column(name)[0]:.10g} {unit})")
    dt = np.diff(t)
    bad = np.flatnonzero(~(dt > 0))
    if len(t) < 3:
        raise LogError(f"only {len(t)} rows, at least 3 are needed", raw.path)
    if bad.size:
        k = int(bad[0]) + 1
        raise LogError(f"time is not strictly increasing ({raw.column(name)[k - 1]:.10g} then "
                       f"{raw.column(name)[k]:.10g})", raw.path, int(raw.lines[k]), name)
    if spec.rate_hz is not None:
        rebuilt = np.arange(len(t)) / spec.rate_hz
        dev = np.abs(t - rebuilt) * spec.rate_hz
        k = int(np.argmax(dev))
        if dev[k] > 0.5:
            raise LogError(f"time is {dev[k]:.3g} periods away from sample {k} at {spec.rate_hz:g} "
                           "Hz (a dropped or repeated sample, or not that rate)", raw.path,
                           int(raw.lines[k]), name)
        checks.append(f"fixed rate {spec.rate_hz:g} Hz: the logged time agrees with k / rate "
                      f"within {dev[k]:.3g} of a period (at most 0.5)")
        steps.append(f"t rebuilt as k / {spec.rate_hz:g} Hz (--rate)")
        return rebuilt
    period, jitter, k = sampling_jitter(dt)
    if k is not None:
        raise LogError(f"non-uniform sampling: step {dt[k - 1] / TIME_UNITS[unit]:.6g} {unit} "
                       f"against the median {period / TIME_UNITS[unit]:.6g} {unit} (jitter "
                       f"{100 * jitter[k - 1]:.3g} %, over 1 %); resampling is refused: give "
                       "--rate HZ when the drive sampled at a fixed rate and the time stamps "
                       "are rounded", raw.path, int(raw.lines[k]), name)
    checks.append(f"uniform sampling: {len(t)} samples, period {1e3 * period:.6g} ms "
                  f"({1 / period:.6g} Hz), largest jitter {100 * float(jitter.max()):.3g} % "
                  "(at most 1 %)")
    return t


def _position(raw: RawTable, spec: ImportSpec, col: str, prismatic: bool) -> tuple[np.ndarray, str]:
    """A position column in rad (m), joint side; and the sentence saying how."""
    name = spec.columns[col]
    unit = spec.units.get(col, "m" if prismatic else "rad")
    length = unit in LENGTH_UNITS  # already on the linear side: the gear ratio leaves it
    motor = col in spec.motor_side and spec.gear_ratio is not None and not length
    cpr = spec.link_counts_per_turn if col == "q" else spec.counts_per_turn
    if length and not prismatic:
        raise LogError(f"--units {col}={unit}: a length on a revolute axis (give --prismatic "
                       "for a linear axis)", raw.path, column=name)
    if prismatic and not length and not motor:
        raise LogError(f"--units {col}={unit}: an angle on a prismatic axis needs the column "
                       "on the motor side with --gear-ratio (motor rad per m)", raw.path,
                       column=name)
    if unit == "counts":
        if cpr is None:
            flag = "--link-counts-per-turn" if col == "q" else "--counts-per-turn"
            raise LogError(f"--units {col}=counts needs {flag} (the encoder's counts per turn)",
                           raw.path, column=name)
        factor, how = 2 * math.pi / cpr, f"x 2 pi / {cpr:g} counts per turn"
    else:
        factor, how = POSITION_UNITS[unit], ("" if unit in ("rad", "m") else
                                             f"x {POSITION_UNITS[unit]:.10g}")
    if motor:
        factor /= spec.gear_ratio
        how += f" / N = {spec.gear_ratio:g} (motor side -> joint side)"
    return raw.column(name) * factor, f"{col} <- {name} [{unit}] {how}".rstrip()


def _torque(raw: RawTable, spec: ImportSpec, prismatic: bool) -> tuple[np.ndarray, str]:
    """tau_m in N m (N), joint side; and the sentence saying how. A force (N) is already on
    the linear side; a motor torque or current on a prismatic axis goes through the gear
    ratio (motor rad per m)."""
    name = spec.columns["tau_m"]
    unit = spec.units.get("tau_m", "N" if prismatic else "Nm")
    if unit == "N" and not prismatic:
        raise LogError("--units tau_m=N: a force on a revolute axis (give --prismatic for a "
                       "linear axis)", raw.path, column=name)
    geared = "tau_m" in spec.motor_side and spec.gear_ratio is not None and unit != "N"
    if prismatic and unit == "Nm" and not geared:
        raise LogError("--units tau_m=Nm: a motor torque on a prismatic axis needs --gear-ratio "
                       "(motor rad per m) to become the force", raw.path, column=name)
    factor, how = 1.0, ""
    if TORQUE_UNITS[unit] is None:
        if spec.torque_constant is None:
            raise LogError(f"--units tau_m={unit} needs --torque-constant (N m per {unit})",
                           raw.path, column=name)
        factor, how = spec.torque_constant, f"x k_t = {spec.torque_constant:g} per {unit}"
    if geared:
        factor *= spec.gear_ratio
        how += f" x N = {spec.gear_ratio:g} (motor side -> joint side)"
    return raw.column(name) * factor, f"tau_m <- {name} [{unit}] {how}".rstrip()


def _metadata(spec: ImportSpec, rate_hz: float, path: str, steps: list) -> dict[str, str]:
    """The log's metadata: the rate, N, the given keys (numbers and booleans checked as the
    reader checks them), motor-side gains referred to the joint side."""
    # 7 digits: what time stamps rounded to 1e-10 s (or 10 digits of ms) over seconds tell
    meta = {"sample_rate_hz": f"{rate_hz:.7g}"}
    if spec.gear_ratio is not None:
        meta["gear_ratio"] = f"{spec.gear_ratio:.10g}"
    for key, value in spec.meta.items():
        if key in NUMERIC_META:
            number = meta_number(key, value, path, None)
            if spec.gains_side == "motor" and key in GAIN_POWERS:
                if spec.gear_ratio is None:
                    raise LogError(f"motor-side gains need --gear-ratio ({key})", path)
                number *= spec.gear_ratio ** GAIN_POWERS[key]
                steps.append(f"{key}: motor side {value} x N^{GAIN_POWERS[key]} = {number:.10g}")
            low, high = META_RANGES.get(key, (-math.inf, math.inf))
            if not low <= number <= high:
                why = ("gravity is an acceleration's magnitude [m/s^2]" if key == "gravity"
                       else "a gain is >= 0")
                raise LogError(f"metadata '{key}' = {number:g} is outside [{low:g}, {high:g}] "
                               f"({why})", path)
            value = f"{number:.10g}"
        elif key in NONNEGATIVE_META:
            meta_number(key, value, path, None)
        elif key in BOOLEAN_META:
            value = "true" if meta_boolean(key, value, path, None) else "false"
        meta[key] = value
    if spec.counts_per_turn is not None and "motor_encoder_resolution_rad" not in meta:
        res = 2 * math.pi / spec.counts_per_turn / (spec.gear_ratio or 1.0)
        meta["motor_encoder_resolution_rad"] = f"{res:.10g}"
    if spec.link_counts_per_turn is not None and "link_encoder_resolution_rad" not in meta:
        meta["link_encoder_resolution_rad"] = f"{2 * math.pi / spec.link_counts_per_turn:.10g}"
    meta["source"] = f"jointbench import of {os.path.basename(path)}"
    return meta


def convert(raw: RawTable, spec: ImportSpec) -> ImportResult:
    """The jointbench log of `raw` under `spec`, with what was done and checked.
    Raises LogError (file, line, column) for what cannot be converted."""
    _check_spec(raw, spec)
    steps: list[str] = [f"read {raw.path}: {len(raw.data)} rows, columns "
                        f"{', '.join(raw.header)} (delimiter {raw.delimiter!r})"]
    checks: list[str] = []
    prismatic = spec.meta.get("axis", "").strip().lower().startswith("prismatic")
    t = _time(raw, spec, steps, checks)
    cols: dict[str, np.ndarray] = {}
    for col in POSITIONS:
        if col in spec.columns:
            cols[col], how = _position(raw, spec, col, prismatic)
            steps.append(how)
    cols["tau_m"], how = _torque(raw, spec, prismatic)
    steps.append(how)
    _check_range(raw, spec, cols)
    rate = (len(t) - 1) / float(t[-1] - t[0])  # the mean period: uniform checked above
    meta = _metadata(spec, spec.rate_hz or rate, raw.path, steps)
    log = Log(t=t, q_m=cols["q_m"], tau_m=cols["tau_m"], q=cols.get("q"),
              q_ref=cols.get("q_ref"), meta=meta, path=raw.path)
    check_writable(log)
    validate(log, row_lines=raw.lines)
    checks.append(f"log checks of docs/log-format.md passed (t increasing and uniform, "
                  f"sample_rate_hz {meta['sample_rate_hz']} agrees with t)")
    checks += _model_checks(log)
    constant = [f"{raw.path}: column '{spec.columns[c]}' ({c}) is constant"
                for c in ("q_m", "q", "tau_m") if c in spec.columns and np.ptp(cols[c]) == 0]
    return ImportResult(log, tuple(steps), tuple(checks),
                        tuple(unit_warnings(log) + _rate_warnings(raw, spec, log) + constant))


def _check_range(raw: RawTable, spec: ImportSpec, cols: dict[str, np.ndarray]) -> None:
    """LogError, naming the raw column and the factor applied, for a converted value beyond
    what the log reader accepts (MAX_ABS_VALUE): a gear ratio, a counts per turn or a torque
    constant that is a typo, or a corrupted cell."""
    for col, x in cols.items():
        big = np.flatnonzero(~(np.abs(x) <= MAX_ABS_VALUE))
        if big.size:
            k = int(big[0])
            name = spec.columns[col]
            raw_value = float(raw.column(name)[k])
            factor = float(x[k] / raw_value) if raw_value else float("nan")
            raise LogError(f"{col} = {x[k]:.6g} after conversion (raw {raw_value:.6g} x "
                           f"{factor:.6g}): over {MAX_ABS_VALUE:g} in magnitude, which the log "
                           "format refuses as a corrupted cell; check --gear-ratio, --units, "
                           "--counts-per-turn and --torque-constant", raw.path,
                           int(raw.lines[k]), name)


def _rate_warnings(raw: RawTable, spec: ImportSpec, log: Log) -> list[str]:
    """A warning when the log's rate is above what a drive logs (MAX_DRIVE_RATE_HZ), naming
    the time unit that would give a drive's rate."""
    rate = log.sample_rate_hz
    if not rate > MAX_DRIVE_RATE_HZ:
        return []
    unit = spec.units.get("t", "s")
    slower = {"us": "ms", "ms": "s"}.get(unit)
    hint = (f"if the time column '{spec.columns['t']}' is in {slower}, not {unit}, give "
            f"--units t={slower} (a rate of {rate * TIME_UNITS[unit] / TIME_UNITS[slower]:.6g}"
            " Hz)") if slower else "check the time column's unit (--units t=...) and --rate"
    return [f"{raw.path}: sample rate {rate:.6g} Hz, above what a drive logs (at most "
            f"{MAX_DRIVE_RATE_HZ:g} Hz): the time unit is likely wrong; {hint}"]


def _model_checks(log: Log) -> list[str]:
    """What the converted log allows: the models and the replay."""
    out = ["link position q present: the joint-motor model (eq. 13) applies" if log.q is not None
           else "no link position q: motor-only and rigid models only"]
    gains = [k for k in ("kp", "kv", "ki", "tau_max") if k not in log.meta]
    if log.q_ref is None or gains:
        missing = ", ".join((["q_ref column"] if log.q_ref is None else []) + gains)
        out.append(f"not replayable (inverse analyses only): missing {missing}")
    else:
        out.append("replayable: q_ref and the controller gains kp, kv, ki, tau_max are given")
    return out
