"""The segment test kept to the instants an effect's column acts on (identification.
discrepancy.heldout.evidence's `instants`, lag_band.engaged): the shares and the segments'
log-ratios are those of the kept instants, against their definition (no MuJoCo)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from jointbench.identification.discrepancy import heldout, lag_band

T = 800   # instants; two blocks stacked (motor, link)


def _errors(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """e0 on both blocks; e1 that halves e0 on the kept instants of the link block and leaves
    every other row as it is; the mask of kept instants (every other instant of the first
    half of the log)."""
    rng = np.random.default_rng(seed)
    e0 = rng.normal(size=2 * T)
    kept = np.zeros(T, bool)
    kept[: T // 2: 2] = True
    e1 = e0.copy()
    e1[T:][kept] *= 0.5
    return e0, e1, kept


def test_shares_and_ratios_are_those_of_the_kept_instants():
    e0, e1, kept = _errors(1)
    ev = heldout.evidence(e0, e1, T, (1,), None, kept)
    # the kept instants' errors halve: a quarter of their squared error is left
    assert np.isclose(ev.acts_pct, 75.0)
    # over both blocks' kept instants the motor block's are unchanged
    m, l = (float(np.sum(e0[b * T:(b + 1) * T][kept] ** 2)) for b in (0, 1))
    assert np.isclose(ev.explained_pct, 100 * 0.75 * l / (m + l))
    # only the segments holding kept instants are tested, each with log(4) (halved errors)
    assert ev.segments == heldout.SEGMENTS // 2
    keep = np.tile(kept, 2)
    l = heldout.segment_log_ratios(np.where(keep, e0, 0.0), np.where(keep, e1, 0.0), T, (1,))
    assert np.allclose(l, np.log(4.0))
    # over every instant the same change is diluted by the unchanged ones
    assert heldout.evidence(e0, e1, T, (1,)).acts_pct < ev.acts_pct


def test_engaged_instants_pass_their_folds_engagement():
    qm = np.linspace(-1.0, 1.0, T)
    sig = SimpleNamespace(qm=qm, q=np.zeros(T), index=np.arange(T))
    engagement = tuple(0.1 * (1 + f) for f in range(heldout.FOLDS))
    mask = lag_band.engaged(SimpleNamespace(sig=sig), engagement)
    fold = heldout.segment_of_rows(T) % heldout.FOLDS
    assert np.array_equal(mask, np.abs(qm) > np.asarray(engagement)[fold])
    assert lag_band.engaged(SimpleNamespace(sig=sig), ()) is None
