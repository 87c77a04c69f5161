"""A second view of `torque_lag` in a band that reaches the excitation's top, of
`hardening` there at large deflections, and of `backlash` there over every segment.

**Why the lag alone.** A first-order lag T shifts the applied torque's phase by about w T:
its evidence grows with frequency, by physics. The chooser's band (identification.filter_choice:
decimated cutoff about 1.4 f1) keeps only the bottom of a sweep that runs far above the first
mode, so on a low-f1 axis a lag shows in the few segments of the chirp's top part (for a
5 ms lag on a 4 Hz axis swept to 30 Hz: 0.15 rad at the 5.4 Hz cutoff, 0.8 rad at the
sweep's top). The other effects act at low speed, small deflection or at the mode, which the
chooser's band holds, so only the lag gets a second band for its phase; the two kinks of the
spring law, a hardening's and a dead band's, get one for their harmonics (below).

**The band** is identification.band_choice.wide_settings's, as identify's band rule uses it:
the chooser's Butterworth, the decimation lowered until the decimated cutoff reaches the
least of the excitation's top measured on the log, the 5-point stencil's 1 % top and the
Butterworth's flat band; with the diagnosis's 3-point differences. The nominal is identified
again there, the causes named so far are applied with their values, and the lag is searched
and tested exactly as in the chooser's band (identification.discrepancy.heldout).

**The level.** The hypothesis "no lag" is then tested in two bands, and the two bands share
its level: each at alpha / 2 (Candidate.views, Candidate.level), alpha its Holm level in the
round (inverse: ALPHA / m, m the effects the round tests). That is Bonferroni within the
hypothesis: 2 min(p_chooser, p_wide) is a valid p-value for "no lag" whatever the two tests'
dependence, and Holm's step-down over the round's m hypotheses runs on it as on any other,
so on a log without an unmodelled effect the chance of naming one stays under ALPHA.
Counting the second test as an (m + 1)-th hypothesis would do as well, but would raise every
other effect's bar too; split within the lag, only the lag's own tests pay for the second
look: t > 4.50 in the chooser's band in a first round of 8 (4.23 without q, 4 effects). The
split is fixed by the log's band alone (the lag is tested in two bands whenever the log has a
wide band), never by what either test finds, so it holds even where the second view is not
run. The wide band's half is split again over its two tests (SecondView.split, WIDE_VIEWS),
over every segment and at the top of the sweep, each at alpha / 4 (weighted Bonferroni:
alpha / 2 + alpha / 4 + alpha / 4 = alpha), and the view reported is the one with the
smaller p.

**The top of the sweep.** A lag's evidence grows with frequency, and a sweep spends most of
its segments below the frequencies where the lag's phase w T is material: tested over every
segment, each of those carries the MATERIAL margin and nothing else, and a lag that removes
a third of the wide band's held-out residual, all of it at the sweep's top, can fail there.
So the wide band also tests it over the half of the segments where the lag's held-out
prediction changes most (`top_of_sweep`): the difference of the two fold fits' predictions
on the held-out rows, which their training rows and the held-out regressors set, never the
held-out torque. Under the null hypothesis that difference is estimation noise independent
of the held-out errors, E[e1^2] = E[e0^2] + E[(e0 - e1)^2] on every row, so the kept
segments' log-ratios have a negative mean as every segment's do (more negative where the
difference is largest), and the segment test counts their number in its degrees of freedom
(heldout.dof). The half is the median's split, set by no log. The test over every segment
stays beside it: an excitation that is not a sweep (a multisine holds every frequency in
every segment) shows its lag in segments that the size of the prediction's change need not
rank first, and there the view over every segment is the one that sees it.

**The guard.** The wide band also holds what the two-mass nominal misses up there (higher
modes of a real arm at 15-19 Hz, the sensors' and the sampling's own phase), and a lag column
takes up any phase the model lacks. A true lag is one time constant in every band; a phase
the model misses above the chooser's band pulls the wide band's T alone. So the wide view
only confirms (SecondView.confirms) a lag that the chooser's band fits physically with a
positive held-out share (Candidate.significant's other conditions), whose wide fit is
physical too, and whose two time constants agree: their difference within CONSISTENCY_Z
(band_choice's 3 sigma) of its root-sum-square spread, each spread the delete-a-fold
jackknife of the ten folds' preferred values (Candidate.fold_values), plus what the
discretisation of the lag's columns allows between the bands (`discretisation`): this log's
own statistics and the bands' numerics, no threshold set on a battery. (Root-sum-square
ignores that both bands fit the same log, which makes the difference's true spread smaller:
the agreement it asks is the lenient one; the level above does not rest on it.) The fold
spreads alone measure noise only, and on a quiet log they are a few tenths of a % of T,
while the led columns x + T x' are 3-point differences whose
gain sin(x)/x, x = w ts, falls with frequency (4 % at 28 Hz at the paper's rate): two bands
that see the lag at different frequencies may then differ by that share of T.

**Ranking** is unchanged: the candidates are ranked on the chooser's band's numbers (held-
out share, t), and the named lag's value and gain are the chooser's band's; the wide view
only decides whether the lag is significant.

**The hardening at large deflections.** A hardening, Kh dz(qm - q, d) beside K (effects.
hardening), acts only where the deflection passes its engagement d: near the mode, in the
few segments of the sweep whose deflection is largest, and there its evidence is in the
harmonics the kink makes, 3 f1 and above, which the chooser's band (about 1.4 f1) cuts. Over
every segment its evidence would be diluted twice: by the segments where the spring never
engages (their log-ratios carry the MATERIAL margin and nothing else), and by the few decimated
rows each engaged segment has (13 a segment on a 40 s log of a 2 Hz axis), whose log-ratios
then jump from one segment to the next, which the successive differences count as noise; so
the chooser's band's test counts each engagement apart (heldout: an engaging spring's units).
Its second view is in the wide band (more rows, the harmonics), over
the segments where the deflection reaches the engagement only (`large_deflections`): segment
s is kept when the largest |qm - q| on its rows exceeds the engagement that its fold's
training rows chose (Candidate.fold_values[s mod FOLDS]), a choice made from the positions and
the other folds, never from the held-out residual it is tested on; and within those segments
over the instants where |qm - q| passes that engagement only (`engaged`), where the column
Kh dz(qm - q, d) is not zero. Elsewhere the two models differ only by the shared parameters'
refit, as the other equation does for an effect that acts in one (heldout.segment_log_ratios):
those instants add nearly the same error to both sums and pull each segment's ratio towards 1
by a share that changes from segment to segment with how long the spring stays engaged, which
the successive differences count as noise. Under the null hypothesis the kept segments'
log-ratios have a negative mean as every segment's do (the column adds only estimation
variance, and it adds it on the very instants where the column is not zero). Its level is
split with the chooser's band's test, half each (t > 4.50 in either view over every segment
in a first round of 8; the wide band's one view keeps the whole half, where the lag's two
share it).

**The unit of the hardening's view: an engagement, not a segment.** The spring engages once
in each half-cycle of the deflection near the mode, and each engagement is one observation
of the second spring. Counted by segments, a low-f1 axis whose mode the sweep passes in its
first seconds has four that reach the engagement, and a t over four values has 2.25 degrees
of freedom (heldout.dof): at half the level of a second round of 7 it asks for t > 55,
however much the hardening explains (beside a ripple, 99 % of the held-out residual of the
engaged instants, with t = 31 over those four segments, fails). So the view's log-ratios are
taken over the engagements (`engagements`): each maximal run of consecutive engaged instants
within one segment that reaches the engagement (within one segment, so that one fold's fit
holds each run out), log(sum e0^2 / sum e1^2) over the equations the hardening acts in, and
the segment test (heldout.segment_t: the MATERIAL margin, the successive differences'
spread in time order, their number in its degrees of freedom) runs over those values. The
runs are set by the deflection and the folds' engagements, which the training rows chose,
never by the held-out residual. Two runs are apart by at least one decimated row where the
spring is not engaged, and the wide band's decimated cutoff is 0.8 of the decimated Nyquist
frequency (identification.band_choice.wide_settings: Nd = ceil(0.8 Fs / (2 top))), so its
impulse response spans a row or two: the runs' errors are close to independent, as the
segments' are. Under the null hypothesis each
run's log-ratio has a negative mean (the column adds only estimation variance there), so the
view's p-value stays valid, the two views' Bonferroni split keeps the chance of naming a
hardening that the log does not carry under the hypothesis' level, and Holm's step-down
keeps that of naming anything on a clean log under ALPHA (identification.discrepancy.
inverse).

**Where both bands engage the spring.** A hardening is one engagement in every band, but the
wide band places it loosely: the loud engagements at the mode, which hold most of its
residual, are fitted about as well by a lower engagement and a softer second spring, and its
folds' values spread over tens of mrad where the chooser's band's agree within one. A fold
whose wide fit engages the spring below where it engages makes a unit of every half-cycle
whose deflection passes that lower value, and past the mode the sweep's decaying deflection
makes many of them, a decimated row or two each, where the model puts a spring torque the
joint does not make: counted one each they outnumber the loud engagements, and the view can
explain two thirds of its rows' held-out residual with a negative t. So an instant counts as
engaged when both bands' fits of its fold put it past their engagement (`engaged_in_both`:
the larger of the two fold values, each chosen by the fold's training rows); below the wide
band's own value the column is zero and the instants carry only the refit, as before. The
units stay set by the positions and the training rows, never by the held-out residual, and
the view's p-value stays valid under the null hypothesis.

The guard differs from the lag's. The wide view confirms only a hardening that the chooser's
band fits physically (its overall share there need not be positive: beside a backlash the
chooser's band, without the harmonics, lets a wider dead band and a stiffer K take the
hardening's part, and the share it adds is lost in the refit), whose wide fit is physical too,
and whose two engagements agree within CONSISTENCY_Z of their jackknife spreads' root-sum-
square plus the search grid's step at the engagement (`grid_step`), what a search on a
geometric grid can tell apart (the fold values are the search's trials, and every fold may
prefer the same one). And the wide fit's engagement must lie beyond the first step of its
grid (hardening.grid: from 2 % of the 99th percentile of |qm - q|): engaged there, Kh dz(d, d0)
is Kh d - Kh d0 sign(d) on nearly every row, a stiffness and a sign of the deflection, not a
spring that engages at large deflections, and in the wide band such a column takes up what the
nominal and a named cause miss above the chooser's band (beside a spring damping whose value
the wide band refits, it explained a fifth of the residual of the segments it covered, most of
them). Such a fit is not a physical instance of the effect: SecondView.unphysical says why.
Last, the view must explain more than MATERIAL of the held-out residual of the rows it is
over (SecondView.confirms, `diluted`): it tests the typical engagement, and a column that
fits a small misfit in the many quiet engagements of a spring engaged near its grid's
bottom can pass there while the rows keep their residual (beside a lag on the soft family,
0.6 % of it with t = 4.2 over 44 engagements); the floor of later rounds asks the same.

**The backlash in the wide band.** A dead band K dz(qm - q, b) is a kink of the spring law
at the band's edges, crossed at every link-torque reversal, and like a hardening's kink its
evidence is in the harmonics it makes, which the chooser's band cuts; what that band keeps of
it, the fundamental, is mostly a softer K. On an axis whose sweep passes the mode early (the
soft family, f1 4 Hz) the deflection leaves the band in the log's first few segments only,
with a dozen decimated rows each: tested over every segment of the chooser's band, a dead
band of 7 % visibility that removes four fifths of the held-out residual has t = 2.9, and
in the wide band, with its harmonics and three times the rows, t = 13. Its second view is the
wide band's own test of it, over every segment (the segments that the deflection never
takes out of the band carry the MATERIAL margin in both bands alike: a view over the others
only would ask a t for a handful of segments, heldout.dof). Its level is split with the
chooser's band's test, half each, as the hardening's. The guard is the lag's, with a share
above MATERIAL: the wide view only confirms a backlash that the chooser's band fits physically
and that removes more than MATERIAL of the chooser's band's held-out residual, over the whole
log, over the rows its test reads (Candidate.own_test: the link equation, for a second cause
of the spring law) and in its typical segment (the segment test's t > 0, short of its bar):
what a dead band removes in the wide band, its fundamental removes in part in the chooser's
band. A dead band that makes the link equation's held-out residual worse in the chooser's
band (its typical segment better, the few segments at the mode much worse) is not a kink of
the spring law seen in both bands but a column that takes up the misfit of the cause of the
law named before it (a hardening's), and the wide band, with that misfit's harmonics, can
then credit it with a large share. Beside a
spring damping whose value the wide band refits, a dead band of a fraction of a mrad took up
a tenth to a half of the wide band's residual where the chooser's band's segments saw less
than MATERIAL of theirs (t = -9.9 and -0.8). Its wide fit must be physical too, and the
two widths agree within CONSISTENCY_Z of their jackknife spreads' root-sum-square plus the
width grid's step there (identification.effects.backlash.grid_step): a dead band is one
width in every band, while a phase or a mode the nominal misses above the chooser's band pulls
the wide band's width alone.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from jointbench.identification.band_choice import CONSISTENCY_Z, wide_settings
from jointbench.identification.discrepancy.candidates import (CHOOSER, OWN_ROWS, Candidate,
                                                              SecondView, candidate,
                                                              reference)
from jointbench.identification.discrepancy.heldout import (MATERIAL, SEGMENTS, engaged,
                                                           engagement_log_ratios, engagements,
                                                           evidence, large_deflections,
                                                           segment_of_rows, segment_t)
from jointbench.identification.discrepancy.nominal import Nominal, nominal
from jointbench.identification.effects import EFFECTS, backlash
from jointbench.identification.filtering import FilterSettings, stencil_gain
from jointbench.identification.log import Log

LAG = "torque_lag"
HARDENING = "hardening"
WIDE_VIEWS = 2   # the lag's tests in the wide band (every segment, the top of the sweep)


class LagBand:
    """The wide band of one log (None when the chooser's band already reaches the
    excitation's top, or no top is found) and its nominal, identified on first use."""

    def __init__(self, log: Log, settings: FilterSettings, link_friction: bool = True,
                 limit_applied: bool = False):
        wide, _, why = wide_settings(log, settings)
        self.settings = None if wide is None else replace(wide, stencil=settings.stencil)
        self.label = "" if wide is None else (
            f"wide band (Nd {wide.Nd}, decimated cutoff {wide.decimated_cutoff_hz:.3g} Hz: "
            f"{why})")
        self._log, self._link_friction, self._limit = log, link_friction, limit_applied
        self._nominal: Nominal | None = None

    def nominal(self) -> Nominal:
        if self._nominal is None:
            self._nominal = nominal(self._log, self.settings, self._link_friction,
                                    self._limit)
        return self._nominal

    def release(self) -> None:
        """Drop the wide band's kept decimations (Signals.release)."""
        if self._nominal is not None:
            self._nominal.sig.release()


def jackknife(values: tuple[float, ...]) -> float:
    """The delete-a-group jackknife's standard error of an estimate from the k fold fits'
    values (each on all folds but one): sqrt((k - 1) / k sum (v_f - mean)^2); inf for none."""
    v = np.asarray(values, float)
    if len(v) < 2:
        return math.inf
    return float(np.sqrt((len(v) - 1) / len(v) * np.sum((v - v.mean()) ** 2)))


def discretisation(settings: FilterSettings, lag_s: float) -> float:
    """The share of a lag T [s] by which its fits in two bands may differ through the led
    columns' 3-point differences (nominal._led): |T| (1 - sin(x) / x), x = 2 pi fc ts at the
    wide band's decimated cutoff fc, the derivative's relative error at the band's top."""
    x = 2 * math.pi * settings.decimated_cutoff_hz * settings.ts
    return abs(lag_s) * (1.0 - float(stencil_gain(x, 3)))


def engaged_in_both(chooser: tuple[float, ...], wide: tuple[float, ...]) -> tuple[float, ...]:
    """Each fold's engagement for the hardening's view (module docstring: where both bands
    engage the spring): the larger of the chooser's band's and the wide band's fold values,
    both chosen by that fold's training rows; the wide band's alone when the chooser's are
    not given fold by fold."""
    if len(chooser) != len(wide):
        return tuple(wide)
    return tuple(max(float(a), float(b)) for a, b in zip(chooser, wide))


def grid_step(nom: Nominal, value: float) -> float:
    """The step of the hardening's geometric search grid on `nom`'s rows at `value`:
    |value| (r - 1), r the grid's ratio."""
    g = EFFECTS[HARDENING].grid(nom)
    return abs(value) * (float(g[1] / g[0]) - 1.0) if len(g) > 1 and g[0] > 0 else 0.0


def second_view(band: LagBand, c: Candidate,
                causes: tuple[tuple[str, dict], ...], split: int = 1) -> Candidate:
    """`c` itself unless it is a torque lag, a hardening or a backlash and the log has a wide
    band; then
    `c` with its level split over its two bands (Candidate.views = 2) and, when the chooser's
    band fits it physically with a positive held-out share but does not find it significant
    at that level, the wide band's view (Candidate.second): the lag's over every segment and
    at the top of the sweep, the two sharing the band's level (SecondView.split), the
    hardening's over its large deflections, the backlash's over every segment (module
    docstring). `causes`: the named causes
    with their values (the round's reference). `split`: the views the hypothesis is split
    over besides the two bands (a clipped log's two inverse views, bench.analysis.diagnose.
    clipped): each band's test is then at alpha / (2 split), and the wide band's view is
    run whenever the chooser's band fails at that level."""
    view = EFFECTS[c.effect].wide_view if c.effect in EFFECTS else ""
    if not view or band.settings is None or not c.testable:
        return c
    c = replace(c, views=c.views * 2 * split)   # its rows' views besides (Candidate.views)
    # a lag must show a positive share in the chooser's band, a backlash one above MATERIAL
    # overall, over the rows its test reads and in a typical segment (t > 0); a hardening's
    # share there may be lost to a cause beside it (module docstring: the guard)
    shown = {"deflection": True,
             "width": min(c.heldout_pct, c.own_test.own_share) > 100 * MATERIAL
             and c.t_stat > 0}.get(view, c.heldout_pct > 0)
    if c.unphysical or c.significant or not shown:
        return c
    try:
        nom = band.nominal()
        w = candidate(nom, c.effect, reference(nom, causes))
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return c   # no second view (LogError is a ValueError: too short for the band)
    if view == "deflection":
        return replace(c, second=_deflection_view(nom, c, w, band.label))
    if view == "width":
        return replace(c, second=_width_view(nom, c, w, band.label))
    tc, tw = c.fixed["lag_s"], w.fixed["lag_s"]
    sc, sw = jackknife(c.fold_values), jackknife(w.fold_values)
    allowed = CONSISTENCY_Z * math.hypot(sc, sw) + discretisation(band.settings, tc)
    agree = abs(tw - tc) <= allowed
    detail = (f"lag {1e3 * tw:.3g} +- {1e3 * sw:.2g} ms against {1e3 * tc:.3g} +- "
              f"{1e3 * sc:.2g} ms in the chooser's band, "
              + ("within" if agree else "more than") + f" the {1e3 * allowed:.2g} ms allowed "
              f"({CONSISTENCY_Z:g} sigma and the columns' discretisation)")
    n = len(nom.sig.index)
    top = top_of_sweep(w, n)
    ev = evidence(w.reference_errors, w.heldout_errors, n, w.acts, top)
    every = (f"{band.label}, over every segment", w.heldout_pct, w.t_stat, w.p_heldout,
             w.acts_pct, SEGMENTS)
    upper = (f"{band.label}, at the top of the sweep ({ev.segments} of {SEGMENTS} segments)",
             ev.explained_pct, ev.t, ev.p, ev.acts_pct, ev.segments)
    # the two wide tests share the wide band's half of the level (module docstring: the
    # level); the view reported is the one with the smaller p, the other is in the detail
    best, other = (every, upper) if every[3] <= upper[3] else (upper, every)
    detail += (f"; {other[0]}: held out {other[1]:.3g} %, t = {other[2]:.3g} "
               f"(p = {other[3]:.2g})")
    label, share, t, p, acts, segments = best
    return replace(c, second=SecondView(
        band=label, heldout_pct=share, t_stat=t, p_heldout=p, value=tw, agree=agree,
        detail=detail, unphysical=w.unphysical, acts_pct=acts, segments=segments,
        split=WIDE_VIEWS))


def top_of_sweep(w: Candidate, n: int) -> np.ndarray:
    """The segments (a mask over heldout.SEGMENTS) where the lag's held-out prediction
    changes most (module docstring: the top of the sweep): the upper half by the sum over
    the segment's motor rows (the first of `n` instants) of (e0 - e1)^2, e0 and e1 the
    reference's and the lag's held-out errors. e0 - e1 is the difference of the two fold
    fits' predictions on the held-out rows, a function of the training rows and the
    held-out regressors, not of the held-out torque."""
    d = (w.reference_errors - w.heldout_errors)[:n]
    size = np.bincount(segment_of_rows(n), d * d, minlength=SEGMENTS)
    return size >= np.median(size)


def _deflection_view(nom: Nominal, c: Candidate, w: Candidate, label: str) -> SecondView:
    """The hardening `w` fitted in the wide band (`nom`), its held-out errors tested against
    its reference's over the segments of large deflection only (large_deflections), its
    engagement against the chooser's band's `c`, and not a physical hardening at large
    deflections when that engagement is in the first step of its search grid (module
    docstring: the guard)."""
    at = engaged_in_both(c.fold_values, w.fold_values)
    within = large_deflections(nom, at)
    n = len(nom.sig.index)
    ev = evidence(w.reference_errors, w.heldout_errors, n, w.acts, within, engaged(nom, at))
    # the segment test over the engagements of the spring, not the segments they lie in
    runs = engagements(nom, at)
    l = engagement_log_ratios(w.reference_errors, w.heldout_errors, n, w.acts, runs)
    t, p = segment_t(l + math.log(1 - MATERIAL))
    dc, dw = c.fixed["deflection_rad"], w.fixed["deflection_rad"]
    sc, sw = jackknife(c.fold_values), jackknife(w.fold_values)
    allowed = CONSISTENCY_Z * math.hypot(sc, sw) + grid_step(nom, max(dc, dw))
    agree = abs(dw - dc) <= allowed
    g = EFFECTS[HARDENING].grid(nom)
    edge = (f"engagement {1e3 * dw:.3g} mrad in the first step of its search grid "
            f"({1e3 * g[0]:.3g} to {1e3 * g[1]:.3g} mrad): a stiffness and a sign of the "
            "deflection, not a spring engaging at large deflections") if dw < g[1] else ""
    detail = (f"engagement {1e3 * dw:.3g} +- {1e3 * sw:.2g} mrad against {1e3 * dc:.3g} +- "
              f"{1e3 * sc:.2g} mrad in the chooser's band, "
              + ("within" if agree else "more than") + f" the {1e3 * allowed:.2g} mrad allowed "
              f"({CONSISTENCY_Z:g} sigma and the search grid's step)")
    label = (f"{label}, at large deflections ({int(within.sum())} of {SEGMENTS} segments "
             f"reach the engagement, {len(l)} engagements)")
    return SecondView(band=label, heldout_pct=ev.explained_pct, t_stat=t, p_heldout=p,
                      value=dw, agree=agree, detail=detail,
                      unphysical="; ".join(x for x in (w.unphysical, edge) if x),
                      acts_pct=ev.acts_pct, diluted=True, segments=len(l))


# The effects seen at the mode (Effect.at_the_mode: the dead band, the spring's damping)
# have a view where they are visible (`where_visible`) beside another effect of the spring.
VISIBLE_VIEWS = 2   # their tests against such a model: every segment, where it is visible


def _spring(name: str, at_the_mode: bool = False) -> bool:
    """Whether the effect `name` acts in the spring's law or damping (Effect.in_spring),
    and, with `at_the_mode`, is seen where the sweep passes the mode (Effect.at_the_mode)."""
    e = EFFECTS.get(name)
    return e is not None and e.in_spring and (e.at_the_mode or not at_the_mode)


def where_visible(c: Candidate, n: int, model: tuple[tuple[str, dict], ...]) -> Candidate:
    """`c` itself unless it is seen at the mode (Effect.at_the_mode: a backlash, a spring
    damping) and `model` holds another effect of the spring's law or damping
    (Effect.in_spring); then `c` with its level split
    over two views (Candidate.views), every segment and the half where its held-out
    prediction changes most (`changed_most`), the second as its SecondView.

    The weaker effect of a pair is tested against the model holding the stronger, and a
    sweep shows a dead band or a spring damping where it swings the deflection and its rate:
    near the mode, a few of the 40 segments (on a soft axis the chirp's first seconds). Once
    the stronger cause is in the model, the other segments' residual is what the numerics
    leave, and there the candidate's refit moves the held-out prediction by a share of that
    small residual that varies from one segment to the next: their log-ratios carry the
    MATERIAL margin and that noise, and the successive differences count the jump between
    the few segments of the mode and the rest as noise too. A dead band that removes 96 % of
    the held-out residual on top of a spring damping, all of it near the mode, then fails
    over every segment. The half of the segments where its prediction changes most holds the
    mode, and the test there is the lag's at the top of the sweep (module docstring): that
    change is the difference of the two fold fits' predictions on the held-out rows, set by
    their training rows and the held-out regressors, never by the held-out torque; under the
    null hypothesis the kept segments' log-ratios have a negative mean as every segment's
    do, and the segment test counts their number in its degrees of freedom. The split is
    fixed by the effect and the round (a model holding a cause), never by what either view
    finds: each view at half the level (Bonferroni within the hypothesis), so the chance of
    naming an effect the log does not carry stays under the round's level. A backlash whose
    level second_view has already split over its two bands has it split again here (each of
    its three tests at a quarter of the level), and keeps the wide band's view when that one
    confirms. Against the
    nominal (the first round) the stronger of a pair is tested as every effect is, over every
    segment: the view is for the weaker, against the model holding the stronger.

    Only beside another effect of the spring's law or damping, which acts where the sweep
    swings the deflection as the candidate does: against a model holding a motor-side cause
    (a torque lag, whose evidence and residual misfit sit at the top of the sweep), the half
    where a dead band's prediction changes most is where that cause's own misfit is, and a
    dead band takes it up there (a single lag on the prototype: a third of that half's
    held-out residual). The view would then test the first cause's misfit, not a second
    effect."""
    if (not _spring(c.effect, at_the_mode=True) or not c.testable
            or not any(_spring(name) for name, _ in model)):
        return c
    c = replace(c, views=c.views * VISIBLE_VIEWS)
    if (c.unphysical or not c.heldout_pct > 0 or c.heldout_errors is None
            or c.reference_errors is None):
        return c
    rows = (EFFECTS[c.effect].block,) if c.rows == OWN_ROWS else c.acts
    keep = changed_most(c, n, rows)
    ev = evidence(c.reference_errors, c.heldout_errors, n, rows, keep)
    value = next(iter(c.fixed.values()), math.nan) if c.fixed else math.nan
    label = (f"{CHOOSER}{', ' + c.rows if c.rows else ''}, where it is visible ({ev.segments} "
             f"of {SEGMENTS} segments: its held-out prediction changes most)")
    if c.second is not None and c.second.confirms(c.level):
        return c   # the wide band's view (second_view) confirms it at the split level
    return replace(c, second=SecondView(
        band=label, heldout_pct=ev.explained_pct, t_stat=ev.t, p_heldout=ev.p,
        value=float(value), agree=True, detail="the chooser's band's fit, its segments where "
        "the held-out prediction changes most", acts_pct=ev.acts_pct, segments=ev.segments))


def changed_most(c: Candidate, n: int, rows: tuple[int, ...] = ()) -> np.ndarray:
    """The segments (a mask over heldout.SEGMENTS) where `c`'s held-out prediction changes
    most: the upper half by the sum over the segment's rows of `rows` (the equation blocks of
    n instants; () every block) of (e0 - e1)^2, e0 and e1 the reference's and `c`'s held-out
    errors (top_of_sweep's measure, over the equations its test reads)."""
    d = (c.reference_errors - c.heldout_errors).reshape(-1, n)
    sq = (d[list(rows)] if rows else d) ** 2
    size = np.bincount(segment_of_rows(n), sq.sum(axis=0), minlength=SEGMENTS)
    return size >= np.median(size)


def _width_view(nom: Nominal, c: Candidate, w: Candidate, label: str) -> SecondView:
    """The backlash `w` fitted in the wide band (`nom`), its own held-out test there over
    every segment (the rows its candidate test is over; where that is split between two
    sets of rows, candidates._test, so is the view's level: SecondView.split), and its width
    against the chooser's band's `c` (module docstring: the backlash)."""
    bc, bw = c.fixed["backlash_rad"], w.fixed["backlash_rad"]
    sc, sw = jackknife(c.fold_values), jackknife(w.fold_values)
    allowed = CONSISTENCY_Z * math.hypot(sc, sw) + backlash.grid_step(nom, max(bc, bw))
    agree = abs(bw - bc) <= allowed
    detail = (f"width {1e3 * bw:.3g} +- {1e3 * sw:.2g} mrad against {1e3 * bc:.3g} +- "
              f"{1e3 * sc:.2g} mrad in the chooser's band, "
              + ("within" if agree else "more than") + f" the {1e3 * allowed:.2g} mrad allowed "
              f"({CONSISTENCY_Z:g} sigma and the search grid's step)")
    rows = f", {w.rows}" if w.rows else ""
    return SecondView(band=f"{label}, over every segment{rows}", heldout_pct=w.heldout_pct,
                      t_stat=w.t_stat, p_heldout=w.p_heldout, value=bw, agree=agree,
                      detail=detail, unphysical=w.unphysical, acts_pct=w.acts_pct,
                      split=w.views)
