"""An offset alone does not move the nominal (identification.discrepancy.nominal._with_bias):
a constant torque on the motor (eq. 6), -2.5 % of the torque limit on the bench prototype
without feedforward, with torque noise (30 s at the paper's rate, seed 3). Before, the
offset went into the motor rows' residual, their block weight fell thirtyfold and the
homogeneous link equation shrank as a whole: K, JL, FV, FS and P all about 0.3 times their
values on the same log without the offset (K = 6092 for 2.01e4 on a 40 s log)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.campaign.battery import BENCH_PLACES, BenchRunner
from jointbench.identification.discrepancy import nominal

NOMINAL = sys.modules["jointbench.identification.discrepancy.nominal"]   # the module
LINK = ("K", "JL", "FV", "FS", "P")   # the link equation's parameters (eq. 5)


@pytest.fixture(scope="module")
def logs():
    runner = BenchRunner(30.0)
    proto = next(p for p in BENCH_PLACES if p.model == "prototype")
    offset = -0.025 * runner.scales(proto)[0]
    clean = runner.log(proto, (), 3, False, True)
    shifted = runner.log(proto, (("offset", offset, {}),), 3, False, True)
    return clean, shifted, offset, runner.scales(proto)[2]


def sigmas(nom) -> dict[str, float]:
    """Standard deviations of the nominal's parameters from its own weighted fit (the motor
    constant beside them), white-noise approximation of the weighted residual."""
    Wb = NOMINAL._with_bias(nom.sig, nom.W)
    A = Wb * nom.weights[:, None]
    r = (nom.y - Wb @ np.r_[nom.X, nom.bias]) * nom.weights
    cov = (r @ r) / (len(r) - A.shape[1]) * np.linalg.pinv(A.T @ A)
    return dict(zip(nom.names, np.sqrt(np.diag(cov))))


def test_an_offset_alone_does_not_move_the_nominal(logs):
    clean, shifted, offset, K_true = logs
    s = diagnosis_settings(clean)[0]
    a, b = nominal(clean, s), nominal(shifted, s)
    sig = sigmas(a)
    for name in ("Jm", "FVm", "FSm") + LINK:
        # The same experiment, the same noise draw, plus a constant the integrator takes up:
        # the closed loop's path differs only where the quantised encoder rounds another way
        # (and another CPU's last bits move that too), so the fits agree within one sigma of
        # their own (two independent noise draws would differ by sqrt(2) sigma rms). A constant
        # left in the residual moves every one of them by 4 sigma (FSm) to 66 sigma (K).
        assert abs(b.value(name) - a.value(name)) < 1.0 * sig[name], name
    assert b.bias - a.bias == pytest.approx(offset, rel=0.02)   # tau_m holds the offset
    # and K is the spring's: -3.5 % here (noise, no feedforward: 3.8 of this white-noise
    # sigma, which the decimated rows' correlation makes too small); shrunk, -62 %
    assert a.value("K") == pytest.approx(K_true, rel=0.05)
    # the block weights: 1 / each block's spread, taken as far as the link equation's scale
    # allows (nominal.scale_weights), an exponent set where the shrink of K meets t times
    # its jackknifed standard error; that standard error, over 40 segments, is itself known
    # to about 1 / sqrt(2 * 39) = 11 %, so the two logs' exponents differ by a few % of the
    # weights' logarithm
    assert np.allclose(b.weights, a.weights, rtol=0.05)


def test_without_the_constant_the_link_equation_shrinks(logs, monkeypatch):
    clean, shifted, _, _ = logs
    s = diagnosis_settings(clean)[0]
    a = nominal(clean, s)
    sig = sigmas(a)
    monkeypatch.setattr(NOMINAL, "_with_bias",
                        lambda sig, W: np.column_stack([W, np.zeros(len(W))]))
    c = nominal(shifted, s)   # with the block weights' scale test (scale_shrunk)
    with monkeypatch.context() as mp:
        mp.setattr(NOMINAL, "scale_shrunk", lambda *args: False)
        b = nominal(shifted, s)   # without it
    ratios = [b.value(n) / a.value(n) for n in LINK]
    assert max(ratios) < 0.6 and np.ptp(ratios) < 0.1   # one scale, the link equation's
    assert a.value("K") - b.value("K") > 20 * sig["K"]
    # the test takes the weights only part of the way (scale_weights): the link rows'
    # weight relative to the motor rows' is less, and the link equation shrinks less
    assert c.weights[-1] / c.weights[0] < b.weights[-1] / b.weights[0]
    assert c.value("K") > b.value("K") + 20 * sig["K"]
