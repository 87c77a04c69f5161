"""Out-of-sample evidence for an effect: does adding it predict rows the fit
has not seen better, by more than this log's own spread?

**Folds.** The decimated instants are cut into SEGMENTS = 40 contiguous segments of equal
length (1.5 s of a 60 s log; the motor and link rows of an instant stay together), and segment
s belongs to fold s mod FOLDS (10 folds): every fold then spans the whole experiment, each
band of the chirp, in contiguous pieces much longer than the residual's correlation (the
band's impulse response, a few decimated rows). Contiguous folds would instead make every
held-out fold a frequency range no training row has: its error would be extrapolation, not
the effect. For each fold the reference design (the nominal model, or the nominal extended by
the causes already named) and the extended design are fitted on the other folds, with the
nominal's block weights, and predict the held-out rows: the weighted errors e0_i and e1_i. An
effect's nonlinear value (backlash width, lag time constant, ...) is chosen for each fold by
the training rows' RSS among the values its search evaluated, so the held-out rows do not
pick it.

**Statistic.** In each segment, the log-ratio of the held-out error sums,
l_s = log(sum e0^2 / sum e1^2) + log(1 - MATERIAL), and a one-sided t of their mean. The
segments are far apart in correlation terms, so the l_s are close to independent; as ratios
within a segment they do not depend on how loud the residual is there (the chirp makes it vary
by orders of magnitude from one band to the next). Their spread is measured by the mean
square successive difference (von Neumann 1941), sigma^2 = sum (l_{s+1} - l_s)^2 / (2 (S - 1)),
not by the spread around their mean: an effect acts where the chirp's band makes it visible
(a lag at the high frequencies, a ripple at low speed, a dead band at small deflection), so
its mean E[l_s] follows the sweep slowly from segment to segment, and the plain standard
deviation would count that variation as noise, capping t near sqrt(S f / (1 - f)) for an
effect seen in a share f of the segments, whatever its size. Successive differences cancel a mean that moves
slowly and keep the segment-to-segment noise; on independent l_s their estimate has the
variance of a chi-square with nu = 2 (S - 1)^2 / (3 S - 4) degrees of freedom (26 for S = 40),
which the p-value uses. The spread holds the noise, the residual's colour and the effect's own
uneven visibility within a segment as this log has them: no noise level, correlation time or
effect size is assumed. The sums run over the rows of the equations the effect's columns
change (identification.discrepancy.candidates.acts_in; segment_log_ratios): the rows of the
other equation carry the same errors in both models, up to the shared parameters' refit, and
only dilute each ratio towards 1. Under the null hypothesis (the effect's columns carry nothing the
reference misses) the extra columns only add estimation variance to the held-out prediction:
E[l_s] < 0 in every segment.

Successive differences also count as noise how an effect's visibility changes between
segments; a spread within each segment is not used instead, because once the true cause is
named, what its model misses is structured, and a within-segment spread calls it significant.

**Materiality.** On a 60 s log a test without margin finds mismatches that are real but
immaterial: dead bands at the encoder's resolution, MuJoCo's own small damping; they remove
0.1-3 % of the held-out residual. The margin log(1 - MATERIAL) asks the effect to remove
significantly more than MATERIAL = 5 % of what the reference misses in a typical segment (its
prediction then moves by more than a fifth of the residual's RMS, sqrt(0.05) = 0.22). It is a
share of this log's own residual, whatever its noise or scale, not a share of the torque.

**An engaging spring's units.** A hardening's column Kh dz(qm - q, d) is zero until the
deflection passes its engagement d (identification.effects.base.Effect.engages), and a sweep
passes d in a few segments only (near the mode), with a few decimated rows each there. Over
the segments the engaged ones' log-ratios jump from one to the next, which the successive
differences count as noise, and the others' dilute the mean: the t is capped by how many
segments the spring engages in, whatever it explains (half of the held-out residual with
t = 3.5 on a soft axis whose sweep passes the mode in its first seconds). Each engagement is
one observation of the second spring, so its test counts them apart (`engagement_units`): each
run of consecutive instants whose |qm - q| passes the engagement its fold's training rows chose,
within one segment that reaches it (`engagements`), is a unit, and the other instants of each
segment are one more, so that every row is counted once (what the spring's refit K changes
where it does not engage stays in the test). The segment test runs over the units' log-ratios
in time order, their number in its degrees of freedom (`over_engagements`). The units are set
by the positions and the training rows, never by the held-out residual, and two runs are a
decimated row or more apart, about the band's impulse response (the decimated cutoff is
about 0.8 of the decimated Nyquist frequency): their errors are close to independent, as the
segments' are, and under the null hypothesis each unit's log-ratio has a negative mean as a
segment's has. The shares stay those over every row.

**Rule.** An effect is significant when its one-sided p-value P(T_nu >= t) is under ALPHA / m,
m the number of effects its round tests (identification.discrepancy.inverse: Holm's step-down
Bonferroni), and it explains a positive share of the held-out residual over every row (the t
weighs every segment alike, the share every row by its error: an effect that helps the quiet
segments and costs the loud ones more has a large t and no share): on a log without any unmodelled effect the chance that any effect is named is at
most about ALPHA = 0.1 %, whatever the log's length, noise or sample rate. The level is set
from that rate alone. (With the 8 effects a log with q tests in the first round the bar is
t > 4.23, 7 in the second t > 4.18; 4 effects without q, t > 3.97.) A torque lag on a log
whose excitation runs above the chooser's band is tested in that wider band too, each of its
two tests at half its level (identification.discrepancy.lag_band: t > 4.50 in a first round
of 8); so is a hardening, its second test there over the segments of large deflection only,
and a backlash, its second test there over every segment.

Among the significant effects the named one explains the most of the held-out residual,
100 (1 - sum e1^2 / sum e0^2).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy import stats

from jointbench.identification.discrepancy.nominal import Nominal

FOLDS = 10
ALPHA = 1e-3
MATERIAL = 0.05
SEGMENTS = 40


def segment_of_rows(n: int) -> np.ndarray:
    """The segment (0 .. SEGMENTS-1) of each of n instants: contiguous, equal lengths."""
    return (np.arange(n) * SEGMENTS) // max(n, 1)


def fold_of_rows(nom: Nominal, k: int = FOLDS) -> np.ndarray:
    """The fold (0 .. k-1) of each stacked row: segment s belongs to fold s mod k, so that
    every fold spans the whole experiment (a chirp's every band) in contiguous pieces; both
    equation blocks of an instant alike."""
    n = len(nom.sig.index)
    return np.tile(segment_of_rows(n) % k, len(nom.y) // max(n, 1))


@dataclass(frozen=True)
class Scores:
    """One design's weighted RSS: on all rows, on each fold's training rows, held out."""

    full: float
    X: np.ndarray
    train: np.ndarray
    held: np.ndarray
    errors: np.ndarray       # each row's weighted held-out error (its fold's fit)
    fold_X: np.ndarray | None = None   # each fold's training fit, one row per fold


def scores(nom: Nominal, folds: np.ndarray, y: np.ndarray, W: np.ndarray) -> Scores:
    """Fit `y = W X` on all rows and on each fold's complement (the nominal's weights), by
    the normal equations of the column-scaled design (the Gram matrix, less the fold's for a
    fold fit): the designs are well conditioned once scaled (condition numbers 5 to 40 on
    the bench axes), and one small solve per fit is what makes the folds affordable (the
    fold fits in one batched solve). A column that is zero (a term the data does not excite,
    such as gravity on a horizontal axis) is not identifiable: its parameter is exactly 0, as
    in the nominal's `solve`, not the rounding of a minimum-norm solution."""
    A, b, scale = _scaled(nom, y, W)
    dead = ~np.any(A != 0, axis=0)
    order, bounds = _fold_order(nom, folds)
    As, bs = A[order], b[order]
    k = len(bounds) - 1
    # per fold (its rows contiguous in `order`): its Gram matrix, A^T b and b^T b; a fit on
    # the others subtracts them
    cuts = [slice(bounds[f], bounds[f + 1]) for f in range(k)]
    # (the right operand a copy: with two distinct operands numpy forms the general product,
    # the arithmetic of the fold's rows gathered on their own, not its symmetric rank-k
    # update, which rounds differently: the sums below, and the comparisons a search makes
    # of them, are the same to the last digit however the rows are gathered)
    grams = [(As[i].T @ As[i].copy(), As[i].T @ bs[i], float(bs[i] @ bs[i])) for i in cuts]
    G, c, bb = (sum(g[j] for g in grams) for j in range(3))
    # the fit on all rows by lstsq: a search's trials compare this RSS, to the last digit
    x = np.linalg.lstsq(G, c, rcond=None)[0]
    x[dead] = 0.0
    full = _rss(G, c, bb, x)
    Gs = G - np.stack([g[0] for g in grams])
    cs = c - np.stack([g[1] for g in grams])
    xs = np.zeros(cs.shape)
    live = ~dead
    xs[:, live] = _min_norm(Gs[:, live][:, :, live], cs[:, live])
    train = _rss_many(Gs, cs, bb - np.array([g[2] for g in grams]), xs)
    # each row by its fold's fit, in fold order, then back in row order
    errors = np.empty(len(b))
    errors[order] = np.concatenate([bs[i] - As[i] @ xs[f] for f, i in enumerate(cuts)])
    held = np.bincount(folds, errors * errors, minlength=k)
    return Scores(full=full, X=x / scale, train=train, held=held, errors=errors,
                  fold_X=xs / scale)


