"""The memory a command needs, estimated before it starts, and the limit it must stay under.

Every command holds a handful of arrays per log sample: the simulated signals and the log's
text (`simulate`: about 360 bytes a sample), the filtered signals, their
derivatives and the regressor (`identify`: about 480 bytes a sample; `diagnose` without the
forward view about 180). `BYTES_PER_SAMPLE` rounds the largest up to 1 KiB. A command that
would need more than the limit is refused with the number (exit status 2) instead of
swapping the machine to a halt or dying with MemoryError. The limit is the environment
variable JOINTBENCH_MAX_MEMORY_MB when set, else half of the physical memory.

Standard library only.
"""

from __future__ import annotations

from jointbench.bench.cli.common import UsageError
from jointbench.bench.memory import BASE_MB, BYTES_PER_SAMPLE, MEMORY_ENV
from jointbench.bench.memory import memory_limit_mb as _limit


def memory_limit_mb(environ: dict[str, str] | None = None) -> float:
    """JOINTBENCH_MAX_MEMORY_MB, else half of the physical memory (bench.memory). UsageError
    when the variable is not a positive number."""
    try:
        return _limit(environ)
    except ValueError as err:
        raise UsageError(str(err)) from None


def check_memory(samples: float, what: str, copies: int = 1) -> float:
    """UsageError when `copies` (workers) of a command holding `samples` log samples would need
    more than the limit; returns the estimate in MB. `what` says where the samples come from
    (e.g. "--duration 1e+06 s at 1000 Hz")."""
    need = copies * (BASE_MB + samples * BYTES_PER_SAMPLE / 2**20)
    limit = memory_limit_mb()
    if not need <= limit:
        per = f" ({copies} workers)" if copies > 1 else ""
        raise UsageError(f"{what}: {samples:.3g} samples need about {need:,.0f} MB of memory"
                         f"{per}, over the {limit:,.0f} MB limit (set {MEMORY_ENV} to raise it)")
    return need


def check_survey_memory(axes: int, duration: float, rate_hz: float, workers: int | None) -> None:
    """Before any run: this process holds every axis's log and, with workers (as many as
    run_survey starts: at most one per axis), each worker also holds one axis's experiment
    and identification beside its own interpreter (bench.cli.resources' figures per sample
    and per process). UsageError over the limit, in MB."""
    import os

    samples = duration * rate_hz
    what = f"--duration {duration:g} s on {axes} axes"
    used = max(1, min(workers or os.cpu_count() or 1, axes))
    if used == 1:
        check_memory(axes * samples, what)
        return
    mb = samples * BYTES_PER_SAMPLE / 2**20            # one axis's samples
    need = BASE_MB + axes * mb + used * (BASE_MB + mb)
    limit = memory_limit_mb()
    if not need <= limit:
        raise UsageError(f"{what} with {used} workers: about {need:,.0f} MB of memory "
                         f"({BASE_MB + axes * mb:,.0f} MB here and {BASE_MB + mb:,.0f} MB per "
                         f"worker), over the {limit:,.0f} MB limit (set {MEMORY_ENV} to raise "
                         "it, or give fewer --workers)")
