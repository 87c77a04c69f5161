"""The hardening's view at large deflections counts the instants where both bands' fits of
a fold engage the spring (identification/discrepancy/lag_band.py, `engaged_in_both`): a
wide-band fit whose engagement sits below the spring's makes a unit of every half-cycle past
that lower value, where it predicts a torque the joint does not make; past the mode those
units are many and short and, counted one each, outnumber the loud engagements (no MuJoCo)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from jointbench.identification.discrepancy import heldout, lag_band

T = 2000            # instants; two blocks stacked (motor, link)
D_TRUE = 0.02       # the spring's engagement [rad], the chooser's band's fold values
D_WIDE = 0.01       # the wide band's fold values: engaged too early
KH = 1.0            # the second spring's stiffness (torque per rad)
SIGMA = 0.003       # the held-out errors' spread: the spring's torque at the mode is 0.1,
                    # the early fit's error between the two engagements up to 0.005


def _log() -> tuple[SimpleNamespace, np.ndarray]:
    """A deflection with a 12-row period whose amplitude decays from a mode passed early
    (0.12 rad) to below the true engagement: a long tail of half-cycles between the two
    engagements."""
    t = np.arange(T)
    amp = 0.12 * np.exp(-t / 150.0) + 0.015 * (t < T // 2)
    d = amp * np.sin(2 * np.pi * t / 12.0)
    sig = SimpleNamespace(qm=d, q=np.zeros(T), index=np.arange(T), sl=slice(None))
    return SimpleNamespace(sig=sig), d


def _dz(d: np.ndarray, b: float) -> np.ndarray:
    return np.sign(d) * np.maximum(np.abs(d) - b, 0.0)


def _view(chooser: float):
    nom, d = _log()
    rng = np.random.default_rng(7)
    true = KH * _dz(d, D_TRUE)
    # the wide fit: an earlier engagement with a softer spring, matched at the mode's peak
    soft = KH * (0.12 - D_TRUE) / (0.12 - D_WIDE)
    wide = soft * _dz(d, D_WIDE)
    noise = rng.normal(scale=SIGMA, size=2 * T)
    e0 = noise + np.r_[true, -true]               # the reference lacks the spring
    e1 = noise + np.r_[true - wide, wide - true]  # the wide band's hardening
    c = SimpleNamespace(fixed={"deflection_rad": chooser},
                        fold_values=(chooser,) * heldout.FOLDS)
    w = SimpleNamespace(fixed={"deflection_rad": D_WIDE}, fold_values=(D_WIDE,) * heldout.FOLDS,
                        reference_errors=e0, heldout_errors=e1, acts=(0, 1), unphysical="")
    return lag_band._deflection_view(nom, c, w, "wide band")


def test_engaged_in_both_is_the_later_engagement_of_each_fold():
    assert lag_band.engaged_in_both((0.02, 0.01), (0.01, 0.03)) == (0.02, 0.03)
    assert lag_band.engaged_in_both((), (0.01, 0.03)) == (0.01, 0.03)


def test_the_view_counts_where_both_bands_engage_the_spring():
    """The true spring removes most of the engaged rows' residual: its view passes the
    bar of the wide band's half of a first round of 8 effects, where counting the early
    fit's own engagements (the chooser's band at the wide band's value) gives the many
    short units between the two engagements a vote each, against it."""
    level = heldout.bar(8) / 2
    both = _view(D_TRUE)
    assert both.heldout_pct > 50 and both.p_heldout < level
    early = _view(D_WIDE)
    assert early.heldout_pct > 50 and early.t_stat < 0 < both.t_stat
    assert early.segments > 2 * both.segments   # the short units past the mode
