"""Calling a plug-in method under a deadline (bench.campaign.methods).

A method found by name runs in a *host*: a child process (spawn start method, daemon) of the
process that runs the experiments, kept for the next calls. The log goes down a pipe, the
answer comes back with the call's own wall time. When no answer comes within the deadline the
host is killed (SIGKILL: a loop in C code stops too) and the next call starts a fresh one; a
method that crashes its process (os._exit, a segfault) takes only its host with it. The
campaign's engines never see any of this: a hung method costs its run at most the deadline,
and a worker of `LocalExecutor` owns its hosts (one per thread), which die with it (daemon
children; a host whose parent was killed reads end-of-file and exits).

A callable without a name (a lambda in a notebook) and any method in a daemonic process (a
Dask worker, which may not start children) run in a thread of this process instead: the
deadline is kept, but a hung call cannot be stopped and runs on in the background.
"""

from __future__ import annotations

import contextlib
import math
import multiprocessing
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable

from jointbench.bench.campaign.methods import resolve

_CONTEXT = multiprocessing.get_context("spawn")


@dataclass(frozen=True)
class Answer:
    """One call: `value` when it returned, else `error` (one line); `wall_s` its own time."""

    value: Any = None
    error: str | None = None
    wall_s: float = math.nan


def _describe(err: BaseException) -> str:
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _timed(fn: Callable, arg) -> Answer:
    t0 = time.perf_counter()
    try:
        value = fn(arg)
    except BaseException as err:  # noqa: BLE001 - SystemExit too: the method's failure
        return Answer(error=_describe(err), wall_s=time.perf_counter() - t0)
    return Answer(value=value, wall_s=time.perf_counter() - t0)


def _serve(conn) -> None:
    """The host's loop, until the pipe closes: ("resolve", ref) -> None or an error text;
    ("call", ref, log) -> Answer."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # Ctrl-C is the campaign's to handle
    os.dup2(2, 1)                                  # a method's prints never reach stdout
    sys.stdout = sys.stderr
    import jointbench.bench.api  # noqa: F401 - the public API, loaded before any deadline
    conn.send(None)                                # ready
    while True:
        try:
            what, ref, *arg = conn.recv()
        except (EOFError, OSError):
            return
        if what == "resolve":
            try:
                resolve(ref)
                conn.send(None)
            except Exception as err:  # noqa: BLE001 - said to the caller
                conn.send(_describe(err))
            continue
        answer = _timed(resolve(ref), arg[0])
        try:
            conn.send(answer)
        except Exception as err:  # noqa: BLE001 - an answer that cannot be pickled
            conn.send(Answer(error=f"returned an object that cannot be sent back: "
                                   f"{_describe(err)}", wall_s=answer.wall_s))


class Host:
    """One child process serving calls (see the module docstring). Starting it and importing
    a method's module are waited for up to `STARTUP_S`, outside any call's deadline."""

    STARTUP_S = 300.0

    def __init__(self):
        self.conn, child = _CONTEXT.Pipe()
        self.process = _CONTEXT.Process(target=_serve, args=(child,), daemon=True,
                                        name="jointbench-method-host")
        self.process.start()
        child.close()
        self.ready: set[str] = set()
        self.failed = self._wait(self.STARTUP_S, "start")

    def _wait(self, timeout_s: float, what: str) -> str | None:
        """None when the host answered None within `timeout_s`, else why not."""
        try:
            if self.conn.poll(timeout_s):
                return self.conn.recv()
        except (EOFError, OSError):
            self.close()
            return f"its process died (exit code {self.process.exitcode}) during {what}"
        self.close()
        return f"no answer within {timeout_s:g} s during {what}"

    def call(self, ref: str, arg, timeout_s: float) -> Answer:
        """ref(arg) in the host; the host is closed (and must be replaced) unless it answered."""
        if self.failed is None and ref not in self.ready:
            try:
                self.conn.send(("resolve", ref))
            except OSError as err:
                self.failed = _describe(err)
            else:
                self.failed = self._wait(self.STARTUP_S, f"the import of {ref}")
            if self.failed is None:
                self.ready.add(ref)
        if self.failed is not None:
            error, self.failed = self.failed, None
            if self.alive:  # the method's module does not import here: keep the host
                return Answer(error=error)
            return Answer(error=f"method host: {error}")
        try:
            self.conn.send(("call", ref, arg))
            if self.conn.poll(timeout_s):
                return self.conn.recv()
        except (EOFError, OSError):
            self.process.join(5)
            self.close()
            return Answer(error=f"its process died (exit code {self.process.exitcode})")
        self.close()
        return Answer(error=f"timeout: no answer within {timeout_s:g} s (call stopped)",
                      wall_s=timeout_s)

    @property
    def alive(self) -> bool:
        return not self.conn.closed and self.process.is_alive()

    def close(self) -> None:
        if self.process.is_alive():
            self.process.kill()
        self.process.join(5)
        self.conn.close()


_LOCAL = threading.local()
_HOSTS: list[Host] = []
_LOCK = threading.Lock()


def _host() -> Host:
    host = getattr(_LOCAL, "host", None)
    if host is None or not host.alive:
        host = _LOCAL.host = Host()
        with _LOCK:
            _HOSTS.append(host)
    return host


def close_hosts() -> None:
    """Stop every host this process started (the end of a campaign)."""
    with _LOCK:
        hosts, _HOSTS[:] = list(_HOSTS), []
    for host in hosts:
        host.close()
    _LOCAL.host = None


def _in_thread(fn: Callable, arg, timeout_s: float) -> Answer:
    box: list[Answer] = []
    worker = threading.Thread(target=lambda: box.append(_timed(fn, arg)), daemon=True,
                              name="jointbench-method")
    with contextlib.redirect_stdout(sys.stderr):
        worker.start()
        worker.join(timeout_s)
    if box:
        return box[0]
    return Answer(error=f"timeout: no answer within {timeout_s:g} s (the call could not be "
                        "stopped: it runs on in a background thread)", wall_s=timeout_s)


def call(ref: str | None, fn: Callable | None, arg, timeout_s: float) -> Answer:
    """The method named `ref` (in a host process) or the callable `fn` (in a thread) on `arg`,
    with a deadline of `timeout_s` seconds."""
    if ref is None or multiprocessing.current_process().daemon:
        return _in_thread(fn if fn is not None else resolve(ref), arg, timeout_s)
    return _host().call(ref, arg, timeout_s)
