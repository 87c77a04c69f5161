"""The Python API's argument checks (bench.api): every public function calls `check(name,
locals())` first, so that a misuse raises TypeError or ValueError naming the argument and
what was expected, before any numerics, and for the same reasons the command line refuses
the same input (bench.cli: exit status 2).

- numbers: finite, of their sign and range (`seed` in [0, 2**32) as `--seed`,
  `sample_rate_hz` within the rates a log may have as `--rate`, `duration` at least the
  chirp's fades as `--duration`, and within the memory limit as `check_memory`);
- a `Log` given as an object: numpy arrays of real numbers, one length, finite, at least 3
  samples, its sampling what the log reader accepts (identification.log.read.validate);
- output paths: checked by the one output layer (bench.output_files.check_file) before any work;
- `id_models`: a sequence of model names (a single string is refused: it would be read as
  letters).
"""

from __future__ import annotations

import inspect
import math
import numbers
import os
from typing import Any

import numpy as np

from jointbench.identification.log.schema import Log, LogError

SEED_LIMIT = 2**32
MAX_SUBSTEPS = 1000      # as `simulate --substeps`
LOG_COLUMNS = ("t", "q_m", "tau_m", "q", "q_ref")
IDENTIFY_MODELS = ("joint-motor", "motor-only", "motor-only-printed", "rigid", "auto")


def _type(value: Any) -> str:
    return type(value).__name__


def number(name: str, value: Any, *, low: float | None = None, low_open: bool = False,
           high: float | None = None) -> float:
    """`value` as a float: a real number (not a bool), finite, within [low, high] (`low_open`:
    above low). TypeError or ValueError naming `name`."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name}: expected a number, got {_type(value)} {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"{name}: expected a finite number, got {value!r}")
    below = low is not None and (x <= low if low_open else x < low)
    if below or (high is not None and x > high):
        if low is not None and high is not None:
            span = f"must lie in {'(' if low_open else '['}{low:g}, {high:g}]"
        elif low is not None:
            span = f"must be above {low:g}" if low_open else f"must be at least {low:g}"
        else:
            span = f"must be at most {high:g}"
        raise ValueError(f"{name}: {span}, got {value!r}")
    return x


def integer(name: str, value: Any, low: int, high: int | None = None,
            high_shown: str | None = None) -> int:
    """`value` as an int (numpy integers too, not a bool nor a float), in [low, high]
    (`high_shown`: how the message writes the upper bound, e.g. "2**32)" for an open one)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name}: expected an integer, got {_type(value)} {value!r}")
    x = int(value)
    if x < low or (high is not None and x > high):
        span = f"lie in [{low}, {high_shown or f'{high}]'}" if high is not None else \
            f"be >= {low}"
        raise ValueError(f"{name}: must {span}, got {x}")
    return x


def text(name: str, value: Any, optional: bool = False) -> None:
    """A str (or None when `optional`)."""
    if value is None and optional:
        return
    if not isinstance(value, str):
        raise TypeError(f"{name}: expected a str, got {_type(value)} {value!r}")


def path_like(name: str, value: Any) -> None:
    """A str or os.PathLike, not empty."""
    if not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name}: expected a file name (str or os.PathLike), got "
                        f"{_type(value)} {value!r}")
    if not str(os.fspath(value)).strip():
        raise ValueError(f"{name}: an empty file name")


def log_object(name: str, log: Any) -> None:
    """A Log whose columns are numpy arrays of real numbers of one length (finite, at least 3
    samples, sampling as the reader accepts), or a file name."""
    if not isinstance(log, Log):
        path_like(name, log)
        return
    from jointbench.identification.log.read import validate

    for col in LOG_COLUMNS + tuple(f"extra['{k}']" for k in log.extra):
        value = getattr(log, col) if col in LOG_COLUMNS else log.extra[col[7:-2]]
        if value is None and col in ("q", "q_ref"):
            continue
        if not isinstance(value, np.ndarray):
            raise TypeError(f"{name}.{col}: expected a 1-D numpy array of floats, got "
                            f"{_type(value)}" + (" (np.asarray(...) makes one)"
                                                 if isinstance(value, (list, tuple)) else ""))
        if value.dtype.kind not in "fiu":
            raise TypeError(f"{name}.{col}: expected an array of real numbers, got dtype "
                            f"{value.dtype}")
        if value.ndim != 1 or len(value) != len(log.t):
            raise ValueError(f"{name}.{col}: shape {value.shape}, and {name}.t has "
                             f"{len(log.t)} samples: the columns must be 1-D of one length")
        bad = np.flatnonzero(~np.isfinite(value))
        if bad.size:
            raise ValueError(f"{name}.{col}: {value[bad[0]]} at sample {int(bad[0])}: a log "
                             "holds finite numbers only")
    if len(log.t) < 3:
        raise ValueError(f"{name}: {len(log.t)} samples, at least 3 are needed")
    if not isinstance(log.meta, dict):
        raise TypeError(f"{name}.meta: expected a dict of str, got {_type(log.meta)}")
    try:
        validate(log)
    except LogError as err:
        raise ValueError(f"{name}: {err.message}"
                         + (f" (column '{err.column}')" if err.column else "")) from None


def output_path(name: str, value: Any) -> None:
    """None, or a file name the output layer accepts (bench.output_files.check_file)."""
    if value is None:
        return
    path_like(name, value)
    from jointbench.bench.output_files import check_file

    check_file(value, name)


