"""Shared, session-scoped experiments: each virtual run is simulated once per test session."""

from __future__ import annotations

import matplotlib
import pytest

matplotlib.use("Agg")


@pytest.fixture(scope="session")
def prototype_run():
    """The demo's experiment: the paper's prototype, 60 s chirp, default sensors, seed 1."""
    from jointbench.bench.sim.experiment import run_experiment

    return run_experiment("prototype", duration=60.0, seed=1)


@pytest.fixture(scope="session")
def prototype_log(prototype_run):
    return prototype_run.log