def _fold_order(nom: Nominal, folds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows sorted by fold (stable: each fold's rows in their order) and where each
    fold's rows start in that order (k + 1 bounds); kept on `nom` for these very folds."""
    kept = nom.memo.get("fold_order")
    if kept is not None and kept[0] is folds:
        return kept[1], kept[2]
    order = np.argsort(folds, kind="stable")
    bounds = np.r_[0, np.cumsum(np.bincount(folds, minlength=int(folds.max()) + 1))]
    nom.memo["fold_order"] = (folds, order, bounds)
    return order, bounds


# The smallest ratio of the Cholesky factor's diagonal entries (the pivots' square roots)
# at which a batch of normal equations is solved directly. The design is column-scaled, so a
# system near lstsq's cut (singular values under eps max(M, N), 2e-15, of the largest: a
# column almost dead on a fold's training rows, or almost a combination of the others) shows
# a pivot that small or fails the factorisation; away from it the direct solve and lstsq's
# SVD agree to rounding.
DIRECT = 1e-6


def _min_norm(G: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The minimum-norm solutions x of G x = c for a stack of symmetric positive
    semi-definite G (np.linalg.lstsq's, with its default cut: singular values under
    eps max(M, N) of the largest count as 0): one batched solve where every G is well
    conditioned (DIRECT), one batched SVD otherwise."""
    if G.shape[-1] == 0:
        return np.zeros(c.shape)
    try:
        d = np.diagonal(np.linalg.cholesky(G), axis1=-2, axis2=-1)
        if np.all(d.min(axis=-1) > DIRECT * d.max(axis=-1)):
            return np.linalg.solve(G, c[..., None])[..., 0]
    except np.linalg.LinAlgError:
        pass
    p = G.shape[-1]
    return (np.linalg.pinv(G, rcond=np.finfo(float).eps * p) @ c[..., None])[..., 0]


def _rss_many(G: np.ndarray, c: np.ndarray, bb: np.ndarray, x: np.ndarray) -> np.ndarray:
    """_rss of a stack of fits."""
    return bb - np.einsum("fi,fi->f", x, 2 * c - (G @ x[..., None])[..., 0])


def fitted_rss(nom: Nominal, y: np.ndarray, W: np.ndarray) -> float:
    """The weighted RSS of `y = W X` fitted on all rows, as `scores` fits it (normal
    equations of the scaled design). A scalar search needs no more: an SVD of the tall design
    costs 40 times more where BLAS threads compete for the cores (1.4 ms alone, 60 ms at a
    load of 8 on 2 cores, 4000 x 14)."""
    A, b, _ = _scaled(nom, y, W)
    G, c = A.T @ A, A.T @ b
    return _rss(G, c, float(b @ b), np.linalg.lstsq(G, c, rcond=None)[0])


def _scaled(nom: Nominal, y: np.ndarray,
            W: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The design and left-hand side with the nominal's row weights, the columns scaled to
    unit norm, and the scales."""
    w = nom.weights
    A, b = W * w[:, None], y * w
    scale = np.linalg.norm(A, axis=0)
    scale[scale == 0] = 1.0
    return A / scale, b, scale


def _rss(G: np.ndarray, c: np.ndarray, bb: float, x: np.ndarray) -> float:
    """||b - A x||^2 from the normal equations' terms: b^T b - 2 x^T A^T b + x^T A^T A x (the
    residual is a few % of b here, so the cancellation costs about 1e-13 of it)."""
    return float(bb - 2 * x @ c + x @ G @ x)


def preferred(records: list[Scores]) -> np.ndarray:
    """The trial (index into `records`) each fold's training rows prefer: least RSS."""
    return np.argmin(np.array([r.train for r in records]), axis=0)


def held_out(records: list[Scores], folds: np.ndarray) -> np.ndarray:
    """Each row's held-out error at the trial (of a searched effect) its fold's training rows
    prefer."""
    out = np.empty(len(folds))
    for f, j in enumerate(preferred(records)):
        rows = folds == f
        out[rows] = records[j].errors[rows]
    return out


@dataclass(frozen=True)
class Evidence:
    """The held-out comparison of an extended model with its reference."""

    explained_pct: float     # 100 (1 - sum e1^2 / sum e0^2): share of the held-out RSS removed
    t: float                 # t of the segments' log-ratios (MSSD spread), MATERIAL margin
    p: float                 # its one-sided p-value, dof(SEGMENTS) degrees of freedom
    acts_pct: float = float("nan")   # the share over the rows of the equations it acts in
    segments: int = SEGMENTS          # the segments its t is over (its degrees of freedom)


def evidence(e0: np.ndarray, e1: np.ndarray, n_times: int,
             blocks: tuple[int, ...] = (), within: np.ndarray | None = None,
             instants: np.ndarray | None = None) -> Evidence:
    """Segment test of e1 removing more than MATERIAL of e0's squared error (module
    docstring); rows are stacked by block, `n_times` instants each. The share is over every
    row; the test over the rows of `blocks` (the equations the effect acts in; () all).
    `within` (a mask over the SEGMENTS segments, None for all) keeps the test and both
    shares to those segments: a band of the log chosen without its residual (lag_band's
    large deflections). `instants` (a mask over the n_times instants, None for all) keeps
    them to those instants: where the effect's column is not zero (lag_band: a hardening's
    engaged spring), as `blocks` keeps them to the equations it acts in; elsewhere the two
    models differ only by the shared parameters' refit."""
    if instants is not None:
        keep = np.tile(np.asarray(instants, bool), len(e0) // n_times)
        e0, e1 = np.where(keep, e0, 0.0), np.where(keep, e1, 0.0)
    a0, a1 = (e ** 2 for e in (e0, e1))
    if within is not None:
        inside = np.tile(np.asarray(within, bool)[segment_of_rows(n_times)], len(a0) // n_times)
        a0, a1 = a0 * inside, a1 * inside
    share = _share(a0, a1)
    rows = list(blocks) if blocks else slice(None)
    acts = _share(a0.reshape(-1, n_times)[rows], a1.reshape(-1, n_times)[rows])
    l = segment_log_ratios(e0, e1, n_times, blocks, within)
    t, p = segment_t(l + np.log(1 - MATERIAL))
    return Evidence(explained_pct=share, t=t, p=p, acts_pct=acts, segments=len(l))


def _share(a0: np.ndarray, a1: np.ndarray) -> float:
    """100 (1 - sum a1 / sum a0), 0 when a0 sums to 0."""
    total0 = float(a0.sum())
    return 100 * (1 - float(a1.sum()) / total0) if total0 > 0 else 0.0


def segment_log_ratios(e0: np.ndarray, e1: np.ndarray, n_times: int,
                       blocks: tuple[int, ...] = (),
                       within: np.ndarray | None = None) -> np.ndarray:
    """log(sum e0^2 / sum e1^2) in each segment (where both are positive; of the segments
    `within` only, a mask over the SEGMENTS, when given), over the rows of `blocks` (every
    block for ()), in time order. An effect that acts in one equation is measured there:
    the other equation's errors, which it leaves as they were, would add the same amount to
    both sums and pull every ratio towards 1."""
    sq0, sq1 = ((e ** 2).reshape(-1, n_times) for e in (e0, e1))
    rows = list(blocks) if blocks else slice(None)
    h0, h1 = segment_sums(sq0[rows].sum(axis=0)), segment_sums(sq1[rows].sum(axis=0))
    ok = (h0 > 0) & (h1 > 0)
    if within is not None:
        ok &= np.asarray(within, bool)
    return np.log(h0[ok] / h1[ok])


def segment_sums(x: np.ndarray) -> np.ndarray:
    """Sums of x over SEGMENTS contiguous segments of equal length (segment_of_rows)."""
    return np.bincount(segment_of_rows(len(x)), x, SEGMENTS)


def large_deflections(nom: Nominal, engagement: tuple[float, ...]) -> np.ndarray:
    """The segments (a mask over heldout.SEGMENTS) whose largest |qm - q| on `nom`'s rows
    exceeds the engagement `engagement[f]` of their fold f = s mod FOLDS (lag_band: the
    hardening's view); none when the folds' values are not given."""
    sig = nom.sig
    if len(engagement) != FOLDS or sig.q is None:
        return np.zeros(SEGMENTS, bool)
    d = np.abs((sig.qm - sig.q)[sig.index])
    top = np.zeros(SEGMENTS)
    np.maximum.at(top, segment_of_rows(len(d)), d)
    return top > np.asarray(engagement, float)[np.arange(SEGMENTS) % FOLDS]


def engaged(nom: Nominal, engagement: tuple[float, ...]) -> np.ndarray | None:
    """The instants (a mask over `nom`'s rows of one block) whose |qm - q| exceeds the
    engagement `engagement[f]` of their fold f (large_deflections): where the hardening's
    column Kh dz(qm - q, d) is not zero; None when the folds' values are not given."""
    sig = nom.sig
    if len(engagement) != FOLDS or sig.q is None:
        return None
    d = np.abs((sig.qm - sig.q)[sig.index])
    return d > np.asarray(engagement, float)[segment_of_rows(len(d)) % FOLDS]


def engagements(nom: Nominal, engagement: tuple[float, ...]) -> np.ndarray | None:
    """Each of `nom`'s instants' engagement of the spring (module docstring: an
    engaging spring's units): 0, 1, ... for the maximal runs of consecutive engaged instants
    (`engaged`) within one segment that reaches the engagement (`large_deflections`), in
    time order, -1 elsewhere; None when the folds' values are not given."""
    on = engaged(nom, engagement)
    if on is None:
        return None
    seg = segment_of_rows(len(on))
    on &= large_deflections(nom, engagement)[seg]
    rows = np.flatnonzero(on)
    out = np.full(len(on), -1)
    starts = np.r_[True, (np.diff(rows) > 1) | (np.diff(seg[rows]) != 0)]
    out[rows] = np.cumsum(starts) - 1
    return out


def engagement_log_ratios(e0: np.ndarray, e1: np.ndarray, n: int, blocks: tuple[int, ...],
                          runs: np.ndarray | None) -> np.ndarray:
    """log(sum e0^2 / sum e1^2) over each engagement `runs` labels (engagements), over the
    rows of `blocks` (every block for ()), in time order; where both sums are positive (none
    when `runs` is None)."""
    if runs is None:
        return np.zeros(0)
    sq0, sq1 = ((e ** 2).reshape(-1, n) for e in (e0, e1))
    rows = list(blocks) if blocks else slice(None)
    on = runs >= 0
    k = int(runs.max()) + 1 if on.any() else 0
    h0 = np.bincount(runs[on], sq0[rows].sum(axis=0)[on], k)
    h1 = np.bincount(runs[on], sq1[rows].sum(axis=0)[on], k)
    ok = (h0 > 0) & (h1 > 0)
    return np.log(h0[ok] / h1[ok])


def engagement_units(nom: Nominal, engagement: tuple[float, ...]) -> np.ndarray | None:
    """A partition of `nom`'s instants into the units of an engaging spring's test (module
    docstring: an engaging spring's units): each engagement (`engagements`) one unit, the
    other instants of each segment one unit, labelled 0, 1, ... in the time order of their
    first instants; None when the folds' values are not given."""
    runs = engagements(nom, engagement)
    if runs is None:
        return None
    key = np.where(runs >= 0, SEGMENTS + runs, segment_of_rows(len(runs)))
    _, first, which = np.unique(key, return_index=True, return_inverse=True)
    rank = np.empty(len(first), int)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return rank[which]


def over_engagements(ev: Evidence, e0: np.ndarray, e1: np.ndarray, n: int,
                     blocks: tuple[int, ...], units: np.ndarray | None) -> Evidence:
    """`ev` (the evidence of e1 against e0 over `blocks`, n instants each) with its t and p
    over the `units` (engagement_units) instead of the segments: the segment test on their
    log-ratios in time order, their number its degrees of freedom; the shares stay `ev`'s."""
    l = engagement_log_ratios(e0, e1, n, blocks, units)
    t, p = segment_t(l + np.log(1 - MATERIAL))
    return replace(ev, t=t, p=p, segments=len(l))


def segment_t(l: np.ndarray) -> tuple[float, float]:
    """t of the mean of per-segment values l (in time order), their spread from successive
    differences (module docstring), and its one-sided p-value P(T_nu >= t); (0, 1) for fewer
    than 3 values."""
    k = len(l)
    if k < 3:
        return 0.0, 1.0
    sd = float(np.sqrt(np.sum(np.diff(l) ** 2) / (2 * (k - 1))))   # von Neumann's MSSD
    m = float(np.mean(l))
    t = m / (sd / np.sqrt(k)) if sd > 0 else (np.inf if m > 0 else 0.0)
    p = float(stats.t.sf(t, dof(k))) if np.isfinite(t) else (0.0 if t > 0 else 1.0)
    return t, p


def dof(k: int) -> float:
    """Degrees of freedom of the successive-difference variance of k independent values
    (von Neumann: var of the MSSD estimate = sigma^4 (3 k - 4) / (k - 1)^2)."""
    return 2.0 * (k - 1) ** 2 / (3 * k - 4)


def bar(m: int) -> float:
    """The p-value bar for one of m effects tested together (Bonferroni at ALPHA)."""
    return ALPHA / max(m, 1)


def t_bar(alpha: float, k: int = SEGMENTS) -> float:
    """The t value that p-value bar `alpha` corresponds to, for a test over k segments."""
    return float(stats.t.isf(alpha, dof(k)))
