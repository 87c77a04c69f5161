"""Calling a plug-in method under a deadline, contained (bench.campaign.methods).

A method found by name runs in a *host*: a child process (spawn start method, daemon) of the
process that runs the experiments, kept for the next calls. The host is contained:

- it leads its own session and process group (`os.setsid`), so the whole group (the host,
  any process the method forks, and the host's watchdog) is killed at once (`os.killpg`,
  SIGKILL: a loop in C code stops too) at a deadline and when the campaign ends;
- a watchdog process in that group blocks on a pipe whose only write end the campaign
  process holds: when the campaign dies, SIGKILL included, the pipe reads end-of-file and
  the watchdog kills the group, however busy the method is;
- importing the method's module, calling it, checking its answer
  (methods.check_estimates) and encoding it happen in the host, each under the deadline;
  the answer comes back as JSON of plain numbers, so nothing the method returns is ever
  unpickled in the campaign process;
- its address space is capped (RLIMIT_AS) at its own footprint plus the memory limit
  (JOINTBENCH_MAX_MEMORY_MB, bench.cli.resources): an allocation past it is that call's
  MemoryError, said in MB;
- its standard output is its standard error: a `print` cannot reach `campaign --json`;
- a method that ends its process (os._exit, a segfault) takes only its host with it: that
  run's failure, with the exit code.

A hung method costs its run at most the deadline; the next call starts a fresh host. A
worker of `LocalExecutor` owns its hosts (one per thread), which die with it.

A callable without a name (a lambda in a notebook) and any method in a daemonic process (a
Dask worker, which may not start children) run in a thread of this process instead: the
deadline is kept, but a hung call cannot be stopped and runs on in the background.
"""

from __future__ import annotations

import contextlib
import json
import math
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

from jointbench.bench.campaign.methods import BadResult, check_estimates, resolve
from jointbench.bench.campaign.settings import CampaignError

_CONTEXT = multiprocessing.get_context("spawn")
# The longest deadline a call may have: poll() and select() take at most about 2**31 ms.
MAX_TIMEOUT_S = 1e6
# Kills the host's process group when the campaign's end of the pipe closes (the campaign
# exited or was killed). Standard library only, started with -I -S: no site, no numpy.
_WATCHDOG = """\
import os, signal, sys
fd = int(sys.argv[1])
while True:
    try:
        if not os.read(fd, 1):
            break
    except InterruptedError:
        continue
    except OSError:
        break
os.killpg(0, signal.SIGKILL)
"""


@dataclass(frozen=True)
class Answer:
    """One call: `value` when it returned, else `error` (one line); `wall_s` its own time."""

    value: Any = None
    error: str | None = None
    wall_s: float = math.nan


def _describe(err: BaseException) -> str:
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def check_timeout(timeout_s: float, flag: str = "method_timeout") -> float:
    """The deadline of one call in s: a finite number in (0, MAX_TIMEOUT_S]. ValueError."""
    try:
        x = float(timeout_s)
    except (TypeError, ValueError):
        raise ValueError(f"{flag}: {timeout_s!r} is not a number of seconds") from None
    if not 0 < x <= MAX_TIMEOUT_S:
        raise ValueError(f"{flag}: {x:g} s is outside (0, {MAX_TIMEOUT_S:g}] s")
    return x


def _timed(fn: Callable, arg) -> Answer:
    t0 = time.perf_counter()
    try:
        value = fn(arg)
    except BaseException as err:  # noqa: BLE001 - SystemExit too: the method's failure
        return Answer(error=_describe(err), wall_s=time.perf_counter() - t0)
    return Answer(value=value, wall_s=time.perf_counter() - t0)


# --------------------------------------------------------------------------------------------
# The host process