def memory(name: str, samples: float) -> None:
    """ValueError naming `name` when `samples` log samples need more than the memory limit
    (bench.memory: the estimate and the limit of the command line)."""
    from jointbench.bench.memory import MEMORY_ENV, memory_limit_mb, samples_mb

    need = samples_mb(samples)
    limit = memory_limit_mb()
    if not need <= limit:
        raise ValueError(f"{name}: {samples:.3g} samples need about {need:,.0f} MB of memory, "
                         f"over the {limit:,.0f} MB limit (set {MEMORY_ENV} to raise it)")


def _simulate(a: dict) -> None:
    from jointbench.bench.effects import HiddenEffect
    from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ, run_experiment
    from jointbench.bench.sim.reference import Chirp
    from jointbench.identification.log.read import MAX_RATE_HZ, MIN_RATE_HZ

    path_like("model", a["model"])
    if a["joint"] is not None and not isinstance(a["joint"], (str, int)):
        raise TypeError(f"joint: expected an axis name or an index from 1, got "
                        f"{_type(a['joint'])} {a['joint']!r}")
    taper = Chirp.__dataclass_fields__["taper"].default
    duration = number("duration", a["duration"], low=2 * taper)
    integer("seed", a["seed"], 0, SEED_LIMIT - 1, "2**32)")
    options = a.get("options", {})
    rate = options.get("sample_rate_hz", SAMPLE_RATE_HZ)
    rate = number("sample_rate_hz", rate, low=MIN_RATE_HZ, high=MAX_RATE_HZ)
    for key in ("amplitude", "tau_max"):
        if options.get(key) is not None:
            number(key, options[key], low=0.0, low_open=True)
    known = set(inspect.signature(run_experiment).parameters) - set(a)
    unknown = sorted(set(options) - known)
    if unknown:
        raise TypeError(f"simulate: unknown option(s) {', '.join(unknown)} (known: "
                        f"{', '.join(sorted(known))})")
    effect = a["effect"]
    if effect is not None and not isinstance(effect, (str, HiddenEffect)) and not (
            isinstance(effect, tuple) and all(isinstance(e, HiddenEffect) for e in effect)):
        raise TypeError(f"effect: expected a text such as 'backlash=0.002', a HiddenEffect or "
                        f"a tuple of them, got {_type(effect)} {effect!r}")
    config = options.get("config")
    if config is not None:
        if not isinstance(config, dict):
            raise TypeError(f"config: expected a dict of axis name -> angle [rad], got "
                            f"{_type(config)}")
        for axis, angle in config.items():
            number(f"config[{axis!r}]", angle)
    if "substeps" in options:
        integer("substeps", options["substeps"], 1, MAX_SUBSTEPS)
    memory("duration", duration * rate)


def _identify(a: dict) -> None:
    log_object("log", a["log"])
    text("model", a["model"])
    if a["model"] not in IDENTIFY_MODELS:
        raise ValueError(f"model: {a['model']!r} is not an identification model "
                         f"({', '.join(IDENTIFY_MODELS)})")
    from jointbench.identification.filtering import FilterSettings

    if a["settings"] is not None and not isinstance(a["settings"], FilterSettings):
        raise TypeError(f"settings: expected a FilterSettings or None, got "
                        f"{_type(a['settings'])}")
    if a.get("f1_hz") is not None:
        number("f1_hz", a["f1_hz"], low=0.0, low_open=True)


def _diagnose(a: dict) -> None:
    log_object("log", a["log"])
    if not isinstance(a["forward"], bool):
        raise TypeError(f"forward: expected True or False, got {_type(a['forward'])}")
    if a["progress"] is not None and not callable(a["progress"]):
        raise TypeError(f"progress: expected a callable or None, got {_type(a['progress'])}")


def _campaign(a: dict) -> None:
    path_like("model", a["model"])
    integer("runs", a["runs"], 1)
    integer("seed", a["seed"], 0, SEED_LIMIT - 1, "2**32)")
    number("duration", a["duration"], low=0.0, low_open=True)
    number("method_timeout", a["method_timeout"], low=0.0, low_open=True, high=1e6)
    ids = a["id_models"]
    if isinstance(ids, str):
        raise TypeError(f"id_models: expected a sequence of model names, e.g. ({ids!r},), got "
                        f"the string {ids!r} (it would be read letter by letter)")
    if not all(isinstance(m, str) for m in ids):
        raise TypeError(f"id_models: expected model names (str), got {list(ids)!r}")
    if a["workers"] is not None:
        integer("workers", a["workers"], 1)
    if a["sweep"] is not None:
        sweep = a["sweep"]
        if not (isinstance(sweep, (tuple, list)) and len(sweep) == 2
                and isinstance(sweep[0], str)):
            raise TypeError("sweep: expected (NAME, values), e.g. ('noise', [0.5, 1, 2])")
        for k, v in enumerate(sweep[1]):
            number(f"sweep values[{k}]", v)
    if a["out"] is not None:
        path_like("out", a["out"])


CHECKS = {"simulate": _simulate, "identify": _identify, "diagnose": _diagnose,
          "campaign": _campaign}


def check(function: str, arguments: dict) -> None:
    """Check the arguments of API function `function` (its `locals()` on entry). TypeError
    or ValueError naming the argument and what was expected."""
    CHECKS[function](arguments)
