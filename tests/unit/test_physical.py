"""Unit tests of identification/physical.py: eq. (19) forward, then Table 3 and the weighted
inversion back (no MuJoCo). The forward relations are written here from the paper and the
ERRATA, independently of the module."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from jointbench.identification.estimate import LSResult
from jointbench.identification.parameters import (MOTOR_ONLY, MOTOR_ONLY_CORRECTED,
                                                  MOTOR_ONLY_PHYSICAL)
from jointbench.identification.physical import InversionError, invert_motor_only, table3

# Table 1's values (the paper's prototype, joint-motor model).
THETA = {"Jm": 174.7996, "K": 20341.0458, "JL": 47.4458, "FVm": 235.91, "FV": 83.1508,
         "FSm": 41.4254, "MX": -0.7241, "MY": -53.4201}


def forward(p: dict[str, float], g: float = 0.0, qc: float = 0.0) -> dict[str, float]:
    """X1..X11 of eq. (19) as the ERRATA reads it (X5 = Jm + JL + FV FVm / K), extended by
    the corrected model's terms; with gravity every link term is divided by
    c = 1 + g (MY cos qc - MX sin qc) / K (physical.py's docstring)."""
    Jm, K, JL, FVm, FV, FSm = (p[k] for k in ("Jm", "K", "JL", "FVm", "FV", "FSm"))
    c = 1.0 + g * (p["MY"] * np.cos(qc) - p["MX"] * np.sin(qc)) / K
    return {"X1": JL / (K * c), "X2": FV / (K * c), "X3": Jm * JL / (K * c),
            "X4": (Jm * FV + JL * FVm) / (K * c), "X5": Jm + (JL + FV * FVm / K) / c,
            "X6": FVm + FV / c, "X7": FSm, "X8": JL * FSm / (K * c),
            "X9": FV * FSm / (K * c), "X10": p["MX"] / c, "X11": p["MY"] / c}


def ls_result(X: dict[str, float], names: tuple[str, ...], rel_sigma: float = 1e-3) -> LSResult:
    """An LSResult holding X with independent relative standard deviations `rel_sigma`."""
    values = np.array([X[n] for n in names])
    sigma = rel_sigma * np.abs(values)
    return LSResult(names=names, X=values, sigma=sigma, cov=np.diag(sigma ** 2), sigma2=1.0,
                    residual=np.zeros(10), r=10, cond=1.0, unidentifiable=(), reasons={})


def test_eq_19_x5_is_the_errata_form():
    # The paper prints X5 = (Jm K + JL K + FV FVm) / K; the ERRATA: Jm + JL + FV FVm / K.
    X = forward(THETA)
    Jm, K, JL, FVm, FV = (THETA[k] for k in ("Jm", "K", "JL", "FVm", "FV"))
    assert X["X5"] == pytest.approx((Jm * K + JL * K + FV * FVm) / K, rel=1e-14)
    # X5 = Jm + X1 K + X2 FVm: the consistency relation between the seven X's.
    assert X["X5"] == pytest.approx(X["X3"] / X["X1"] + X["X1"] * K + X["X2"] * FVm, rel=1e-14)


def test_table3_returns_the_inputs():
    phys = table3(forward(THETA))
    assert set(phys) == set(MOTOR_ONLY_PHYSICAL)
    # Closed-form inversion of exact X's: rounding only (K = FV / X2 with FV = X6 - FVm
    # cancels about one digit, 1e-12 covers it).
    for name in MOTOR_ONLY_PHYSICAL:
        assert phys[name] == pytest.approx(THETA[name], rel=1e-12), name


def test_table3_uses_x5_nowhere():
    # ERRATA: Table 3 leaves X5 out; the seven X's over-determine the six parameters.
    X = forward(THETA)
    assert table3({**X, "X5": 1e6}) == table3(X)


def test_table3_on_the_papers_table_2_gives_its_table_3():
    # Table 2 prints X1 = 0.0021 and X2 = 0.0046 to two significant digits: X1's rounding
    # (0.00005 / 0.0021 = 2.4 %) carries into Jm = X3 / X1, and with X2's (1.1 %) into
    # FVm = (X4 - Jm X2) / X1 (2.4 % + 0.33 x 3.5 % = 3.6 %). FV = X6 - FVm cancels 93 % of
    # X6 and K = FV / X2 with it, so only Jm, FVm and FSm = X7 are checked.
    table2 = {"X1": 0.0021, "X2": 0.0046, "X3": 0.3554, "X4": 3.1739, "X5": 205.4558,
              "X6": 1246.5690, "X7": 5.1624}
    phys = table3(table2)
    assert phys["Jm"] == pytest.approx(172.1890, rel=0.025)
    assert phys["FVm"] == pytest.approx(1157.4716, rel=0.04)
    assert phys["FSm"] == 5.1624


def test_weighted_inversion_returns_the_inputs():
    X = forward(THETA)
    phys = invert_motor_only(ls_result(X, MOTOR_ONLY), g=0.0)
    assert phys.names == MOTOR_ONLY_PHYSICAL
    # A consistent X (chi2 = 0): Levenberg-Marquardt converges to the exact inputs; 1e-6
    # bounds its stopping tolerances (1e-8 on the scaled step).
    for name in MOTOR_ONLY_PHYSICAL:
        assert phys.value(name) == pytest.approx(THETA[name], rel=1e-6), name
    assert phys.chi2 < 1e-10
    assert np.all(np.isfinite(phys.sigma)) and np.all(phys.sigma > 0)
    assert phys.as_dict()["K"] == pytest.approx(THETA["K"], rel=1e-6)


def test_corrected_inversion_with_gravity_returns_the_inputs():
    g, qc = 9.81, 0.3
    X = forward(THETA, g=g, qc=qc)
    # Gravity stiffness G / K = -2.6 % on the prototype: the X's differ from eq. (19)'s.
    assert X["X1"] / forward(THETA)["X1"] == pytest.approx(1.026, abs=0.002)
    phys = invert_motor_only(ls_result(X, MOTOR_ONLY_CORRECTED), g=g, qc=qc)
    assert set(phys.names) == set(MOTOR_ONLY_PHYSICAL) | {"MX", "MY"}
    # Eleven X's, eight parameters, consistent: exact up to the solver's tolerance (1e-6).
    for name in phys.names:
        assert phys.value(name) == pytest.approx(THETA[name], rel=1e-6), name
    assert phys.chi2 < 1e-10


def test_weighted_inversion_sigma_shrinks_with_the_x_sigma():
    X = forward(THETA)
    wide = invert_motor_only(ls_result(X, MOTOR_ONLY, rel_sigma=1e-2))
    narrow = invert_motor_only(ls_result(X, MOTOR_ONLY, rel_sigma=1e-3))
    # Linear propagation: ten times smaller X sigmas give ten times smaller parameter sigmas
    # (the linearisation point is the same exact theta; 1e-4 covers the solver's tolerance).
    np.testing.assert_allclose(wide.sigma / narrow.sigma, 10.0, rtol=1e-4)


def test_table3_refuses_a_zero_or_insignificant_x1():
    X = forward(THETA)
    with pytest.raises(InversionError, match="X1"):
        table3({**X, "X1": 0.0})
    with pytest.raises(InversionError, match="X2"):
        table3({**X, "X2": float("nan")})
    with pytest.raises(InversionError, match="distinguishable from zero"):
        table3(X, sigma={"X1": X["X1"], "X2": 0.0})
    with pytest.raises(InversionError, match="not identified"):
        table3({k: v for k, v in X.items() if k != "X1"})


@pytest.mark.parametrize("name", ["X1", "X2", "X3", "X4", "X5", "X7"])
def test_weighted_inversion_needs_the_xs_it_starts_from(name):
    # The start reads X1..X5 and X7 (FVm from X4, FSm = X7): a dropped one is a stated
    # InversionError, not a KeyError from inside the inversion.
    X = forward(THETA)
    ls = ls_result(X, MOTOR_ONLY)
    dropped = dataclasses.replace(ls, unidentifiable=(name,),
                                  reasons={name: "its column is zero"})
    with pytest.raises(InversionError, match=f"{name} is not identified"):
        invert_motor_only(dropped)


def test_weighted_inversion_uses_x5():
    # Table 3 ignores X5; the weighted inversion fits all seven X's, so an X5 off by three of
    # its standard deviations leaves a misfit (chi2 > 0) and moves the estimate.
    X = forward(THETA)
    ls = ls_result(X, MOTOR_ONLY)
    shifted = dict(X, X5=X["X5"] * (1 + 3e-3))
    phys = invert_motor_only(ls_result(shifted, MOTOR_ONLY))
    assert 0.1 < phys.chi2 < 9.0
    assert table3(shifted) == table3(X)
    assert phys.value("K") != pytest.approx(invert_motor_only(ls).value("K"), rel=1e-6)
