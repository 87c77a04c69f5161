"""Shared, session-scoped experiments: each virtual run is simulated once per test session.

The folder a test lives in is its layer, and its marker (pyproject.toml declares them):

    tests/unit        unit         pure numerics on synthetic arrays, no MuJoCo simulation
    tests/cli         cli          the command line, in-process or as a subprocess
    tests/sim         sim          experiments on the bench (MuJoCo) or the independent simulator
    tests/validation  validation   accuracy bars against the truth, the paper and EMPS

`make check` runs unit and cli without the tests marked slow; `make test` runs everything.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

LAYERS = ("unit", "cli", "sim", "validation")
HERE = Path(__file__).resolve().parent


def pytest_collection_modifyitems(config, items):
    """Mark every test with its folder's layer; a test outside the four folders is an error."""
    for item in items:
        parts = Path(str(item.fspath)).resolve().relative_to(HERE).parts
        if len(parts) < 2 or parts[0] not in LAYERS:
            raise pytest.UsageError(f"{item.nodeid}: a test file belongs in one of tests/"
                                    f"{{{','.join(LAYERS)}}}/")
        item.add_marker(getattr(pytest.mark, parts[0]))


@pytest.fixture(scope="session")
def prototype_run():
    """The demo's experiment: the paper's prototype, 60 s chirp, default sensors, seed 1."""
    from jointbench.bench.sim.experiment import run_experiment

    return run_experiment("prototype", duration=60.0, seed=1)


@pytest.fixture(scope="session")
def prototype_log(prototype_run):
    return prototype_run.log


@pytest.fixture(scope="session")
def indep_log():
    """The independent simulator's logs, each simulated once per session (a 60 s log takes
    seconds in numpy): `indep_log(family, **options)` is jointbench.testing.simulate(family,
    **options), the same Log object for the same arguments. Read it, never write into it."""
    import inspect

    from jointbench.testing import simulate

    signature = inspect.signature(simulate)
    logs = {}

    def get(*args, **options):
        bound = signature.bind(*args, **options)
        bound.apply_defaults()
        key = tuple(bound.arguments.items())
        if key not in logs:
            logs[key] = simulate(*bound.args, **bound.kwargs)
        return logs[key]

    return get
