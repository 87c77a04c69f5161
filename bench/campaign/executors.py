"""Where a campaign's runs execute: one small interface, three engines.

An `Executor` applies a picklable top-level function to items and yields `Done(item, value,
error)` in completion order. `error` is set when the engine itself lost the task (a worker
process died, a Dask worker vanished): the function's own exceptions are the caller's business
(a campaign catches them inside the task and records them in its row). Any other engine
(Ray, MPI, a batch queue) plugs in by implementing `map_unordered` and `close`.

- `SerialExecutor`: in this process, in order (tests, `--workers 1`, debugging).
- `LocalExecutor`: `concurrent.futures.ProcessPoolExecutor` on the local cores, spawn start
  method (every worker imports the project afresh and builds its own MuJoCo models).
- `DaskExecutor`: an existing Dask distributed scheduler (`tcp://HOST:PORT`); the workers
  need this project installed.
"""

from __future__ import annotations

import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections import deque
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any, Callable, Generic, Iterable, Iterator, Protocol, TypeVar

T = TypeVar("T")
R = TypeVar("R")


@dataclass(frozen=True)
class Done(Generic[T, R]):
    """One finished task: `value` when it ran, `error` (a sentence) when the engine lost it."""

    item: T
    value: R | None = None
    error: str | None = None


class Executor(Protocol):
    """The engine interface a campaign needs."""

    workers: int
    description: str

    def map_unordered(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[Done[T, R]]:
        """fn(item) for every item, yielded as the tasks finish (any order)."""
        ...

    def close(self) -> None:
        ...


class SerialExecutor:
    """Runs every task in this process, in order."""

    workers = 1
    description = "serial (this process)"

    def map_unordered(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[Done[T, R]]:
        for item in items:
            yield Done(item, fn(item))

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


PR_SET_PDEATHSIG = 1  # linux/prctl.h


def _watch_parent(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(1.0)
    os._exit(1)


def die_with_parent(parent: int) -> None:
    """Worker initializer: the worker ends when the campaign process `parent` dies, SIGKILL
    included (a pool's own shutdown never runs then). On Linux the kernel sends SIGKILL
    (prctl PR_SET_PDEATHSIG); elsewhere, and as a back-up, a daemon thread polls the parent
    id every second. A parent already gone exits at once."""
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL),
                                                    0, 0, 0)
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True,
                     name="jointbench-parent-watch").start()


class LocalExecutor:
    """A process pool on the local cores (default: all of them, os.cpu_count()).

    At most `2 workers` tasks are in flight, so a campaign of a million runs holds a million
    items, not a million futures. Workers die with this process (`die_with_parent`). When a
    worker process dies (BrokenProcessPool) every task in flight fails with it and none can
    be blamed: the pool is rebuilt and those tasks run again one at a time; one that kills
    its worker alone comes back with `error` set.
    """

    def __init__(self, workers: int | None = None, start_method: str = "spawn"):
        self.workers = int(workers or os.cpu_count() or 1)
        if self.workers < 1:
            raise ValueError(f"workers must be >= 1, got {workers}")
        self._context = multiprocessing.get_context(start_method)
        self._pool: ProcessPoolExecutor | None = None
        self.description = f"{self.workers} local processes ({start_method})"

    def _submit(self, fn: Callable[[T], R], item: T) -> Future:
        if self._pool is None:
            self._pool = ProcessPoolExecutor(self.workers, mp_context=self._context,
                                             initializer=die_with_parent,
                                             initargs=(os.getpid(),))
        return self._pool.submit(fn, item)

    def _drop_pool(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None

    def map_unordered(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[Done[T, R]]:
        source = iter(items)
        suspects: deque[T] = deque()
        running: dict[Future, tuple[T, bool]] = {}  # future -> (item, running alone)
        exhausted = False
        while True:
            if suspects:
                if not running:
                    item = suspects.popleft()
                    running[self._submit(fn, item)] = (item, True)
            else:
                while not exhausted and len(running) < 2 * self.workers:
                    try:
                        item = next(source)
                    except StopIteration:
                        exhausted = True
                        break
                    running[self._submit(fn, item)] = (item, False)
            if not running:
                return
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            broken = False
            for fut in done:
                item, alone = running.pop(fut)
                try:
                    value = fut.result()
                except BrokenProcessPool as err:
                    broken = True
                    if alone:
                        yield Done(item, error=f"its worker process died ({err})")
                    else:
                        suspects.append(item)
                    continue
                yield Done(item, value)
            if broken:
                suspects.extend(item for item, _ in running.values())
                running.clear()
                self._drop_pool()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class DaskExecutor:
    """Tasks on an existing Dask distributed cluster (`distributed.Client(address)`).

    At most `2 x (worker threads)` tasks are in flight. A task the cluster loses (worker died,
    KilledWorker after Dask's own retries) comes back with `error` set.
    """

    def __init__(self, address: str, timeout_s: float = 10.0):
        try:
            from distributed import Client
        except ImportError as err:  # the `cluster` extra
            raise ValueError("--scheduler needs Dask distributed: pip install "
                             "'jointbench[cluster]'") from err
        try:
            self._client = Client(address, timeout=timeout_s, set_as_default=False)
        except (OSError, TimeoutError) as err:
            raise ValueError(f"cannot reach the Dask scheduler at {address}: {err}") from None
        threads = sum(self._client.nthreads().values())
        self.workers = max(1, threads)
        self.description = f"Dask scheduler {address} ({threads} worker threads)"

    def map_unordered(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[Done[T, R]]:
        from distributed import as_completed

        source = iter(items)
        owner: dict[Any, T] = {}

        def submit_next():
            try:
                item = next(source)
            except StopIteration:
                return None
            fut = self._client.submit(fn, item, pure=False)
            owner[fut.key] = item
            return fut

        first = [f for f in (submit_next() for _ in range(2 * self.workers)) if f is not None]
        if not first:
            return
        pool = as_completed(first, loop=self._client.loop)
        for fut in pool:
            item = owner.pop(fut.key)
            try:
                value = fut.result()
            except Exception as err:  # noqa: BLE001 - the cluster lost the task
                yield Done(item, error=f"Dask lost this run: {type(err).__name__}: {err}")
            else:
                yield Done(item, value)
            fut.release()
            nxt = submit_next()
            if nxt is not None:
                pool.add(nxt)

    def close(self) -> None:
        self._client.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def make_executor(workers: int | None = None, scheduler: str | None = None) -> Executor:
    """`--scheduler ADDRESS` -> DaskExecutor; `--workers 1` -> SerialExecutor; else a
    LocalExecutor on `workers` cores (default all)."""
    if scheduler:
        return DaskExecutor(scheduler)
    if workers is not None and workers < 1:
        raise ValueError(f"--workers must be >= 1, got {workers}")
    if workers == 1:
        return SerialExecutor()
    return LocalExecutor(workers)