def _memory_cap(limit_mb: float) -> None:
    """RLIMIT_AS at this process's address space now plus `limit_mb` (none when unknown)."""
    try:
        import resource
        with open("/proc/self/status", encoding="ascii") as f:
            size_kb = next(int(line.split()[1]) for line in f if line.startswith("VmSize:"))
        cap = size_kb * 1024 + int(limit_mb * 2**20)
        hard = resource.getrlimit(resource.RLIMIT_AS)[1]
        if hard != resource.RLIM_INFINITY:
            cap = min(cap, hard)
        resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    except (ImportError, OSError, ValueError, StopIteration):
        pass   # not Linux: no cap, the command's own estimate still holds


def _answer_json(answer: Answer, limit_mb: float) -> bytes:
    """The answer as JSON of plain numbers: {"value": {name: [v, sigma]}} once the value is
    checked here (methods.check_estimates), else {"error": text}; "wall_s" in both."""
    doc: dict[str, Any] = {"wall_s": answer.wall_s}
    if answer.error is not None:
        doc["error"] = answer.error
    else:
        try:
            est, sig = check_estimates(answer.value)
            doc["value"] = {k: [v, sig.get(k)] for k, v in est.items()}
        except BadResult as err:
            doc["error"] = " ".join(str(err).split())
        except MemoryError:
            doc["error"] = _memory_text(limit_mb)
        except BaseException as err:  # noqa: BLE001 - the method's objects: anything
            doc["error"] = f"its answer cannot be read: {_describe(err)}"
    return json.dumps(doc, allow_nan=False).encode("utf-8")


def _memory_text(limit_mb: float) -> str:
    return (f"MemoryError: the method needed more than the {limit_mb:,.0f} MB memory limit "
            "(JOINTBENCH_MAX_MEMORY_MB)")


