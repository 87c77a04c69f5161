"""Progress of a long command on stderr: one tqdm bar, drawn only on a terminal and never
with --quiet, so that a pipe, a log file or a test's captured stderr gets no progress text.
The library reports progress through callbacks; these bars are what the commands pass."""

from __future__ import annotations

import sys
from typing import Callable

from tqdm import tqdm


def bar(label: str, total: int, unit: str, *, initial: int = 0, quiet: bool = False) -> tqdm:
    """A bar of `total` steps on stderr (`initial` of them done before); a no-op bar with
    `quiet` or when stderr is not a terminal. Close it (or use it as a context manager)."""
    return tqdm(total=total, initial=initial, desc=label, unit=unit, file=sys.stderr,
                disable=quiet or not sys.stderr.isatty(), dynamic_ncols=True)


def runs(b: tqdm) -> Callable[[bool], None]:
    """The `progress(ok)` callback of a campaign or a filter search: one run done, the
    failed ones counted beside the bar."""
    failed = [0]

    def done(ok: bool) -> None:
        if not ok:
            failed[0] += 1
            b.set_postfix(failed=failed[0], refresh=False)
        b.update(1)
    return done


def fraction(b: tqdm) -> Callable[[float], None]:
    """The `progress(fraction)` callback of a virtual experiment on a bar of total 100."""
    def at(frac: float) -> None:
        b.update(max(0, round(100 * frac) - b.n))
    return at


def count(b: tqdm) -> Callable[[int, int], None]:
    """The `progress(done, total)` callback of a replica loop."""
    def at(done: int, total: int) -> None:
        b.update(max(0, done - b.n))
    return at
