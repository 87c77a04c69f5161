"""The simulated plant's metadata (docs/log-format.md "The simulated plant"): how a log's
MuJoCo plant was discretised, which the bench's replays read to simulate it as it was. The
identification reads none of it; a measured log has none.

The bench checks these keys where it loads a log (`check`), as the reader checks its own:
an invalid value is refused with the file and line.
"""

from __future__ import annotations

from jointbench.identification.log.schema import Log, meta_number

PLANT_STEPS_KEY = "substeps"            # physics steps per sample, a positive integer
PLANT_INTEGRATOR_KEY = "integrator"     # MuJoCo's integrator name (mjINT_...)
PLANT_TIMECONST_KEY = "friction_timeconst_s"   # the rotor's solreffriction [s]


def _number(log: Log, key: str, units: tuple[str, ...], positive: bool) -> float | None:
    if key not in log.meta:
        return None
    return meta_number(key, log.meta[key], log.path, log.meta_lines.get(key), units=units,
                       positive=positive)


def plant_steps(log: Log) -> float | None:
    """The log's physics steps per sample, or None when it has none (LogError naming the
    file and line when the value is not a positive number)."""
    return _number(log, PLANT_STEPS_KEY, (), True)


def plant_timeconst(log: Log) -> float | None:
    """The simulated plant's friction time constant [s] (MuJoCo's solreffriction); None when
    the log has none or gives MuJoCo's direct form (<= 0). LogError naming the file and line
    when the value is not a number."""
    value = _number(log, PLANT_TIMECONST_KEY, ("s",), False)
    return value if value is not None and value > 0 else None


def check(log: Log) -> Log:
    """`log`, once its plant keys are valid numbers (LogError naming the file and line)."""
    plant_steps(log)
    plant_timeconst(log)
    return log
