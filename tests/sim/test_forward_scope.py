"""The forward view's replay steps and its scope for a torque periodic in the motor angle
(bench.analysis.diagnose.forward: plant_substeps, phase_errors, forward_scope; verdict's
forward_worse over the judged segments)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.forward import (MIN_JUDGED, PHASE_LIMIT,
                                                        forward_scope, phase_errors,
                                                        plant_substeps, replay_tau0)
from jointbench.bench.analysis.diagnose.verdict import forward_worse
from jointbench.bench.sim import nominal as nominal_axes
from jointbench.bench.sim.replay import replay
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.discrepancy import SEGMENTS
from jointbench.identification.log import Log
from jointbench.testing import FAMILIES, simulate

RATE = PAPER_RATE
N = 4000          # samples: 100 per segment
PERIOD = 0.01     # rad


def _log(meta: dict[str, str], rate: float = RATE, q_m: np.ndarray | None = None) -> Log:
    t = np.arange(N) / rate
    q_m = np.zeros(N) if q_m is None else q_m
    return Log(t=t, q_m=q_m, tau_m=np.ones(N), meta={"sample_rate_hz": str(rate), **meta})


def test_plant_substeps_follow_the_log():
    # a MuJoCo plant: its own steps (its discretisation is its physics)
    assert plant_substeps(_log({"integrator": "mjINT_RK4", "substeps": "1"})) == 1
    assert plant_substeps(_log({"integrator": "mjINT_RK4", "substeps": "3"})) == 3
    # a continuous plant (measured, another simulator): steps no longer than the friction's
    # time constant, 2 ms by default: ceil(2.85 / 2) = 2 at the paper's rate, 1 at 1 kHz
    assert plant_substeps(_log({})) == 2
    assert plant_substeps(_log({"integrator": "RK4 (fixed step, numpy)", "substeps": "9"})) == 2
    assert plant_substeps(_log({}, rate=1000.0)) == 1
    # the log's own time constant: ceil(2.85 / 0.25) = 12
    assert plant_substeps(_log({"friction_timeconst_s": "0.00025"})) == 12


def test_a_continuous_plant_replays_with_resolved_friction():
    """The independent simulator's soft axis without feedforward, noise-free: its true
    parameters replay the log at 25.8 % torque error with one MuJoCo step a sample (the
    friction constraint's 2 ms time constant under the 2.85 ms step), 1.79 % with the two
    steps plant_substeps gives (8 steps: 1.78 %)."""
    fam = FAMILIES["soft"]
    log = simulate(fam, 7, 12.0, feedforward=False, ideal_sensors=True)
    spec = nominal_axes.two_mass_axis(Jm=fam.Jm, FVm=fam.FVm, FSm=fam.FSm, K=fam.K, JL=fam.JL,
                                      FV=fam.FV, FS=fam.FS, timestep=log.ts,
                                      tau_max=fam.tau_max, gravity=log.gravity, name="soft")
    model, axis = nominal_axes.compile_axis(spec)

    def error(n: int) -> float:
        r = replay(model, axis, log, substeps=n, tau0=replay_tau0(log))
        return 100 * float(np.linalg.norm(r.tau_m - log.tau_m) / np.linalg.norm(log.tau_m))

    n = plant_substeps(log)
    assert n == 2
    assert error(n) < 3.0
    assert error(1) > 5 * error(n)


def test_phase_errors_analytic():
    """A replay a constant e off a motion of constant step dq: 2 pi / p sqrt(e^2 + (dq/2)^2)."""
    dq, e = 0.001, 0.0007
    q = dq * np.arange(N)
    s = phase_errors(q, [q + e, q - 0.5 * e], PERIOD)
    # the last sample's step is 0 (np.diff appended with the last value): segment 39 differs
    want = 2 * math.pi / PERIOD * math.hypot(e, dq / 2)
    assert s[:-1] == pytest.approx(np.full(SEGMENTS - 1, want), rel=1e-9)
    assert s[-1] < want


def _diagnosis(q_m: np.ndarray, off_nominal: np.ndarray, off_extended: np.ndarray,
               effect: str = "torque_ripple"):
    # replays whose torque follows the logged one (forward.follows): the phase decides
    tau = 10.0 + np.sin(np.arange(len(q_m)))
    view = lambda off: SimpleNamespace(q_m=q_m + off, tau_m=tau + 0.1)   # noqa: E731
    return SimpleNamespace(log=SimpleNamespace(q_m=q_m, meta={}, tau_m=tau),
                           forward_nominal=view(off_nominal),
                           forward_extended=view(off_extended),
                           causes=(SimpleNamespace(effect=effect),),
                           extended_parameters={"ripple_period_rad": PERIOD})


def _replayed(d, tau: np.ndarray, nominal: np.ndarray, extended: np.ndarray, effect: str):
    """`d` with the logged torque `tau` and the two replays' torques, their relative errors,
    and a named `effect` whose inverse view halves the residual."""
    d.log.tau_m = tau
    for view, t in ((d.forward_nominal, nominal), (d.forward_extended, extended)):
        view.tau_m = t
        view.tau_rel_pct = 100 * np.linalg.norm(t - tau) / np.linalg.norm(tau)
    d.inverse = SimpleNamespace(named=SimpleNamespace(effect=effect, before_pct=20.0,
                                                      after_pct=10.0))
    return d


def test_forward_scope():
    q = np.zeros(N)
    seg = np.arange(N) * SEGMENTS // N
    small = np.full(N, 0.02 * PERIOD)   # phase error 0.13 rad
    large = np.full(N, 0.5 * PERIOD)    # pi rad: the replayed ripple is out of phase
    # both replays keep the phase everywhere: every segment judged, no note
    scope = forward_scope(_diagnosis(q, small, -small))
    assert scope.judged and scope.keep is None and scope.note == ""
    # not a periodic effect: every segment, whatever the replays' position errors
    scope = forward_scope(_diagnosis(q, large, large, effect="backlash"))
    assert scope.judged and scope.keep is None
    # the extended replay loses the phase in the second half: only the first half is judged
    scope = forward_scope(_diagnosis(q, small, np.where(seg < 20, small, large)))
    assert scope.judged and scope.keep.tolist() == [k < 20 for k in range(SEGMENTS)]
    assert "20 of 40 segments" in scope.note
    # the nominal loses it everywhere but MIN_JUDGED - 1 segments: the view cannot judge
    scope = forward_scope(_diagnosis(q, np.where(seg < MIN_JUDGED - 1, small, large), small))
    assert not scope.judged and scope.keep is None
    assert scope.note.startswith("the forward view cannot judge torque_ripple on this log")
    # the limit: a phase error just under sqrt(2 ln 2) is judged, just over is not
    at = PHASE_LIMIT * PERIOD / (2 * math.pi)
    assert forward_scope(_diagnosis(q, small, np.full(N, 0.99 * at))).keep is None
    assert not forward_scope(_diagnosis(q, small, np.full(N, 1.01 * at))).judged


def test_forward_worse_on_the_judged_segments():
    rng = np.random.default_rng(3)
    tau = rng.standard_normal(N)
    seg = np.arange(N) * SEGMENTS // N
    nominal = tau + 0.5 * rng.standard_normal(N)
    # the extended replay is 3 times worse in the first half, 2 times better in the second
    extended = tau + np.where(seg < 20, 1.5, 0.25) * rng.standard_normal(N)
    t_all, _ = forward_worse(tau, nominal, extended)
    t_first, p_first = forward_worse(tau, nominal, extended, seg_mask(lambda k: k < 20))
    t_second, p_second = forward_worse(tau, nominal, extended, seg_mask(lambda k: k >= 20))
    assert t_first > 10 and p_first < 1e-6
    assert t_second < -10 and p_second > 0.999
    assert t_second < t_all < t_first


def seg_mask(which) -> np.ndarray:
    return np.array([which(k) for k in range(SEGMENTS)])


def test_gain_reason_judges_a_ripple_where_the_phase_is_kept():
    """verdict.gain_reason on a torque_ripple: the replays keep its phase in the first half
    only; the extended replay is 1.2 times worse there and far better in the second half (a
    gain over 1 on the whole log): overruled, with the judged segments' errors. When the
    phase is kept in fewer than MIN_JUDGED segments, the forward view does not overrule."""
    from jointbench.bench.analysis.diagnose.verdict import gain_reason

    rng = np.random.default_rng(5)
    seg = np.arange(N) * SEGMENTS // N
    tau = 10 + rng.standard_normal(N)
    q = np.zeros(N)
    small, large = np.full(N, 0.02 * PERIOD), np.full(N, 0.5 * PERIOD)
    nominal_tau = tau + rng.standard_normal(N)
    extended_tau = tau + np.where(seg < 20, 1.2, 0.1) * rng.standard_normal(N)

    def diagnosis(off_extended):
        return _replayed(_diagnosis(q, small, off_extended), tau, nominal_tau, extended_tau,
                         "torque_ripple")

    d = diagnosis(np.where(seg < 20, small, large))
    assert d.forward_extended.tau_rel_pct < d.forward_nominal.tau_rel_pct   # gain > 1 overall
    why = gain_reason(d)
    assert "worse in the forward view on the 20 segments it judges" in why
    # judged nowhere but MIN_JUDGED - 1 segments: no forward verdict
    assert gain_reason(diagnosis(np.where(seg < MIN_JUDGED - 1, small, large))) == ""


def test_a_nominal_replay_that_follows_nothing_judges_nothing():
    """A nominal replay not significantly closer to the logged torque than a zero torque
    (forward.follows): the forward view cannot judge, whatever the extended replay does."""
    from jointbench.bench.analysis.diagnose.forward import follows

    rng = np.random.default_rng(6)
    tau = 10 * np.sin(np.linspace(0, 300, N)) + rng.standard_normal(N)
    assert follows(tau, tau + 0.5 * rng.standard_normal(N))
    lost = rng.standard_normal(N) * np.std(tau)          # a replay unrelated to the log
    assert not follows(tau, lost) and not follows(tau, np.zeros(N) + 1e-9)
    d = _diagnosis(np.zeros(N), np.zeros(N), np.zeros(N), effect="offset")
    d.forward_nominal.tau_m, d.forward_nominal.tau_rel_pct = lost, 141.0
    scope = forward_scope(d)
    assert not scope.judged and "the nominal's replay does not follow it" in scope.note


def test_phase_errors_of_a_plant_that_held_the_torque_too():
    """A log of a MuJoCo plant held the ripple over the sample as the replay does: only the
    position error counts."""
    dq, e = 0.001, 0.0007
    q = dq * np.arange(N)
    s = phase_errors(q, [q + e], PERIOD, held=True)
    assert s == pytest.approx(np.full(SEGMENTS, 2 * math.pi / PERIOD * e), rel=1e-9)


def test_a_replay_that_rings_right_but_out_of_phase_is_judged_by_its_envelope():
    """verdict.envelope_better: a torque of amplitude 1; the nominal replay rings in phase
    at 0.7 of it in segments 10 to 29 (a more damped loop), the extended one at the log's
    amplitude, 1.1 rad off at the mode (segments 10 to 19: a lightly damped loop's phase is
    sensitive there) and in phase above it; elsewhere both follow it alike. Sample by sample
    the extended replay is worse at the mode (2 (1 - cos 1.1) = 1.09 of the power against
    (1 - 0.7)^2 = 0.09) and better above it: a pooled gain under 1 within the segments'
    spread, which gain_reason took as a replay that does not confirm it; its envelope is the
    log's and is found significantly closer. A wrong extended model, in phase at 1.4 times
    the log's amplitude where the nominal rings, is not, and stays overruled."""
    from jointbench.bench.analysis.diagnose.verdict import envelope_better, gain_reason
    from jointbench.identification.discrepancy.heldout import ALPHA

    rng = np.random.default_rng(7)
    seg = np.arange(N) * SEGMENTS // N
    mode, above = (seg >= 10) & (seg < 20), (seg >= 20) & (seg < 30)
    phase = 2 * math.pi * 0.05 * np.arange(N)
    tau = np.sin(phase) + 0.05 * rng.standard_normal(N)   # the logged torque's noise
    away = (1 + 0.02 * rng.standard_normal(SEGMENTS)[seg]) * np.sin(phase)
    ring = (1 + 0.02 * rng.standard_normal(SEGMENTS)[seg]) * np.sin(phase + 1.1)
    nominal = np.where(mode | above, 0.7 * np.sin(phase), away)
    extended = np.where(mode, ring, away)
    wrong = np.where(mode | above, 1.4 * np.sin(phase), away)
    assert forward_worse(tau, nominal, extended)[1] > ALPHA          # within the spread
    assert forward_worse(tau, extended, nominal)[1] > ALPHA          # not better either
    assert np.linalg.norm(extended - tau) > np.linalg.norm(nominal - tau)
    assert envelope_better(tau, nominal, extended)[1] < ALPHA
    assert envelope_better(tau, nominal, wrong)[1] > 0.5

    q = np.zeros(N)
    d = _replayed(_diagnosis(q, q, q, effect="torque_lag"), tau, nominal, extended,
                  "torque_lag")
    assert gain_reason(d) == ""
    d.forward_extended.tau_m = wrong
    d.forward_extended.tau_rel_pct = 100 * np.linalg.norm(wrong - tau) / np.linalg.norm(tau)
    assert gain_reason(d).startswith("torque_lag's extended model")


def test_the_weaker_cause_of_a_pair_is_judged_against_the_model_holding_the_stronger():
    """verdict.gain_reason's `before`: a torque of amplitude 1 in 40 segments. In the first
    ten the stronger cause acts: the nominal replays them with the log's envelope but
    0.5 rad late, the model holding the stronger cause in phase at 0.85 of the amplitude
    (a sample-by-sample error 0.02 of the segment's power against 0.25: the replay accepts
    it against the nominal). The weaker cause, a lag, acts at the mode (segments 10 to 19:
    its model rings 1.3 times the log's amplitude 0.8 rad off, where the others ring at 0.8
    in phase) and at the top of the sweep (segments 20 to 39: the log's amplitude, where the
    others replay 0.9 of it). Against the nominal the model with both loses sample by
    sample and its envelope is no closer: the stronger cause's envelope loss in the first
    ten segments (0.15 of the amplitude against the nominal's exact one) enters the lag's
    comparison, and the lag is not confirmed. Against the model holding the stronger cause
    those segments are the same in both replays, and the lag's envelope, the log's at the
    top of the sweep, is significantly closer: it stands. A wrong lag whose replay is 1.2
    times the log's amplitude at the top is rejected against either."""
    from jointbench.bench.analysis.diagnose.verdict import gain_reason

    rng = np.random.default_rng(7)
    seg = np.arange(N) * SEGMENTS // N
    k = np.arange(SEGMENTS)
    first, mode = k < 10, (k >= 10) & (k < 20)
    phase = 2 * math.pi * 0.05 * np.arange(N)
    tau = np.sin(phase) + 0.05 * rng.standard_normal(N)   # the logged torque's noise

    def replayed(amp: np.ndarray, shift: np.ndarray) -> np.ndarray:
        jitter = 1 + 0.02 * rng.standard_normal(SEGMENTS)   # each segment's amplitude
        return (amp * jitter)[seg] * np.sin(phase + shift[seg])

    def view(t: np.ndarray) -> SimpleNamespace:
        return SimpleNamespace(q_m=np.zeros(N), tau_m=t,
                               tau_rel_pct=100 * np.linalg.norm(t - tau) / np.linalg.norm(tau))

    def diagnosis(extended: np.ndarray, *effects: str) -> SimpleNamespace:
        causes = tuple(SimpleNamespace(effect=e, before_pct=20.0, after_pct=10.0)
                       for e in effects)
        return SimpleNamespace(log=SimpleNamespace(q_m=np.zeros(N), meta={}, tau_m=tau),
                               forward_nominal=view(nominal), forward_extended=view(extended),
                               causes=causes, extended_parameters={}, forward_note="",
                               inverse=SimpleNamespace(named=causes[0], causes=causes))

    zero, others = np.zeros(SEGMENTS), np.where(mode, 0.8, 0.9)
    nominal = replayed(np.where(first, 1.0, others), np.where(first, 0.5, 0.0))
    stronger = replayed(np.where(first, 0.85, others), zero)
    ring = (np.where(mode, 1.3, 1.0), np.where(mode, 0.8, 0.0))
    both = replayed(np.where(first, 0.85, ring[0]), ring[1])
    wrong = replayed(np.where(first, 0.85, np.where(mode, 1.3, 1.2)), ring[1])
    assert gain_reason(diagnosis(stronger, "backlash")) == ""
    assert gain_reason(diagnosis(both, "backlash", "torque_lag")).startswith(
        "the extended model with backlash, torque_lag does not improve the forward view")
    assert gain_reason(diagnosis(both, "backlash", "torque_lag"), view(stronger)) == ""
    assert gain_reason(diagnosis(wrong, "backlash", "torque_lag"), view(stronger)).startswith(
        "torque_lag's extended model, against the one holding backlash, is worse")
    assert gain_reason(diagnosis(wrong, "backlash", "torque_lag")) != ""


def test_the_scope_ends_where_the_extended_replay_stops_reproducing_itself(monkeypatch):
    """Judged only before the first segment where the extended replay from a start half an
    encoder step away differs from itself as much as from the log (forward.start_spread,
    replaced here by its per-segment value); asked only when the extended replay is not
    better than the nominal's."""
    import jointbench.bench.analysis.diagnose.forward as F

    seg = np.arange(N) * SEGMENTS // N
    tau = 10.0 + np.sin(np.arange(N))
    d = _diagnosis(np.zeros(N), np.zeros(N), np.zeros(N), effect="backlash")
    d.log.q_ref = np.zeros(N)
    d.forward_nominal.tau_m = tau + 0.2                    # error 0.2 everywhere
    d.forward_extended.tau_m = tau + np.where(seg < 15, 0.01, 0.5)
    spread = np.where(np.arange(SEGMENTS) < 15, 0.001, 0.6)  # reproduces itself until 15
    monkeypatch.setattr(F, "start_spread", lambda d: spread)
    scope = forward_scope(d)
    assert scope.judged and scope.keep.tolist() == [k < 15 for k in range(SEGMENTS)]
    assert "from segment 16 of 40 on" in scope.note
    # it stops reproducing itself before MIN_JUDGED segments: the view cannot judge
    monkeypatch.setattr(F, "start_spread",
                        lambda d: np.where(np.arange(SEGMENTS) < MIN_JUDGED - 1, 0.001, 0.6))
    scope = forward_scope(d)
    assert not scope.judged and scope.note.startswith("the forward view cannot judge")
    # an extended replay better than the nominal's is not asked about its spread
    d.forward_extended.tau_m = tau + 0.01
    monkeypatch.setattr(F, "start_spread", lambda d: pytest.fail("asked"))
    assert forward_scope(d).keep is None
