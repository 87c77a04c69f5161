"""The inverse view's fits as diagnose's searches form them (identification.discrepancy):
the held-out folds' fits of heldout.scores against least squares done directly on each
fold's training rows, and a torque lag's led columns (Nominal.columns with a lead) against
their definition, the led raw-rate column decimated (no MuJoCo)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import signal

from jointbench.identification.discrepancy import heldout
from jointbench.identification.discrepancy.nominal import _led, nominal
from jointbench.identification.discrepancy.signals import stack
from jointbench.identification.effects.base import hat, sign0
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log

N = 1600   # stacked rows: 800 instants, motor and link equations


def _design(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Folds as diagnose cuts them, a random design of 9 columns, y, row weights."""
    rng = np.random.default_rng(seed)
    folds = np.tile(heldout.segment_of_rows(N // 2) % heldout.FOLDS, 2)
    W = rng.normal(size=(N, 9)) * rng.uniform(0.01, 100.0, 9)   # badly scaled columns
    y = W @ rng.normal(size=9) + rng.normal(size=N)
    return folds, W, y, rng.uniform(0.5, 2.0, N)


def _lstsq(W: np.ndarray, y: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float]:
    """Weighted least squares on the given rows by QR (numpy's lstsq): X and the RSS."""
    X = np.linalg.lstsq(W * w[:, None], y * w, rcond=None)[0]
    return X, float(np.sum(((y - W @ X) * w) ** 2))


@pytest.mark.parametrize("case", ["plain", "dead column", "one fold's column"])
def test_fold_fits_are_least_squares_on_the_training_rows(case):
    folds, W, y, w = _design(7)
    if case == "dead column":
        W[:, 4] = 0.0          # a term the data does not excite: its parameter exactly 0
    elif case == "one fold's column":
        W[folds != 3, 5] = 0.0   # only fold 3's rows excite it: 0 in the fit without them
    nom = SimpleNamespace(weights=w, memo={})
    s = heldout.scores(nom, folds, y, W)
    # normal equations of the scaled design against QR: both backward stable, the design's
    # condition number once scaled is under 10, so they agree to ~1e-13 of the values; 1e-9
    # leaves room for any BLAS and still fails on a wrong fold, weight or scale (O(1) changes)
    live = np.any(W != 0, axis=0)
    X, rss = np.zeros(9), 0.0
    X[live], rss = _lstsq(W[:, live], y, w)
    assert s.X == pytest.approx(X, rel=1e-9, abs=1e-12)
    assert s.full == pytest.approx(rss, rel=1e-9)
    for f in range(heldout.FOLDS):
        train = folds != f
        on = live & np.any(W[train] != 0, axis=0)
        Xf = np.zeros(9)
        Xf[on], rss_f = _lstsq(W[train][:, on], y[train], w[train])
        assert s.fold_X[f] == pytest.approx(Xf, rel=1e-9, abs=1e-12)
        assert s.train[f] == pytest.approx(rss_f, rel=1e-9)
        held = (y[~train] - W[~train] @ Xf) * w[~train]
        assert s.errors[~train] == pytest.approx(held, rel=1e-9, abs=1e-12)
        assert s.held[f] == pytest.approx(float(held @ held), rel=1e-9)
    if case == "dead column":
        assert s.X[4] == 0.0 and np.all(s.fold_X[:, 4] == 0.0)
    if case == "one fold's column":
        # no information on it without fold 3: the minimum-norm fit's 0, to the SVD's rounding
        others = s.fold_X[np.arange(heldout.FOLDS) != 3, 5]
        assert abs(s.fold_X[3, 5]) <= 1e-12 * np.max(np.abs(others)) and np.all(others != 0)


def _two_mass_log(seconds: float = 20.0) -> Log:
    """A sweep on the motor, the link behind a deflection that follows the torque, a noisy
    torque: enough for the nominal's columns (their values are what is compared)."""
    t = np.arange(int(seconds * PAPER_RATE)) / PAPER_RATE
    qm = 0.1 * signal.chirp(t, 0.1, t[-1], 20.0) * signal.windows.tukey(len(t), 0.2)
    tau = (np.gradient(np.gradient(qm, t), t) + 0.3 * np.sign(np.gradient(qm, t))
           + np.random.default_rng(1).normal(0, 1e-2, len(t)))
    return Log(t=t, q_m=qm, tau_m=tau, q=qm - 1e-3 * tau, q_ref=qm,
               meta={"sample_rate_hz": f"{PAPER_RATE}"})


def test_led_columns_are_the_led_signals_decimated():
    nom = nominal(_two_mass_log(), FilterSettings(wn=176.0, m=4, Nd=26, ts=1 / PAPER_RATE))
    s = nom.sig
    col = {n: i for i, n in enumerate(nom.names)}
    scale = np.max(np.abs(nom.W), axis=0)
    for lead, deflection in ((2e-3, None), (5e-4, 0.9 * (s.qm - s.q)), (5e-4, None)):
        _, W, _ = nom.columns(deflection=deflection, lead=lead)
        dk = hat(s.qm - s.q if deflection is None else deflection)
        expected = {"K": stack(s, _led(s, dk, lead), -dk),
                    "Jm": stack(s, _led(s, s.qmdd, lead), None),
                    "FVm": stack(s, s.qmd + lead * s.qmdd, None),
                    "FSm": stack(s, _led(s, sign0(s.qmd), lead), None)}
        for name, x in expected.items():
            # the decimation is linear: dec(x + T x') and dec(x) + T dec(x') differ by rounding
            assert np.max(np.abs(W[:, col[name]] - x)) <= 1e-12 * scale[col[name]], name
        untouched = [i for n, i in col.items() if n not in expected]
        assert np.array_equal(W[:, untouched], nom.W[:, untouched])
