"""Shared, session-scoped experiments: each virtual run is simulated once per session.
`make test` and `make check` run one process per core (pytest-xdist, `--dist loadfile
--no-loadscope-reorder`): every test file stays in one process, so its module fixtures run
once, and two files that ask bench_log or indep_log for the same run share it: simulated by
one process, read by the other from the session's shared folder. The files go out longest
first (LONGEST below).

The folder a test lives in is its layer, and its marker (pyproject.toml declares them):

    tests/unit        unit         pure numerics on synthetic arrays, no MuJoCo simulation
    tests/cli         cli          the command line, in-process or as a subprocess
    tests/sim         sim          experiments on the bench (MuJoCo) or the independent simulator
    tests/validation  validation   accuracy bars against the truth, the paper and EMPS

`make check` runs unit and cli without the tests marked slow; `make test` runs everything.
A test may not rely on another's side effects, on the working folder (monkeypatch.chdir into
its tmp_path) or on files outside its tmp_path: the processes run side by side.
"""

from __future__ import annotations

import hashlib
import inspect
import os
import pickle
import time
from pathlib import Path

# One BLAS thread a test process, set before numpy loads (the xdist processes inherit it): the
# processes already take one core each, and OpenBLAS's threads spin on the small regressors
# identification/ solves (docs/validation.md, "BLAS threads": 1.4-1.7x the CPU of one thread).
# A value the caller set is kept.
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import hypothesis  # noqa: E402
import matplotlib  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

matplotlib.use("Agg")

# The suite is a gate: one checkout draws the same property-test examples on every run, so a
# red run names a defect of the change, not an unlucky draw. `make fuzz` draws new ones.
hypothesis.settings.register_profile("gate", derandomize=True)
hypothesis.settings.register_profile("explore", derandomize=False)
hypothesis.settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "gate"))

LAYERS = ("unit", "cli", "sim", "validation")
HERE = Path(__file__).resolve().parent


# The files that take longest (over 10 CPU seconds each, summed over their tests), longest first.
# `make test` hands whole files to its processes in collection order (--no-loadscope-reorder):
# these go first and the many short files fill in at the end, so that both processes finish
# together. A file missing here only runs later; the list orders, it selects nothing.
LONGEST = (
    "validation/test_arm.py",
    "sim/test_refine.py",
    "validation/test_indep_accuracy.py",
    "sim/test_extended_runs.py",
    "validation/test_identification.py",
    "validation/test_diagnose_model.py",
    "validation/test_indep_frictionless_motor_only.py",
    "validation/test_diagnose_heldout.py",
    "sim/test_campaign.py",
    "sim/test_methods.py",
    "validation/test_diagnose.py",
    "sim/test_first_mode.py",
    "sim/test_debias.py",
    "sim/test_ros_bag_import.py",
    "sim/test_diagnose_named_claims.py",
    "validation/test_lab_rig_holdback.py",
    "validation/test_indep_logsweep.py",
    "sim/test_diagnose_clipped_limit.py",
    "sim/test_survey.py",
    "sim/test_diagnose_link_law.py",
    "sim/test_replay.py",
    "sim/test_validate.py",
)


def _file_rank(parts: tuple[str, ...], slow: bool) -> tuple[int, int, int]:
    """LONGEST first, in its order; then the layers, the slower first (validation, sim,
    cli, unit), within a layer the files holding a test marked slow first; within a rank,
    collection order (the sort is stable)."""
    name = "/".join(parts)
    if name in LONGEST:
        return 0, LONGEST.index(name), 0
    return 1, ("validation", "sim", "cli", "unit").index(parts[0]), 0 if slow else 1


def pytest_collection_modifyitems(config, items):
    """Mark every test with its folder's layer (a test outside the four folders is an
    error), and put the longest files first."""
    file_of, slow = {}, {}
    for item in items:
        parts = Path(str(item.fspath)).resolve().relative_to(HERE).parts
        if len(parts) < 2 or parts[0] not in LAYERS:
            raise pytest.UsageError(f"{item.nodeid}: a test file belongs in one of tests/"
                                    f"{{{','.join(LAYERS)}}}/")
        item.add_marker(getattr(pytest.mark, parts[0]))
        file_of[item.nodeid] = parts
        slow[parts] = slow.get(parts, False) or item.get_closest_marker("slow") is not None
    rank = {parts: _file_rank(parts, s) for parts, s in slow.items()}
    items.sort(key=lambda item: rank[file_of[item.nodeid]])


