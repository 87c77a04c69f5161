"""The model holding an asymmetric friction and an offset is the same whichever entered first
(identification.discrepancy.stacked.apply). While the motor moves the asymmetry's Coulomb part
is a constant torque; its design beside an offset keeps the (1 + a s) law's viscous-to-Coulomb
split (identification.effects.asymmetric_friction.design). An asymmetry whose search chose no
viscous part (theta = 0: the constant opposes the viscous part, which the law cannot hold) is
that constant alone, and an offset stacked after it found its own column there: the offset
tested on top of the asymmetry could add nothing, by construction (no MuJoCo)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from jointbench.identification.discrepancy.nominal import nominal
from jointbench.identification.discrepancy.stacked import stacked
from jointbench.identification.effects.base import sign0
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log

J, FV, FS = 0.5, 0.3, 0.3       # the rigid axis: [kg m^2], [N m s/rad], [N m]
OFFSET = -0.2                   # [N m], a constant opposing the asymmetry's viscous part
VISCOUS = 0.1                   # [N m s/rad], the asymmetry's viscous part a FV |qm'|


def _log(seconds: float = 20.0) -> Log:
    """A rigid axis swept in position, its torque J qm'' + FV qm' + FS sign qm' with an offset
    and a direction-dependent viscous torque of the other sign, and a noise."""
    t = np.arange(int(seconds * PAPER_RATE)) / PAPER_RATE
    qm = signal.chirp(t, 0.1, t[-1], 3.0) * signal.windows.tukey(len(t), 0.2)
    qmd = np.gradient(qm, t)
    tau = (J * np.gradient(qmd, t) + FV * qmd + FS * np.sign(qmd) + OFFSET
           + VISCOUS * np.abs(qmd) + np.random.default_rng(1).normal(0, 1e-2, len(t)))
    return Log(t=t, q_m=qm, tau_m=tau, q_ref=qm, meta={"sample_rate_hz": f"{PAPER_RATE}"})


@pytest.fixture(scope="module")
def nom():
    return nominal(_log(), FilterSettings(wn=176.0, m=4, Nd=26, ts=1 / PAPER_RATE))


def _fit(nom, effects) -> tuple[dict, float]:
    y, W, names = stacked(nom, effects).design()
    X = np.linalg.lstsq(W * nom.weights[:, None], y * nom.weights, rcond=None)[0]
    return dict(zip(names, X)), float(np.sum(((y - W @ X) * nom.weights) ** 2))


@pytest.mark.parametrize("theta", [0.0, 0.5, 1.0])
def test_either_order_is_one_model(nom, theta):
    # the friction the asymmetry scales, physical (a nominal fit of FV < 0 is not: stacked.
    # _richer_in)
    asym = ("asymmetric_friction", {"FV_ref": FV, "FS_ref": FS, "viscous_share": theta})
    offset = ("offset", {})
    moving = np.abs(sign0(nom.sig.qmd[nom.sig.index]))
    assert moving.all()   # the motor rests on no row: the Coulomb part is a constant there
    first, rss_first = _fit(nom, (offset, asym))
    after, rss_after = _fit(nom, (asym, offset))
    assert rss_after == pytest.approx(rss_first, rel=1e-9)
    assert after == pytest.approx(first, rel=1e-6, abs=1e-9)
    # both columns carry information, and the constant beside the asymmetry's viscous part is
    # the offset, within 4 of its standard errors (the weighted least squares' covariance,
    # sigma from the residual over the degrees of freedom)
    y, W, names = stacked(nom, (asym, offset)).design()
    assert np.linalg.matrix_rank(W) == W.shape[1]
    Xw = W * nom.weights[:, None]
    cov = rss_after / (len(y) - W.shape[1]) * np.linalg.inv(Xw.T @ Xw)
    g = np.zeros(len(names))
    g[names.index("offset")], g[names.index("a")] = 1.0, 0.5 * FS
    c, se = g @ [after[n] for n in names], float(np.sqrt(g @ cov @ g))
    assert abs(c - OFFSET) < 4 * se
