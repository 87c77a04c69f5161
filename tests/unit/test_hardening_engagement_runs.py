"""The hardening's view at large deflections counts engagements, not segments
(identification/discrepancy/lag_band.py, `engagements`, `engagement_log_ratios`): the runs of
engaged instants against their definition, and the view's p-value valid under the null
hypothesis on white errors (no MuJoCo); likewise the chooser's band's units, the segments
with each engagement apart (heldout.engagement_units)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from jointbench.identification.discrepancy import heldout, lag_band

T = 1200   # instants; two blocks stacked (motor, link)
D = 0.01   # every fold's engagement [rad]


def _nominal(deflection: np.ndarray) -> SimpleNamespace:
    sig = SimpleNamespace(qm=deflection, q=np.zeros(len(deflection)),
                          index=np.arange(len(deflection)))
    return SimpleNamespace(sig=sig)


def _sweep() -> np.ndarray:
    """A deflection that oscillates with a 12-row period and an amplitude above the
    engagement over the first 8 segments only (a mode passed early in the sweep)."""
    t = np.arange(T)
    amp = np.where(t < 8 * T // heldout.SEGMENTS, 0.03, 0.002)
    return amp * np.sin(2 * np.pi * t / 12.0)


def test_runs_are_the_engaged_stretches_within_a_segment():
    d = _sweep()
    nom = _nominal(d)
    runs = lag_band.engagements(nom, (D,) * heldout.FOLDS)
    on = np.abs(d) > D
    assert np.array_equal(runs >= 0, on)   # every engaged instant (the segments reach D)
    seg = heldout.segment_of_rows(T)
    rows = np.flatnonzero(on)
    for k in range(int(runs.max()) + 1):
        r = np.flatnonzero(runs == k)
        assert np.all(np.diff(r) == 1)              # contiguous
        assert len(set(seg[r])) == 1                # within one segment (one fold's fit)
    # a new run wherever the engaged instants break or a segment boundary cuts them
    breaks = 1 + np.sum((np.diff(rows) > 1) | (np.diff(seg[rows]) != 0))
    assert runs.max() + 1 == breaks
    # two half-cycles engaged in each 12-row period, over 8 segments of 30 rows each
    assert 35 <= breaks <= 45
    assert lag_band.engagements(nom, ()) is None


def test_log_ratios_per_engagement():
    d = _sweep()
    runs = lag_band.engagements(_nominal(d), (D,) * heldout.FOLDS)
    rng = np.random.default_rng(3)
    e0 = rng.normal(size=2 * T)
    e1 = e0.copy()
    e1[T:][runs >= 0] *= 0.5       # the link block's engaged rows: a quarter of the squares
    l = lag_band.engagement_log_ratios(e0, e1, T, (1,), runs)
    assert len(l) == runs.max() + 1 and np.allclose(l, np.log(4.0))
    both = lag_band.engagement_log_ratios(e0, e1, T, (), runs)
    assert np.all(both > 0) and np.all(both < np.log(4.0))   # the motor rows dilute


def test_the_view_is_valid_under_the_null():
    """White held-out errors and a hardening column that adds only its fold fits' estimation
    noise (one small coefficient per fold on the engaged instants): without the MATERIAL
    margin, the t over the engagements (their successive differences' spread, their number
    in its degrees of freedom) rejects at a nominal 5 % about 5 % of the time, as a valid
    test does on independent units; with the margin, as the view runs it, far less."""
    d = _sweep()
    runs = lag_band.engagements(_nominal(d), (D,) * heldout.FOLDS)
    column = np.where(np.abs(d) > D, np.abs(d) - D, 0.0) / 0.02
    fold = heldout.segment_of_rows(T) % heldout.FOLDS
    rng = np.random.default_rng(11)
    draws = 800
    plain = margin = 0
    for _ in range(draws):
        e0 = rng.normal(size=2 * T)
        c = rng.normal(scale=0.03, size=heldout.FOLDS)[fold]
        e1 = e0 + np.r_[-c * column, c * column]   # action and reaction
        l = lag_band.engagement_log_ratios(e0, e1, T, (0, 1), runs)
        plain += heldout.segment_t(l)[1] < 0.05
        margin += heldout.segment_t(l + np.log(1 - heldout.MATERIAL))[1] < 0.05
    sd = np.sqrt(0.05 * 0.95 / draws)   # a 5 % rate's binomial spread over the draws
    assert abs(plain / draws - 0.05) < 3 * sd
    assert margin / draws < 0.01


def test_a_view_over_the_engaged_rows_must_explain_a_material_share():
    """A hardening's view at large deflections (diluted) confirms only when it explains
    more than MATERIAL of its rows' held-out residual, whatever its t; a lag's wide view
    asks a positive share."""
    from jointbench.identification.discrepancy.candidates import SecondView
    share = 100 * heldout.MATERIAL
    seen = SecondView(band="wide, at large deflections", heldout_pct=2 * share, t_stat=9.0,
                      p_heldout=1e-9, value=0.02, agree=True, detail="", diluted=True)
    assert seen.confirms(1e-4)
    small = SecondView(**{**seen.__dict__, "heldout_pct": share / 2})
    assert not small.confirms(1e-4)
    assert SecondView(**{**small.__dict__, "diluted": False}).confirms(1e-4)


def test_the_chooser_band_units_are_the_segments_with_each_engagement_apart():
    """heldout.engagement_units: every instant in one unit, each engagement a unit of its
    own, the other instants of each segment one more, labelled in time order; and the
    segment test over them, without the MATERIAL margin, rejecting at a nominal 5 % at most
    about 5 % of the time under the null hypothesis on white errors (the rest of a segment
    then carries no refit: its log-ratio is 0)."""
    d = _sweep()
    nom = _nominal(d)
    runs = lag_band.engagements(nom, (D,) * heldout.FOLDS)
    units = heldout.engagement_units(nom, (D,) * heldout.FOLDS)
    seg = heldout.segment_of_rows(T)
    k = int(units.max()) + 1
    assert units.min() == 0 and k == int(runs.max()) + 1 + heldout.SEGMENTS
    for r in range(int(runs.max()) + 1):           # each engagement is a unit as it was
        u = units[runs == r]
        assert len(set(u)) == 1 and np.all(runs[units == u[0]] == r)
    for s in range(heldout.SEGMENTS):              # the rest of each segment one unit
        rest = (seg == s) & (runs < 0)
        assert len(set(units[rest])) == 1
    first = [int(np.flatnonzero(units == u)[0]) for u in range(k)]
    assert first == sorted(first)                   # in time order
    assert heldout.engagement_units(nom, ()) is None
    column = np.where(np.abs(d) > D, np.abs(d) - D, 0.0) / 0.02
    fold = seg % heldout.FOLDS
    rng = np.random.default_rng(5)
    draws, plain = 400, 0
    for _ in range(draws):
        e0 = rng.normal(size=2 * T)
        c = rng.normal(scale=0.03, size=heldout.FOLDS)[fold]
        e1 = e0 + np.r_[-c * column, c * column]
        plain += heldout.segment_t(lag_band.engagement_log_ratios(e0, e1, T, (0, 1),
                                                                  units))[1] < 0.05
    sd = np.sqrt(0.05 * 0.95 / draws)   # a 5 % rate's binomial spread over the draws
    assert plain / draws < 0.05 + 3 * sd