@pytest.fixture(scope="session")
def prototype_run():
    """The demo's experiment: the paper's prototype, 60 s chirp, default sensors, seed 1."""
    from jointbench.bench.sim.experiment import run_experiment

    return run_experiment("prototype", duration=60.0, seed=1)


@pytest.fixture(scope="session")
def prototype_log(bench_log):
    """prototype_run's log, through bench_log (simulated once per session)."""
    return bench_log("prototype", duration=60.0, seed=1)


@pytest.fixture(scope="session")
def prototype_joint_motor(prototype_log):
    """identify(prototype_log, "joint-motor") with the defaults, made once per test process
    for the files that check it. Read it, never write into it."""
    from jointbench.identification.identify import identify

    return identify(prototype_log, "joint-motor")


def _made_once(folder: Path, key: str, make):
    """make() for `key`, computed by one of the session's processes and read from `folder` by
    the others (pickled: arrays bit for bit). The first to create `key`'s lock file computes
    and writes the result atomically; the others wait for it. A lock left by a process that
    is gone, or a computation that failed (the lock removed), is taken over."""
    name = hashlib.sha256(key.encode()).hexdigest()[:32]
    done, lock = folder / f"{name}.pkl", folder / f"{name}.lock"
    while True:
        if done.exists():
            with open(done, "rb") as f:
                return pickle.load(f)
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                owner = int(lock.read_text() or 0)
                os.kill(owner, 0)
            except ProcessLookupError:
                lock.unlink(missing_ok=True)   # its maker is gone
            except (ValueError, FileNotFoundError, PermissionError):
                pass                           # being written, just removed, or alive
            time.sleep(0.05)
            continue
        try:
            os.write(fd, str(os.getpid()).encode())
            os.close(fd)
            value = make()
            part = folder / f"{name}.{os.getpid()}.part"
            with open(part, "wb") as f:
                pickle.dump(value, f, protocol=pickle.HIGHEST_PROTOCOL)
            os.replace(part, done)
            return value
        finally:
            if not done.exists():
                lock.unlink(missing_ok=True)


def _once(run, folder: Path | None = None, keep=lambda result: result):
    """keep(run(...)) made once per distinct set of arguments (bound to run's signature,
    defaults filled in, compared by repr: frozen dataclasses and plain values) and kept for
    the session. With `folder` (the session's folder shared by its xdist processes) it is
    made once in the whole session: the other processes read it from there. Arguments
    holding arrays are not kept."""
    signature = inspect.signature(run)
    kept = {}

    def get(*args, **options):
        bound = signature.bind(*args, **options)
        bound.apply_defaults()
        if any(isinstance(v, np.ndarray) for v in bound.arguments.values()):
            return keep(run(*bound.args, **bound.kwargs))
        key = repr(tuple(bound.arguments.items()))
        if key not in kept:
            def make():
                return keep(run(*bound.args, **bound.kwargs))
            kept[key] = make() if folder is None else _made_once(
                folder, f"{run.__module__}.{run.__qualname__}{key}", make)
        return kept[key]

    return get


@pytest.fixture(scope="session")
def shared_folder(tmp_path_factory) -> Path | None:
    """The folder the session's xdist processes share (beside their own temporary folders,
    so new for every session), or None when the tests run in one process."""
    if "PYTEST_XDIST_WORKER" not in os.environ:
        return None
    folder = tmp_path_factory.getbasetemp().parent / "shared-runs"
    folder.mkdir(exist_ok=True)
    return folder


@pytest.fixture(scope="session")
def bench_log(shared_folder):
    """The bench's logs, each simulated once per session: `bench_log(model, joint, **options)`
    is run_experiment(model, joint, **options).log, the same Log object for the same
    arguments in a process (the other processes read it from shared_folder). Read it, never
    write into it."""
    from jointbench.bench.sim.experiment import run_experiment

    return _once(run_experiment, shared_folder, keep=lambda result: result.log)


@pytest.fixture(scope="session")
def indep_log(shared_folder):
    """The independent simulator's logs, each simulated once per session (a 60 s log takes
    1-10 s in numpy): `indep_log(family, **options)` is jointbench.testing.simulate(family,
    **options), the same Log object for the same arguments in a process (the other processes
    read it from shared_folder). Read it, never write into it."""
    from jointbench.testing import simulate

    return _once(simulate, shared_folder)
