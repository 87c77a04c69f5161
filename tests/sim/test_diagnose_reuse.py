"""What `diagnose` reuses between the trials of its searches (issue 14: under 10 s per 60 s
log) gives exactly what computing again gives, bit for bit:

- the nominal columns of a lagged or dead-band state (stacked._core), the decimated columns an
  effect adds at a given value (stacked._added), both kept on the very Nominal they came from;
- a spring column's link row as the negative of its motor row (signals.stack);
- the fit on all rows of heldout.scores (what a search compares), against the per-fold
  loop; its held-out errors, every fold's fit in one batched solve, to rounding;
- the coupled-width refit's RSS from the normal equations (heldout.fitted_rss), against the
  SVD least squares to rounding.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.campaign.battery import Case, run_case
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.discrepancy import nominal
from jointbench.identification.discrepancy import stacked as st
from jointbench.identification.discrepancy.heldout import fitted_rss, fold_of_rows, scores
from jointbench.identification.discrepancy.signals import stack

TRIALS = (("backlash", {"backlash_rad": 2e-4}), ("hardening", {"deflection_rad": 1e-3}),
          ("hardening", {"deflection_rad": 2e-3}), ("torque_ripple", {"ripple_period_rad": 0.01}),
          ("torque_lag", {"lag_s": 2e-3}), ("spring_damping", {}))


@pytest.fixture(scope="module")
def log():
    # a prototype log with a lag (the state every later trial is built on) and a backlash
    return run_case(Case(0, "prototype", None, PAPER_RATE, 11, "backlash", 0.001),
                    duration=20.0)


def _designs(nom):
    """Every trial's design on top of a lagged state, each computed twice (the second from
    what the first left)."""
    base, _ = st.apply(st.Stacked(nom), "torque_lag", {"lag_s": 1e-3})
    return [st.apply(base, name, fixed)[1] for _ in range(2) for name, fixed in TRIALS]


def _nothing_reused(monkeypatch):
    monkeypatch.setattr(st, "_core", lambda s: (s.nom.y, s.nom.W, s.nom.names) if (
        s.tau is None and s.deflection is None and not s.lead) else
        s.nom.columns(s.tau, s.deflection, s.lead))
    monkeypatch.setattr(st, "_added", lambda nom, key: None)
    monkeypatch.setattr(st, "_keep_added", lambda nom, key, cols: None)


def test_reused_designs_are_the_designs(log, monkeypatch):
    settings, _ = diagnosis_settings(log)
    nom = nominal(log, settings)
    reused = _designs(nom)
    with monkeypatch.context() as m:
        _nothing_reused(m)
        fresh = _designs(nom)
    for a, b in zip(reused, fresh):
        assert a[2] == b[2] and np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    # another Nominal of the same log (same values, another object) reuses nothing of it
    other = nominal(log, settings)
    assert not other.memo and nom.memo["added"] and nom.memo["cores"]
    _designs(other)
    assert other.memo["added"].keys() == nom.memo["added"].keys()
    # a replaced copy (another weighting, say) starts with nothing kept
    assert not dataclasses.replace(nom, weights=2 * nom.weights).memo


def test_an_asymmetry_kept_beside_an_offset_is_not_reused_without_it(log, monkeypatch):
    """An asymmetric friction's design reads whether the base holds an offset (beside it, the
    reference's split, whatever its searched share): the columns kept for it beside an offset
    are not its columns without one. Without the offset, its column at a share 0 is the
    Coulomb part alone, FS_ref |sign qm'| (constant while the motor moves), as computed
    afresh; the split kept beside the offset carries a viscous part that the offset would
    then appear to complete."""
    settings, _ = diagnosis_settings(log)
    nom = nominal(log, settings)
    fixed = {"FV_ref": nom.value("FVm"), "FS_ref": nom.value("FSm"), "viscous_share": 0.0}
    beside, _ = st.apply(st.Stacked(nom), "offset", {})
    _, (_, W_beside, names) = st.apply(beside, "asymmetric_friction", fixed)
    _, (_, W_alone, _) = st.apply(st.Stacked(nom), "asymmetric_friction", fixed)
    with monkeypatch.context() as m:
        _nothing_reused(m)
        _, (_, fresh, _) = st.apply(st.Stacked(nom), "asymmetric_friction", fixed)
    assert np.array_equal(W_alone, fresh)
    sig = nom.sig
    coulomb = stack(sig, fixed["FS_ref"] * np.abs(np.sign(np.nan_to_num(sig.qmd))), None)
    assert np.allclose(W_alone[:, -1], coulomb, rtol=1e-12, atol=0.0)
    # beside the offset the column is another (the reference's split)
    assert names[-2:] == ("offset", "a") and not np.allclose(W_beside[:, -1], W_alone[:, -1])


def test_a_spring_columns_link_row_is_exactly_the_decimated_negative(log):
    settings, _ = diagnosis_settings(log)
    sig = nominal(log, settings).sig
    d = sig.qm - sig.q
    n = len(sig.index)
    col = stack(sig, d, -d)
    assert np.array_equal(col[n:], sig.dec(-d)) and np.array_equal(col[:n], sig.dec(d))
    # a link row that is not the negative is decimated on its own
    for link in (2 * d, d, np.abs(d)):
        assert np.array_equal(stack(sig, d, link)[n:], sig.dec(link))


def _scores_by_fold(nom, folds, y, W):
    """heldout.scores' fits as it computed them before, fold by fold (each fold's rows
    gathered, one lstsq per fit): the fit on all rows (X, weighted RSS) and the held-out
    errors."""
    w = nom.weights
    A, b = W * w[:, None], y * w
    scale = np.linalg.norm(A, axis=0)
    scale[scale == 0] = 1.0
    A = A / scale
    parts = [np.flatnonzero(folds == f) for f in range(int(folds.max()) + 1)]
    grams = [(A[i].T @ A[i], A[i].T @ b[i], float(b[i] @ b[i])) for i in parts]
    G, c, bb = (sum(g[j] for g in grams) for j in range(3))
    x = np.linalg.lstsq(G, c, rcond=None)[0]
    x[~np.any(A != 0, axis=0)] = 0.0
    errors = np.empty(len(b))
    for i, (Gf, cf, _) in zip(parts, grams):
        x_f = np.linalg.lstsq(G - Gf, c - cf, rcond=None)[0]
        errors[i] = b[i] - (A[i] * x_f).sum(axis=1)
    return x / scale, float(bb - 2 * x @ c + x @ G @ x), errors


def test_heldout_errors_in_one_pass_are_the_per_fold_ones(log):
    settings, _ = diagnosis_settings(log)
    nom = nominal(log, settings)
    folds = fold_of_rows(nom)
    for name, fixed in TRIALS:
        y, W, _ = st.apply(st.Stacked(nom), name, fixed)[1]
        s = scores(nom, folds, y, W)
        X, full, errors = _scores_by_fold(nom, folds, y, W)
        # the fit on all rows, whose RSS a search compares between trials: bit for bit
        assert np.array_equal(s.X, X) and s.full == full, name
        # the fold fits in one batched solve against lstsq one by one, on the same normal
        # equations (condition numbers under 1e3 here): both backward stable, the errors
        # agree to ~1e3 eps of the weighted torque; 1e-10 of it leaves room for any BLAS
        # and still fails on a wrong fold or scale
        b = y * nom.weights
        assert np.max(np.abs(s.errors - errors)) <= 1e-10 * np.max(np.abs(b)), name
        assert s.held == pytest.approx([s.errors[folds == f] @ s.errors[folds == f]
                                        for f in range(len(s.held))], rel=1e-12), name


def test_fitted_rss_is_the_least_squares_rss(log):
    settings, _ = diagnosis_settings(log)
    nom = nominal(log, settings)
    for name, fixed in TRIALS:
        y, W, _ = st.apply(st.Stacked(nom), name, fixed)[1]
        # the normal equations of the unit-norm columns (condition numbers under 1e3 here)
        # against the SVD: the same minimum to well under a millionth
        assert fitted_rss(nom, y, W) == pytest.approx(nom.fit(y, W)[1], rel=1e-7)
