"""Issue 17's core: the first mode measured from the log, the band designed from it at
350.87 Hz, and the honest checks (identification.first_mode, defaults.choose_filter,
band_checks)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from jointbench.identification.filter_choice import choose_filter
from jointbench.identification.first_mode import measure_first_mode
from jointbench.identification.identify import identify
from jointbench.identification.log import Log
from jointbench.identification.paper_tables import to_json

ARM = tuple(f"axis{j}" for j in range(1, 7))
# joint-motor K, Jm, JL at 350.87 Hz with defaults (seed 1, 60 s), over 0.5 %: none measured.
# axis2's Jm is the closest, -0.31 % (sigma 0.24 %) at the default physics step; it grows
# toward about -0.49 % as the step shrinks (an ideal Coulomb plant), so this bar is about
# 2 sigma there (docs/design-notes.md, "The default physics step")
JOINT_MOTOR_OVER: dict[str, str] = {}
# motor-only (the link reconstructed from q_m) beyond 3 corrected sigma, seed 1: none (the bench
# steps its physics inside the sample interval, and the link is reconstructed as a continuous
# plant's)
MOTOR_ONLY_Z_OVER: dict[str, str] = {}


@pytest.fixture(scope="session")
def arm_logs(bench_log):
    return {j: bench_log("arm6", j, duration=60.0, seed=1) for j in ARM}


def err(value: float, truth: float) -> float:
    return 100 * (value - truth) / abs(truth)


def test_prototype_f1(prototype_log):
    mode = measure_first_mode(prototype_log)
    assert mode.found and "link" in mode.method
    assert abs(err(mode.f1_hz, prototype_log.truth()["f1_hz"])) < 2
    assert 0 < mode.sigma_hz < 0.1


@pytest.mark.parametrize("joint", ARM)
def test_arm_f1_at_paper_rate(arm_logs, joint):
    log = arm_logs[joint]
    mode = measure_first_mode(log)
    assert mode.found
    assert abs(err(mode.f1_hz, log.truth()["f1_hz"])) < 2, mode


def test_prototype_unchanged(prototype_log, prototype_joint_motor):
    """The paper's filter (wn 176, Nd 26, 3 points) and the reference numbers (seed 1): the
    band rule (identification/band_choice.py) keeps it, the wide band (Nd 9, 15.6 Hz) being
    the less precise on this log (largest relative corrected sigma 0.16 % against 0.13 %)."""
    result = prototype_joint_motor
    s = result.settings
    assert (s.wn, s.Nd, s.stencil) == (176.0, 26, 3)
    assert result.band.used == "chooser" and result.band.alternative.Nd < s.Nd
    assert result.band.alt_rel_sigma > result.band.rel_sigma
    assert result.paper_axis and result.warnings == ()
    out = to_json(result, prototype_log.truth())
    assert out["first_mode"]["source"] == "measured" and out["first_mode"]["found"]
    assert out["filter"]["cutoff_over_f1"] > 1.3


@pytest.mark.parametrize("joint", ARM)
@pytest.mark.parametrize("model,tol", [("joint-motor", 0.5), ("motor-only", 3.0)])
def test_arm_identify_with_defaults(arm_logs, joint, model, tol, request):
    """Issue 17: the band from the measured f1, the 5-point chain, the reference's instruments:
    K, Jm, JL within 0.5 % (joint-motor) and 3 % (motor-only), the truth within 3 corrected
    sigma. Measured (seed 1): joint-motor within 0.15 % on every joint (the band rule,
    identification/band_choice.py, widens axis1's from Nd 7 to 6, 0.17 % against 0.18 %;
    the other joints' bands reach the excitation's top already); motor-only within 0.28 %
    (the link reconstructed from q_m; eqs. 18-20 alone: within 2.5 %)."""
    if model == "joint-motor" and joint in JOINT_MOTOR_OVER:
        request.applymarker(pytest.mark.xfail(
            strict=True, reason=f"joint-motor at 350.87 Hz: {JOINT_MOTOR_OVER[joint]}"))
    if model == "motor-only" and joint in MOTOR_ONLY_Z_OVER:
        request.applymarker(pytest.mark.xfail(
            strict=True, reason=f"motor-only at 350.87 Hz: {MOTOR_ONLY_Z_OVER[joint]}"))
    log = arm_logs[joint]
    result = identify(log, model)
    truth = log.truth()
    assert result.settings.stencil == 5 and not result.paper_axis
    assert result.ls.instrumental == (model == "joint-motor")
    assert any("too low for the mode" in w for w in result.warnings)
    for name in ("K", "Jm", "JL"):
        assert abs(err(result.physical[name], truth[name])) < tol, (name, result.physical[name])
        z = (result.physical[name] - truth[name]) / result.physical_sigma_corrected[name]
        assert abs(z) < 3, (name, z)


def test_rate_too_low_is_warned(arm_logs):
    """axis1 (f1 14.7 Hz) decimated to 100 Hz: eq. (29) asks far more."""
    log = arm_logs["axis1"]
    k = slice(None, None, 3)   # 350.87 / 3 = 117 Hz (no anti-alias: the chirp ends at 30 Hz)
    low = Log(t=log.t[k], q_m=log.q_m[k], tau_m=log.tau_m[k], q=log.q[k], q_ref=log.q_ref[k],
              meta={**log.meta, "sample_rate_hz": f"{log.sample_rate_hz / 3:.6g}"})
    result = identify(low, "joint-motor", f1_hz=14.68)
    assert any("too low for the mode" in w for w in result.warnings)


def test_no_resonance_is_warned():
    """A rigid axis (tau = J qdd + FV qd, q = q_m): no mode, the generic band, a warning."""
    rate, n = 350.87, 20000
    t = np.arange(n) / rate
    rng = np.random.default_rng(0)
    qm = np.cumsum(np.cumsum(rng.normal(0, 1e-3, n))) * 1e-3
    qm = qm - np.linspace(qm[0], qm[-1], n)
    qd = np.gradient(qm, 1 / rate)
    tau = 220 * np.gradient(qd, 1 / rate) + 300 * qd + rng.normal(0, 0.1, n)
    log = Log(t=t, q_m=qm, tau_m=tau, q=qm.copy(), meta={"sample_rate_hz": f"{rate}"})
    mode = measure_first_mode(log)
    assert not mode.found
    result = identify(log, "rigid")
    # a rigid model has no mode to miss: the fallback is stated as a note, not a warning
    assert result.warnings == ()
    assert any(w.startswith("no resonance found") for w in result.notes)
    assert (result.settings.Nd, result.settings.stencil) == (10, 5)
    c = choose_filter(log)
    assert c.settings == result.settings and c.warnings[0].startswith("no resonance found")
