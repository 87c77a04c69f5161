"""A wide backlash on the lab rig (half-width 0.235 rad, its voltage drive under a P loop,
500 Hz, 40 s): the link floats in the dead band between impacts, and the extended model's
closed-loop replay keeps no phase there: replayed again from a start half a link-encoder step
away (bench.analysis.diagnose.forward.start_moved), it differs from itself as much as from
the log after a few segments. Its torque error over the whole log is then no evidence
against the model: the forward view judges only the segments before that
(forward._reproduced_scope), and here cannot judge at all; the backlash, passing its
held-out test, is named with its half-width. The same rig and seed without it names nothing."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.analysis.diagnose.forward import start_moved, start_spread
from jointbench.bench.analysis.diagnose.report import dumps
from jointbench.identification.log.read import position_quantum
from jointbench.testing import LAB_PLACES, LabRigRunner

SEED = 1117507998
B = 0.23546824699859026     # rad: a dead band three times the rig's deflection RMS


@pytest.fixture(scope="module")
def runner():
    return LabRigRunner(duration=40.0)


@pytest.mark.slow
def test_a_backlash_whose_replay_keeps_no_phase_is_named(runner):
    log = runner.log(LAB_PLACES[0], (("backlash", B, {}),), SEED, True, False)
    d = diagnose(log)
    assert [c.effect for c in d.causes] == ["backlash"]
    c = d.causes[0]
    assert c.test.passes and c.test.t > c.test.bar
    # the half-width within a link-encoder step (the link's position is quantised by it)
    step = position_quantum(log.q)
    assert abs(d.extended_parameters["backlash_rad"] - B) < step
    assert "cannot judge the named causes" in d.forward_note
    assert "half an encoder step away" in d.forward_note
    # the start moved by half an encoder step, the link's alone
    moved = start_moved(log)
    assert moved.q[0] - log.q[0] == pytest.approx(0.5 * step)
    assert np.array_equal(moved.q[1:], log.q[1:]) and np.array_equal(moved.q_m, log.q_m)
    # the extended replay is chaotic: from that start it ends as far from itself as from
    # the log, while the first segment reproduces itself closer than the log
    spread = start_spread(d)
    tau, b = np.asarray(log.tau_m), np.asarray(d.forward_extended.tau_m)
    n = len(tau) // 40
    err = np.sqrt(np.mean((b[: 40 * n] - tau[: 40 * n]).reshape(40, n) ** 2, axis=1))
    assert spread[0] < err[0]
    assert (spread >= err).any()
    assert failing_claims(json.loads(dumps(d))) == []


@pytest.mark.slow
def test_the_same_rig_without_backlash_names_nothing(runner):
    d = diagnose(runner.log(LAB_PLACES[0], (), SEED, True, False))
    assert d.causes == ()