def _serve(conn, watch, limit_mb: float) -> None:
    """The host's loop, until the pipe closes: ("resolve", ref) -> {"error": None or text};
    ("call", ref, log) -> the answer's JSON (`_answer_json`)."""
    os.setsid()                                    # its own group: killed whole
    subprocess.Popen([sys.executable, "-I", "-S", "-c", _WATCHDOG, str(watch.fileno())],
                     pass_fds=(watch.fileno(),), stdin=subprocess.DEVNULL,
                     stdout=subprocess.DEVNULL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # Ctrl-C is the campaign's to handle
    os.dup2(2, 1)                                  # a method's prints never reach stdout
    sys.stdout = sys.stderr
    import jointbench.bench.api  # noqa: F401 - the public API, loaded before any deadline
    _memory_cap(limit_mb)
    conn.send_bytes(b'{"error": null}')            # ready
    try:
        while True:
            try:
                what, ref, *arg = conn.recv()
            except (EOFError, OSError):
                return
            if what == "resolve":
                try:
                    resolve(ref)
                    error = None
                except CampaignError as err:
                    error = str(err)
                except MemoryError:
                    error = _memory_text(limit_mb)
                except Exception as err:  # noqa: BLE001 - said to the caller
                    error = _describe(err)
                conn.send_bytes(json.dumps({"error": error}).encode("utf-8"))
                continue
            t0 = time.perf_counter()
            try:
                answer = Answer(value=resolve(ref)(arg[0]), wall_s=time.perf_counter() - t0)
            except MemoryError as err:
                answer = Answer(error=f"{_memory_text(limit_mb)}: {_describe(err)}",
                                wall_s=time.perf_counter() - t0)
            except BaseException as err:  # noqa: BLE001 - SystemExit too: the method's failure
                answer = Answer(error=_describe(err), wall_s=time.perf_counter() - t0)
            conn.send_bytes(_answer_json(answer, limit_mb))
    finally:
        os.killpg(0, signal.SIGKILL)               # what the method left behind, and this host


class _Lost(Exception):
    """The host did not answer: it died, or missed the deadline (`timed_out`); it is closed."""

    def __init__(self, message: str, timed_out: bool = False):
        super().__init__(message)
        self.timed_out = timed_out


class Host:
    """One child process serving calls (see the module docstring). Starting it is waited for
    up to `STARTUP_S`, outside any call's deadline; importing a method's module and each call
    are waited for up to the call's deadline."""

    STARTUP_S = 300.0

    def __init__(self):
        from jointbench.bench.cli.resources import memory_limit_mb

        try:
            self.limit_mb = memory_limit_mb()
        except ValueError:   # a bad JOINTBENCH_MAX_MEMORY_MB: the command refuses it itself
            self.limit_mb = 4096.0
        self.conn, child = _CONTEXT.Pipe()
        watch, self._watch = _CONTEXT.Pipe(duplex=False)   # its EOF: this process is gone
        self.process = _CONTEXT.Process(target=_serve, args=(child, watch, self.limit_mb),
                                        daemon=True, name="jointbench-method-host")
        self.process.start()
        child.close()
        watch.close()
        self.ready: set[str] = set()
        self.failed: str | None = None
        try:
            self._request(None, self.STARTUP_S, "start")
        except _Lost as err:
            self.failed = str(err)

    def _request(self, message, timeout_s: float, what: str) -> dict:
        """Send `message` (None: only wait) and return the host's JSON answer within
        `timeout_s`; _Lost (the host closed) when it died or did not answer in time."""
        try:
            if message is not None:
                self.conn.send(message)
            if self.conn.poll(timeout_s):
                return json.loads(self.conn.recv_bytes())
        except (EOFError, OSError):
            self.close()
            raise _Lost(f"its process died (exit code {self.process.exitcode})"
                        + ("" if what == "the call" else f" during {what}")) from None
        self.close()
        raise _Lost(f"timeout: no answer within {timeout_s:g} s "
                    + ("(call stopped)" if what == "the call" else f"during {what} (stopped)"),
                    timed_out=True)

    def resolve(self, ref: str, timeout_s: float) -> str | None:
        """None when the host imports `ref`'s module and finds it within `timeout_s`, else
        why not (the host is closed unless the import only raised)."""
        if self.failed is not None:
            return f"method host: {self.failed}"
        if ref in self.ready:
            return None
        try:
            error = self._request(("resolve", ref), timeout_s, f"the import of {ref}")["error"]
        except _Lost as err:
            return str(err)
        if error is None:
            self.ready.add(ref)
        return error

    def call(self, ref: str, arg, timeout_s: float) -> Answer:
        """ref(arg) in the host, the import of ref's module included (each under
        `timeout_s`); the host is closed (and must be replaced) unless it answered."""
        error = self.resolve(ref, timeout_s)
        if error is not None:
            return Answer(error=error)
        try:
            doc = self._request(("call", ref, arg), timeout_s, "the call")
        except _Lost as err:
            return Answer(error=str(err), wall_s=timeout_s if err.timed_out else math.nan)
        wall = doc.get("wall_s")
        wall = float(wall) if isinstance(wall, (int, float)) else math.nan
        if doc.get("error") is not None:
            return Answer(error=str(doc["error"]), wall_s=wall)
        return Answer(value={k: (v, s) for k, (v, s) in doc["value"].items()}, wall_s=wall)

    @property
    def alive(self) -> bool:
        return not self.conn.closed and self.process.is_alive()

    def close(self) -> None:
        """Kill the host's process group (the host, its watchdog, whatever the method
        started) and reap the host."""
        if self.process.pid is not None:
            with contextlib.suppress(OSError):
                os.killpg(self.process.pid, signal.SIGKILL)
        self.process.join(5)
        if self.process.is_alive():
            self.process.kill()
            self.process.join(5)
        self.conn.close()
        self._watch.close()


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


def check_refs(refs: Sequence[str], timeout_s: float) -> None:
    """Before any run: every method named in `refs` imports and is found in a host of its
    own, each within `timeout_s` (a module that hangs, ends its process or prints at import
    costs this check, never the campaign process). CampaignError naming the method."""
    if not refs:
        return
    host = Host()
    try:
        for ref in refs:
            error = host.resolve(ref, timeout_s)
            if error is not None:
                raise CampaignError(error if error.startswith("--method") else
                                    f"--method {ref}: cannot import it: {error}")
    finally:
        host.close()


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
