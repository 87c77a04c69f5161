"""The asymmetric friction's physical check with the fit's own uncertainty: the jackknife
spread over the folds' fits (effects.base.spread) and the bound FS (1 +- a_c) >= 0 tested
against it (effects.asymmetric_friction.check, beyond)."""

from types import SimpleNamespace

import numpy as np
import pytest

from jointbench.identification.effects import asymmetric_friction as af
from jointbench.identification.effects.base import FOLD_FITS, spread


def test_spread_of_a_mean_is_its_standard_error():
    # k groups' leave-one-out means of group means x_i: the delete-a-group jackknife gives
    # exactly s / sqrt(k), s the sample standard deviation of the x_i.
    x = np.array([1.0, 3.0, 2.5, 4.0, 0.5, 2.0, 3.5, 1.5, 2.0, 3.0])
    k = len(x)
    folds = tuple({"m": (x.sum() - xi) / (k - 1)} for xi in x)
    assert spread(folds, lambda v: v["m"]) == pytest.approx(x.std(ddof=1) / np.sqrt(k))
    assert spread((), lambda v: v["m"]) == 0.0


def _rows():
    return SimpleNamespace(sig=SimpleNamespace(has_link=True))


def _values(a: float, fs: float, sd: float) -> dict:
    # theta = 0 and FS_ref = 1: the Coulomb part is a itself; ten folds whose excess
    # |a| - FSm spreads with the jackknife standard error sd
    k = 10
    dev = np.array([1.0, -1.0] * (k // 2))
    step = sd / np.sqrt((k - 1) / k * np.sum(dev ** 2))
    folds = tuple({"a": a + step * d, "FSm": fs} for d in dev)
    return {"a": a, "FSm": fs, "FS_ref": 1.0, "viscous_share": 0.0, FOLD_FITS: folds}


@pytest.mark.parametrize("over, physical", [(-1.0, True), (1.0, True), (af.CHECK_Z - 0.1, True),
                                            (af.CHECK_Z + 0.1, False), (10.0, False)])
def test_bound_allows_the_fit_own_uncertainty(over, physical):
    # a Coulomb part over FSm = 2 by `over` standard errors (sd 0.1)
    v = _values(2.0 + 0.1 * over, 2.0, 0.1)
    assert af.beyond(v, _rows()) == pytest.approx(over)
    assert (af.check(v, _rows()) == "") is physical


def test_without_folds_any_excess_is_unphysical():
    v = {"a": 2.01, "FSm": 2.0, "FS_ref": 1.0, "viscous_share": 0.0}
    assert af.beyond(v, _rows()) == np.inf
    assert "exceeds the fitted Coulomb friction" in af.check(v, _rows())
    assert af.check({**v, "a": 1.99}, _rows()) == ""


@pytest.mark.parametrize("over, physical", [(1.0, True), (af.CHECK_Z - 0.1, True),
                                            (af.CHECK_Z + 0.1, False)])
def test_joint_fit_checks_with_its_own_folds(over, physical):
    # The asymmetry's check in the joint fit with a cause named on top of it
    # (inverse._check, _still_physical) weighs the overshoot of its bound against that fit's
    # own fold fits, with the tolerance of the candidate's own check: a Coulomb part at its
    # bound, over FSm = 2 by noise of `over` standard errors (sd 0.1), stays an asymmetry.
    from jointbench.identification.discrepancy.candidates import Candidate
    from jointbench.identification.discrepancy.inverse import _check, _still_physical

    v = _values(2.0 + 0.1 * over, 2.0, 0.1)
    fixed = {"FS_ref": 1.0, "FV_ref": 1.0, "viscous_share": 0.0}
    first = Candidate("asymmetric_friction", True, fixed=fixed)
    then = Candidate("spring_damping", True, names=("a", "FSm", "D"),
                     X=(v["a"], v["FSm"], 0.5), base=(("asymmetric_friction", fixed),),
                     fold_fits=tuple({**f, "D": 0.5} for f in v[FOLD_FITS]))
    assert (_check(_rows(), first, then) == "") is physical
    assert _still_physical(_rows(), first, then) is physical
    assert (_check(_rows(), first, then) == af.check(v, _rows()))


@pytest.mark.parametrize("below_bar", [-2.0, -0.2, 0.2])
def test_joint_fit_near_its_bound_stays_the_offset_alternative(below_bar):
    # An asymmetry whose joint fit with the next round's cause overshoots its bound by more
    # than CHECK_Z but fewer than the round's bar of its standard errors (a Student t with
    # the ten folds' 9 degrees of freedom at alpha, inverse._beyond_bar) is not excluded as
    # a description (inverse._near, applied to the joint fit): it stays the
    # alternative of the offset it reduces to ("one of offset or asymmetric_friction"),
    # never against another effect, and beyond the bar it is left out.
    from jointbench.identification.discrepancy.candidates import Candidate
    from jointbench.identification.discrepancy.heldout import ALPHA
    from jointbench.identification.discrepancy.inverse import _beyond_bar, _near_bound

    alpha = ALPHA / 8   # a first round's Holm level
    over = _beyond_bar(alpha, 10) + below_bar   # standard errors beyond, all over CHECK_Z
    assert over > af.CHECK_Z
    v = _values(2.0 + 0.1 * over, 2.0, 0.1)
    fixed = {"FS_ref": 1.0, "FV_ref": 1.0, "viscous_share": 0.0}
    b = Candidate("asymmetric_friction", True, fixed=fixed, alpha=alpha)
    then = Candidate("spring_damping", True, names=("a", "FSm", "D"),
                     X=(v["a"], v["FSm"], 0.5), base=(("asymmetric_friction", fixed),),
                     fold_fits=tuple({**f, "D": 0.5} for f in v[FOLD_FITS]))
    after = ([then], "", None)
    assert _near_bound(_rows(), b, Candidate("offset", True), after) is (below_bar < 0)
    assert not _near_bound(_rows(), b, Candidate("gravity", True), after)


def test_beyond_bar_holds_its_level_for_a_jackknife_t():
    # a fit exactly at its bound: its excess over ten folds' jackknife standard error is a
    # Student t with 9 degrees of freedom; the tolerance _near and _near_bound allow must
    # exceed it with a chance of at most alpha (binomial sigma of the rate over n draws),
    # where the segment test's bar t_bar (more degrees of freedom) exceeds it far more often
    from jointbench.identification.discrepancy.heldout import t_bar
    from jointbench.identification.discrepancy.inverse import _beyond_bar

    rng = np.random.default_rng(7)
    k, n, alpha = 10, 200_000, 0.01
    x = rng.standard_normal((n, k))
    loo = (x.sum(axis=1, keepdims=True) - x) / (k - 1)
    se = np.sqrt((k - 1) / k * np.sum((loo - loo.mean(axis=1, keepdims=True)) ** 2, axis=1))
    z = x.mean(axis=1) / se
    sigma = np.sqrt(alpha * (1 - alpha) / n)
    assert np.mean(z > _beyond_bar(alpha, k)) == pytest.approx(alpha, abs=5 * sigma)
    assert np.mean(z > t_bar(alpha)) > alpha + 5 * sigma
