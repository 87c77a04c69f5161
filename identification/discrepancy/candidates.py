"""One effect of the registry (identification.effects) against a reference model (the
nominal, or the nominal extended by the causes already named): its nonlinear values searched,
its extended regression fitted, and the evidence for it. The decision is out of sample
(identification.discrepancy.heldout: held-out folds, a t of segment log-ratios, a Bonferroni level); delta
BIC, the F-test and the practical size are reported beside it as information."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, Sequence

import dataclasses

import numpy as np
from scipy import optimize, stats

from jointbench.identification.discrepancy.heldout import (FOLDS, MATERIAL, SEGMENTS, Evidence,
                                                           Scores, bar, engagement_units, evidence,
                                                           fitted_rss, fold_of_rows, held_out,
                                                           over_engagements, preferred, scores,
                                                           segment_of_rows, t_bar)
from jointbench.identification.discrepancy.nominal import (Nominal, transmitted_rms,
                                                           with_link_law)
from jointbench.identification.discrepancy.signals import stack
from jointbench.identification.discrepancy.stacked import Stacked, apply, design_many, stacked
from jointbench.identification.effects import EFFECTS
from jointbench.identification.effects.base import FOLD_FITS, Design, Effect

BIC_MIN = 10.0          # "very strong" evidence on Kass and Raftery's scale (information only)


@dataclass(frozen=True)
class SecondView:
    """The same effect tested again in a second band (identification.discrepancy.lag_band:
    a torque lag in a band reaching the excitation's top), against the same causes: its
    held-out share, t and p there, its searched value and whether that value agrees with the
    first band's within their spreads (`agree`); `unphysical` as Candidate's."""

    band: str
    heldout_pct: float
    t_stat: float
    p_heldout: float
    value: float
    agree: bool
    detail: str            # the two values and their spreads, for the report
    unphysical: str = ""
    acts_pct: float = float("nan")   # its held-out share over the equations it acts in
    # the first band's share over every row need not be positive (lag_band: a hardening's
    # view at large deflections, its share in the first band lost to a cause beside it)
    diluted: bool = False
    segments: int = SEGMENTS   # the segments its test is over (heldout.dof)
    # the tests in this band that share the band's level (lag_band: a lag's two wide views),
    # each at alpha / split; the one reported is the one with the smaller p
    split: int = 1

    def confirms(self, alpha: float) -> bool:
        """Physical, agreeing, significant at its level, and explaining a positive share of
        its rows' held-out residual; more than MATERIAL of it for a view over the rows where
        the effect acts (`diluted`: lag_band's hardening at large deflections). That view
        tests the typical engagement, and its units are many and short: a column that fits
        a small misfit in the quiet ones can pass there while the rows it is over keep
        their residual, so it also asks what the floor of later rounds asks of a cause."""
        floor = 100 * MATERIAL if self.diluted else 0.0
        return (not self.unphysical and self.agree and self.heldout_pct > floor
                and self.p_heldout < alpha / self.split)

    def to_json(self, alpha: float) -> dict:
        """What `diagnose --json` lists under a candidate's "second_view"."""
        return {"band": self.band, "heldout_pct": self.heldout_pct, "t": self.t_stat,
                "p_heldout": self.p_heldout, "alpha": alpha / self.split,
                "value": self.value, "agree": self.agree,
                "unphysical": self.unphysical, "confirms": self.confirms(alpha)}


@dataclass(frozen=True)
class HeldOutTest:
    """One held-out test of a claim "this effect is in the log" (identification.discrepancy.
    heldout): the band or comparison it ran in (`view`), the share of the held-out residual
    the effect removes, the segment t that it removes more than MATERIAL, its one-sided p
    and the level it must pass (its round's Holm level over the views its hypothesis is
    split over). A named cause carries the test that passed; `passes` is that claim."""

    view: str
    heldout_pct: float
    t: float
    p: float
    level: float
    explained_pct: float = float("nan")   # in sample (the chooser's band only)
    acts_pct: float = float("nan")   # the held-out share over the equations it acts in
    segments: int = SEGMENTS   # the segments its t is over: a view over fewer asks more

    @property
    def own_share(self) -> float:
        """The held-out share over the equations it acts in (the rows its segment test
        reads), or over every row when not known: what the floor of later rounds asks."""
        return self.acts_pct if self.acts_pct == self.acts_pct else self.heldout_pct

    @property
    def passes(self) -> bool:
        return bool(self.heldout_pct > 0 and self.p < self.level)

    @property
    def bar(self) -> float:
        """The t its level asks for (heldout.t_bar)."""
        return t_bar(self.level, self.segments) if self.level > 0 else float("inf")

    def describe(self) -> str:
        """"t = .. (p = ..) against the bar t > .. (level ..), held out .. %" with its view."""
        own = (f" ({self.acts_pct:.3g} % of the equations it acts in)"
               if self.acts_pct == self.acts_pct else "")
        return (f"{self.view}: held out it explains {self.heldout_pct:.3g} %{own}, t = "
                f"{self.t:.3g} (p = {self.p:.2g}) against the bar t > {self.bar:.3g} "
                f"(level {self.level:.2g})")

    def to_json(self) -> dict:
        return {"view": self.view, "heldout_pct": self.heldout_pct, "t": self.t,
                "p_heldout": self.p, "alpha": self.level, "t_bar": self.bar,
                "segments": self.segments, "explained_pct": self.explained_pct,
                "acts_pct": self.acts_pct, "passes": self.passes}


CHOOSER = "chooser's band"


@dataclass(frozen=True)
class Candidate:
    """One effect evaluated against a reference model (the nominal, then `base`)."""

    effect: str
    testable: bool
    reason: str = ""
    parameters: dict[str, float] = field(default_factory=dict)
    k: int = 0                       # extra parameters, nonlinear ones included
    rss: float = float("nan")
    explained_pct: float = 0.0       # in sample: share of the reference weighted RSS it removes
    heldout_pct: float = 0.0         # out of sample: share of the held-out RSS it removes
    acts_pct: float = float("nan")   # the same over the equations it acts in (acts)
    t_stat: float = 0.0              # t: held-out share above MATERIAL (heldout)
    p_heldout: float = 1.0           # its one-sided p-value
    alpha: float = 0.0               # its hypothesis' level in the round (Holm)
    delta_bic: float = 0.0           # BIC(reference) - BIC(extended): > 0 favours the effect
    p_value: float = 1.0             # F-test of the added terms
    size_pct: float = 0.0            # RMS change of its block's prediction, % of the block
    before_pct: float = float("nan")  # inverse-view error metric of its block, reference
    after_pct: float = float("nan")   # same with the effect
    block: int = 0
    X: tuple[float, ...] = ()
    names: tuple[str, ...] = ()
    unphysical: str = ""             # why the best fit is not a physical instance of it
    # standard errors by which that fit lies beyond its physical bound (Effect.beyond; inf
    # where the effect gives none)
    beyond_se: float = float("inf")
    residual: np.ndarray | None = field(default=None, repr=False, compare=False)
    # each row's weighted held-out error (its fold's fit): comparisons between candidates
    heldout_errors: np.ndarray | None = field(default=None, repr=False, compare=False)
    # the reference's held-out errors it was weighed against (a coupled cause refitted)
    reference_errors: np.ndarray | None = field(default=None, repr=False, compare=False)
    fixed: dict = field(default_factory=dict)   # values the effect's columns are built with
    # each held-out fold's training fit of the columns (names: X), from which an effect's
    # check takes its fit's own standard errors (effects.base.FOLD_FITS, spread)
    fold_fits: tuple[dict, ...] = field(default=(), repr=False, compare=False)
    base: tuple[tuple[str, dict], ...] = ()     # causes named before it, as its fit has them
    acts: tuple[int, ...] = ()   # the equation blocks its columns change (acts_in); () all
    # the searched value each fold's training rows prefer (a searched effect; its spread)
    fold_values: tuple[float, ...] = ()
    second: SecondView | None = None   # a second band's test (lag_band), when one was run
    views: int = 1   # the tests its hypothesis is split over (lag_band: 2), each at alpha / views
    # the rows its chooser's band test is over when not every row it acts in (OWN_ROWS: a
    # second cause of the spring law over the link equation, _test); "" for those
    rows: str = ""
    round: int = 0   # the round of the inverse view it was tested in (1 against the nominal)
    view: str = CHOOSER   # what its own test is (the masked pair's: on top of the other)
    # the units its chooser's band test is over: SEGMENTS, or for an effect that engages
    # (Effect.engages) the segments with each engagement apart (heldout.engagement_units)
    segments: int = SEGMENTS

    @property
    def level(self) -> float:
        """The bar each of its tests must pass: its hypothesis' level over its views."""
        return self.alpha / self.views

    @property
    def confirmed(self) -> bool:
        """Significant in the second band's view (SecondView.confirms) at its level, with a
        positive share in the first band unless the view says that share is diluted."""
        v = self.second
        return (v is not None and v.confirms(self.level)
                and (self.heldout_pct > 0 or v.diluted))

    @property
    def significant(self) -> bool:
        return (self.testable and not self.unphysical
                and (self.heldout_pct > 0 and self.p_heldout < self.level or self.confirmed))

    @property
    def units(self) -> str:
        """", the segments with each engagement apart (k units)" when its chooser's band
        test counts the spring's engagements (Effect.engages), "" for the segments."""
        e = EFFECTS.get(self.effect)
        return (f", the segments with each engagement apart ({self.segments} units)"
                if e is not None and e.engages else "")

    @property
    def own_test(self) -> HeldOutTest:
        """Its test in the chooser's band (or its `view`), over its `rows`, at its level."""
        view = self.view + self.units
        view = f"{view}, {self.rows}" if self.rows else view
        return HeldOutTest(view, self.heldout_pct, self.t_stat, self.p_heldout, self.level,
                           self.explained_pct, self.acts_pct, self.segments)

    @property
    def test(self) -> HeldOutTest:
        """The test its claim rests on: the chooser's band's when that passes, else the
        second band's when it confirms the effect (lag_band), else the failing chooser's."""
        own = self.own_test
        if own.passes or not self.confirmed:
            return own
        v = self.second
        return HeldOutTest(v.band, v.heldout_pct, v.t_stat, v.p_heldout, self.level / v.split,
                           acts_pct=v.acts_pct, segments=v.segments)

    @property
    def why_not(self) -> str:
        """Why it is not significant ("" when it is): the first bar it fails, with numbers."""
        if not self.testable:
            return self.reason
        if self.unphysical:
            return f"unphysical fit ({self.unphysical})"
        if not self.significant:
            return (f"held out ({FOLDS} folds), it explains {self.heldout_pct:.3g} % of the "
                    f"residual; that it explains more than {100 * MATERIAL:g} % has t = "
                    f"{self.t_stat:.3g} (p = {self.p_heldout:.3g}); the bar is p < "
                    f"{self.level:.2g} (t > {t_bar(self.level, self.segments):.3g}"
                    f"{self.units})" + self.share_note
                    + (f"; {self.second_note}" if self.second else ""))
        return ""

    @property
    def share_note(self) -> str:
        """Why a t above its bar does not pass ("" otherwise): a cause must also explain a
        positive share of the held-out residual over every row (`significant`). The segment
        test weighs every segment alike and the share every row by its error, so an effect
        that helps the quiet segments and costs the loud ones more has a large t and no
        share."""
        if self.heldout_pct > 0 or not self.p_heldout < self.level:
            return ""
        return ("; its t passes the bar, but a cause must also explain a positive share of "
                "the held-out residual over every row: the t weighs every segment alike, the "
                "share every row by its error, and where the residual is loud it predicts "
                "worse than the reference")

    @property
    def second_note(self) -> str:
        """What the second band's view said ("" when none was run)."""
        v = self.second
        if v is None:
            return ""
        verdict = "confirms it" if self.confirmed else "does not confirm it"
        return (f"in the {v.band} it explains {v.heldout_pct:.3g} % with t = {v.t_stat:.3g}"
                f" (p = {v.p_heldout:.3g}), {v.detail}"
                + (f", unphysical ({v.unphysical})" if v.unphysical else "") + f": {verdict}")

    @property
    def gain(self) -> float:
        return self.before_pct / self.after_pct if self.after_pct > 0 else float("inf")


def _effect(name: str) -> Effect:
    if name not in EFFECTS:
        raise ValueError(f"unknown effect {name!r}")
    return EFFECTS[name]


def design(nom: Nominal, effect: str, fixed: dict) -> Design:
    """y, W and names of the nominal model extended by `effect` (docs/effects.md) with its
    nonlinear values `fixed` (searched, or carried over from another log); the linear
    parameters come from least squares on the columns."""
    return _effect(effect).design(nom, fixed)


@dataclass(frozen=True)
class Reference:
    """What candidates are tested against: the nominal extended by `base` (maybe nothing),
    its scores on all rows and on the folds, and the Bonferroni bar of the round."""

    base: Stacked
    folds: np.ndarray
    scores: Scores
    alpha: float

    @property
    def residual(self) -> np.ndarray:
        y, W, _ = self.base.design()
        return y - W @ self.scores.X


def reference(nom: Nominal, causes: tuple[tuple[str, dict], ...] = (),
              m: int = len(EFFECTS)) -> Reference:
    """The reference model of a round: `nom` extended by `causes`; m effects tested in it."""
    base = Stacked(nom)
    for name, fixed in causes:
        base, _ = apply(base, name, fixed)
    folds = fold_of_rows(nom)
    y, W, _ = base.design()
    return Reference(base=base, folds=folds, scores=scores(nom, folds, y, W), alpha=bar(m))


def _search(cost: Callable[[float], float], grid: np.ndarray) -> None:
    """Grid then bounded refinement of a scalar nonlinear parameter: `cost` (the weighted RSS
    on all rows) records every trial."""
    costs = [cost(v) for v in grid]
    i = int(np.argmin(costs))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    if hi > lo:
        optimize.minimize_scalar(cost, bounds=(lo, hi), method="bounded",
                                 options={"xatol": 1e-3 * (hi - lo)})


def _evaluate(nom: Nominal, ref: Reference, e: Effect, fixed: dict,
              records: list[Scores], under: Stacked,
              fold_values: tuple[float, ...] = ()) -> Candidate:
    """Fit the extended design at `fixed` on `under` (the reference's causes, maybe refitted:
    _coupled) and weigh the evidence against the reference; `fold_values`, the searched
    value each fold's training rows prefer, set an engaging effect's units (_units)."""
    _, (y, W, names) = apply(under, e.name, fixed)
    k, block = e.k, e.block
    X = min(records, key=lambda r: r.full).X   # the fit at `fixed` (candidate's choice)
    rss0 = ref.scores.full
    res_after = y - W @ X
    rss = float(np.sum((res_after * nom.weights) ** 2))
    n, n0 = len(y), W.shape[1] - k
    bic0 = n * np.log(rss0 / n) + n0 * np.log(n)
    bic1 = n * np.log(max(rss, 1e-300) / n) + (n0 + k) * np.log(n)
    dof = n - n0 - k
    F = ((rss0 - rss) / k) / (rss / dof) if rss > 0 and dof > 0 else np.inf
    p = float(stats.f.sf(F, k, dof)) if np.isfinite(F) else 0.0
    y0, W0, names0 = ref.base.design()
    res_before = y0 - W0 @ ref.scores.X
    rows = nom.block == block
    pred_change = (res_before - res_after)[rows]
    scale = nom.reference_rms[block]
    size = (100 * float(np.sqrt(np.mean(pred_change ** 2))) / scale if scale > 0
            else float("nan"))
    errors = held_out(records, ref.folds)
    acts = acts_in(nom, (y0, W0, names0), (y, W, names))
    ev, views, rows = _test(e, ref, errors, len(nom.sig.index), acts,
                            _units(nom, e, fold_values), _past_first_step(nom, e, fixed))
    values = dict(zip(names, X))
    best = min(records, key=lambda r: r.full)
    folds = (() if best.fold_X is None
             else tuple(dict(zip(names, x)) for x in best.fold_X))
    # fitted and searched values, and each fold's training fit (the fit's own spread)
    v = {**fixed, **values, FOLD_FITS: folds}
    why = e.check(v, nom) if e.check else ""
    far = float(e.beyond(v, nom)) if e.beyond else float("inf")
    return Candidate(effect=e.name, testable=True, parameters=e.params(values, fixed, nom),
                     k=k, rss=rss, unphysical=why, beyond_se=far,
                     residual=res_after, heldout_errors=errors,
                     reference_errors=ref.scores.errors,
                     explained_pct=100 * (rss0 - rss) / rss0,
                     heldout_pct=ev.explained_pct, acts_pct=ev.acts_pct, t_stat=ev.t,
                     p_heldout=ev.p,
                     alpha=ref.alpha, delta_bic=float(bic0 - bic1), p_value=p, size_pct=size,
                     before_pct=_own_error_pct(nom, res_before, block, W0, ref.scores.X),
                     after_pct=_own_error_pct(nom, res_after, block, W, X), block=block,
                     X=tuple(float(x) for x in X), names=tuple(names), fixed=fixed,
                     fold_fits=folds, fold_values=fold_values,
                     base=under.effects, acts=acts, views=views, rows=rows,
                     segments=ev.segments)


def acts_in(nom: Nominal, reference: Design, extended: Design) -> tuple[int, ...]:
    """The equation blocks (0 motor, 1 link) whose rows the extended design changes: its
    left-hand side, a reference column rebuilt (a lag's led motor columns, a dead band's
    deflection) or an added column not zero there; () when it changes none. Its held-out
    evidence is measured on those rows (identification.discrepancy.heldout.segment_log_ratios):
    elsewhere the extended model differs from the reference only by the shared parameters'
    refit."""
    y0, W0, _ = reference
    y1, W1, _ = extended
    k = W0.shape[1]
    changed = ((y1 != y0) | np.any(W1[:, :k] != W0, axis=1) | np.any(W1[:, k:] != 0, axis=1))
    return tuple(int(b) for b in np.unique(nom.block[changed]))


def _own_error_pct(nom: Nominal, residual: np.ndarray, block: int, W: np.ndarray,
                   X: np.ndarray) -> float:
    """The inverse view's error of `block` for a model (the reference or an extended one):
    the link equation's residual over the model's own transmitted torque (nominal.
    transmitted_rms), as the nominal's is over the nominal's. (Over the nominal's, a nominal
    that shrinks the homogeneous link equation towards 0 = 0, K = 779 where the spring has
    2.0e4 under a large spring damping, makes every model that restores K look worse.)"""
    if block != 1:
        return nom.relative_error_pct(residual, block)
    spring = transmitted_rms(W, X, nom.block)
    return 100.0 * nom.block_rms(residual, 1) / spring if spring > 0 else float("nan")


# A second cause of the spring law is tested over two sets of rows, each at half its level
# (_test); the one reported is the one with the smaller p.
ROW_VIEWS = 2
OWN_ROWS = "over the link equation"


def _units(nom: Nominal, e: Effect, fold_values: tuple[float, ...]) -> np.ndarray | None:
    """The units of an engaging effect's test (Effect.engages; heldout.engagement_units:
    each engagement of the spring, at the engagement its fold's training rows chose, and
    the other instants of each segment); None for the others, tested over the segments.

    A hardening's column Kh dz(qm - q, d) is zero until the deflection passes d, and a sweep
    passes it in a few segments only: on an axis whose sweep crosses the mode in its first
    seconds, 9 of the 40 segments of the chooser's band reach it, with 1 to 13 engaged
    decimated rows each. Counted by segments, the jumps of those few from one to the next
    count as noise in the successive differences and the others dilute the mean: the t is
    set by how many segments the spring engages in, not by what it explains (a hardening that
    removes half of the held-out residual has t = 3.5 there). Each engagement is one
    observation of the second spring, in the chooser's band as in the wide one (lag_band:
    the unit of the hardening's view). The units are set by the positions and the training
    rows' engagements, never by the held-out residual, so under the null hypothesis their
    log-ratios have a negative mean and the test's level holds."""
    if not (e.engages and fold_values):
        return None
    return engagement_units(nom, fold_values)


def _test(e: Effect, ref: Reference, errors: np.ndarray, n: int,
          acts: tuple[int, ...], units: np.ndarray | None = None,
          resolved: bool = True) -> tuple[Evidence, int, str]:
    """The held-out evidence of `e` (its `errors` against `ref`'s, over the `acts` blocks of
    n instants each), the views its level is split over and the rows it is over ("" for every
    row it acts in). A second cause of the spring law (second_of_spring: a named cause in
    `ref` acts in the spring, its law or its damping, a hardening beside a backlash or a
    spring damping) is tested over its own equation too, the link equation (Effect.block):
    ROW_VIEWS views, the one with the smaller p reported (OWN_ROWS when it is the link
    equation's).

    Its columns change the spring torque K dz(qm - q) in both equations (action and
    reaction, eqs. 5-6), but the equations do not see that change alike. The link equation
    is homogeneous (0 = JL q'' + FV q' + FS s(q') + ... - K (qm - q)): the spring torque is
    its whole right-hand side, and once the first cause of the spring is in the model (a
    cause of its law, or a spring damping D (qm' - q'), the torque in parallel with it) its
    residual is what the spring law still misses, the encoders' noise and the numerics'. In
    the motor equation the same torque stands beside the measured motor torque and its
    noise. The rows are weighed by the nominal's block weights, and the nominal's link
    equation spread holds the first cause's whole misfit (the torque K b that a dead band
    of half-width b takes off the spring): summed over both equations, the link equation's
    errors may count for a hundredth of the motor equation's, and the test reads the motor
    torque's noise (a hardening beside a backlash that removes three quarters of the link
    equation's held-out residual removes 2 % of the sum). Over the link equation alone that
    noise is gone (a hardening beside a spring damping on a pendulum with a noisy motor
    torque: over both equations it removes 7 % of the held-out residual with t = 0.3, over
    the link equation t = 10.6, the motor equation's t = -6.6 being its refit's noise);
    but where the second cause engages at the largest deflections only, its
    evidence in the link equation sits in a few segments and the motor equation's rows
    carry it as well, so neither set of rows is the better one for every log. The test
    runs over both and the hypothesis' level is split between them (Candidate.views,
    Bonferroni: 2 min(p_all, p_link) is a valid p-value whatever the two tests'
    dependence), fixed by the design, never by what either test finds. The rows are the
    equation's, not chosen by the residual: under the null hypothesis the link equation's
    segment log-ratios have a negative mean as every row's do (heldout). The first cause of
    the law, tested against the nominal, is tested over every row: the nominal's link
    equation spread is then its own misfit. `units`: the units an engaging effect's t is
    over (_units), None for the segments. A torque lag beside a named spring damping is
    tested over the link equation too, where the damping's refit shows it
    (lead_beside_parallel), when `resolved` (_past_first_step)."""
    def test(blocks: tuple[int, ...]) -> Evidence:
        ev = evidence(ref.scores.errors, errors, n, blocks)
        return (ev if units is None
                else over_engagements(ev, ref.scores.errors, errors, n, blocks, units))

    ev = test(acts)
    if lead_beside_parallel(e, ref.base.effects) and acts == (0,):
        if not resolved:
            return ev, ROW_VIEWS, ""
        split = test((1,))
        return (split, ROW_VIEWS, OWN_ROWS) if split.p < ev.p else (ev, ROW_VIEWS, "")
    if not (second_of_spring(e, ref.base.effects) and e.block in acts and len(acts) > 1):
        return ev, 1, ""
    own = test((e.block,))
    return (own, ROW_VIEWS, OWN_ROWS) if own.p < ev.p else (ev, ROW_VIEWS, "")


def lead_beside_parallel(e: Effect, base: tuple[tuple[str, dict], ...]) -> bool:
    """`e` leads the motor equation's columns (LEADS: a torque lag) and a named cause in
    `base` acts in parallel with the spring (PARALLEL: a spring damping): the lag's evidence
    is then in the link equation as well as in the motor equation it acts in (_test).

    The lag's led motor equation holds T K (qm' - q'), the damping's own motor column (_beside).
    Against the model holding the damping alone, its one D (qm' - q') in both equations, with
    opposite signs (action and reaction), takes that term up in the motor equation, and the
    link equation, which has no lag, then carries D's compromise between the two: D too large
    by a share of T K there. The lag, fitted beside it, takes the motor equation's T K and
    frees D to take the link equation's own value: what the lag adds shows where it does not
    act, in the link equation's held-out residual, through the refit of the parameter the
    two share. Over the motor equation alone, its rows read only the lag's phase beyond
    the damping's column, T (Jm qm''' + FVm qm'' + ...), small on an axis whose motor inertia
    and friction are small against the spring's. The test runs over both sets of rows, the
    motor equation and the link equation, each at half the hypothesis' level (ROW_VIEWS,
    Bonferroni, as for a second cause of the spring law), fixed by the causes named, never
    by what either test finds. Under the null hypothesis (no lag) the lag's column adds only
    estimation variance, the shared parameters' refit included, on the link equation's rows
    as on every row: their segment log-ratios have a negative mean (heldout)."""
    return e.name in LEADS and any(name in PARALLEL for name, _ in base)


def _past_first_step(nom: Nominal, e: Effect, fixed: dict) -> bool:
    """`e`'s searched value lies at or beyond the first step of its search grid (the first
    trial after none), or `e` has no search: the link equation's view of a lag beside a
    damping (lead_beside_parallel) reads the lag only through D's split between the two
    equations, and any phase between the motor torque and the positions splits it too (the
    log's own sampling and numerics: a clean bench log fits a lag of a few hundredths of its
    sample period). A lag below the grid's first trial, the refinement between no lag and
    that trial, is not told from that phase there: its test stays the motor equation's (its
    level split as the design fixes it), as a hardening engaged in the first step of its grid
    is no physical instance of one (lag_band)."""
    if not e.search or e.grid is None or e.search not in fixed:
        return True
    g = e.grid(nom)
    return len(g) < 2 or float(fixed[e.search]) >= float(g[1])


def second_of_spring(e: Effect, base: tuple[tuple[str, dict], ...]) -> bool:
    """`e` shapes the spring law (spring_law) and a named cause in `base` acts in the
    spring (Effect.in_spring: its law or its damping): the link equation's residual is then
    what the spring still misses (_test). A cause of the law is coupled to it (_coupled); a
    spring damping is not (its value is linear), but it is the torque in parallel with the
    spring, in the same homogeneous equation."""
    return spring_law(e) and any(EFFECTS[name].in_spring for name, _ in base)


def _coupled(e: Effect, base: tuple[tuple[str, dict], ...]) -> list[int]:
    """The named causes whose searched value shapes the same law as e's: in the link equation
    the searched values are the spring law's (a backlash's width, a hardening's engagement),
    and two of them share its one deflection column. One searched alone under the other's
    value carries that value's error: a dead band fitted alone widens to take up a hardening
    beyond it, and a hardening tested on top of that width cannot undo it (a wrist hardening
    beside a backlash, tests/sim/test_diagnose_spring_law.py: what the hardening adds to the
    backlash has t = 2.1 with the width held, 8.2 with it searched again)."""
    if not spring_law(e):
        return []
    return [i for i, (name, _) in enumerate(base) if spring_law(EFFECTS[name])]


def spring_law(e: Effect) -> bool:
    """`e` shapes the spring law of the link equation with a searched value (a backlash's
    width, a hardening's engagement: _coupled)."""
    return bool(e.search) and e.block == 1


def _reducing(e: Effect, base: tuple[tuple[str, dict], ...]) -> list[int]:
    """The named causes that reduce to e (registry `reduces_to`: an asymmetric friction
    beside an offset candidate) and have a searched value (the asymmetry's viscous-to-Coulomb
    split). That value was read before the causes named after it were in place, or beside
    the very offset being tested (where the split is arbitrary: the offset takes the
    constant); searched again on the causes alone, the constant its Coulomb part takes under
    them is its own, not the candidate's (a prototype asymmetry whose split, read before a
    torque ripple was named, has no Coulomb part: an offset then took that part up as a
    third cause)."""
    return [i for i, (name, _) in enumerate(base)
            if EFFECTS[name].reduces_to == e.name and EFFECTS[name].search]


def _refitted(nom: Nominal, ref: Reference, coupled: list[int]) -> Reference:
    """`ref` with the searched values of its causes `coupled` searched again, in turn, on the
    causes alone: what a coupled candidate is credited with is then what it adds, not what
    refitting the causes beside the ones named after them gives (otherwise, with a backlash
    named before a spring damping, a hardening on top of both takes up the width's error and
    is named a third cause)."""
    effects = list(ref.base.effects)
    for i in coupled:
        name, fx = effects[i]
        c = EFFECTS[name]
        fits: list[tuple[float, float]] = []

        def cost(w: float) -> float:
            effects[i] = (name, {**fx, c.search: float(w)})
            y, W, _ = stacked(nom, effects).design()
            fits.append((fitted_rss(nom, y, W), float(w)))
            return fits[-1][0]

        _search(cost, c.grid(nom))
        effects[i] = (name, {**fx, c.search: min(fits)[1]})
    base = stacked(nom, effects)
    y, W, _ = base.design()
    return Reference(base=base, folds=ref.folds, scores=scores(nom, ref.folds, y, W),
                     alpha=ref.alpha)


def candidate(nom: Nominal, effect: str, ref: Reference | None = None) -> Candidate:
    """Search the effect's nonlinear parameter (if it has one) on all rows and, for the held-
    out evidence, on each fold's training rows; then evaluate it against `ref` (default: the
    nominal model). A named cause that shapes the same law (_coupled) has its searched value
    searched again beside it, and the effect's once more: the candidate is the effect with
    the causes refitted beside it, against the causes refitted alone (_refitted) where a
    cause was named after the coupled one; a named cause that reduces to the effect has its
    searched value searched again on the causes alone (_reducing). An effect whose model
    holds its own link friction law (Effect.own_link_law, _own_law) is searched and fitted
    once more with the law searched on its extended design, against the same `ref`; an effect
    with a limit (Effect.limit) is weighed against `ref` extended by it (beyond_limit)."""
    ref = ref or reference(nom)
    e = _effect(effect)
    coupled = _coupled(e, ref.base.effects)
    # a cause searched with every cause after it already in place needs no refit alone
    last = len(ref.base.effects) - 1
    refit = [i for i in coupled if i < last] + _reducing(e, ref.base.effects)
    beside = _beside(e, ref.base.effects)
    if refit or beside:
        ref = _refitted(nom, ref, refit + [i for i in beside if i not in refit])
    c = _searched(nom, e, ref, coupled, beside)
    law = _own_law(nom, e, ref, c)
    c = c if law is nom else _searched(law, e, ref, coupled, beside)
    return beyond_limit(nom, e, ref, c)


def beyond_limit(nom: Nominal, e: Effect, ref: Reference, c: Candidate) -> Candidate:
    """`c` with its evidence against `ref` extended by `e`'s limit (Effect.limit: the columns
    its design tends to as its searched value goes to 0, a dead band's torque of the spring's
    sign) where that evidence is the weaker (the larger p); `c` itself otherwise, or for an
    effect without a limit. The claim is that it explains what both references leave: the
    larger of the two p-values is a valid p-value of that claim at the round's level, with no
    split of the level (an intersection-union test), and a reference with a column or two more
    never makes a cause easier to name than the round's own reference does.

    It is the reference of a later round only: the question there is what is left beyond the
    named causes, and their residual misfit joins the nominal's near zero speed (a ripple
    that makes the motor stick, the link creeping behind it). In the first round the
    candidates are weighed against the nominal and each other (ranking, parsimony).

    The limit is a linear column that the nominal's own misfit near zero speed also takes
    (a sticking link held by friction against the spring: identification.effects.base.
    spring_sign), so a cause credited with it would be named for that misfit. The extended model
    is the same (its fit, parameters and held-out errors); only the reference it is weighed
    against holds the column, fitted on the same folds, so that what it is credited with is
    what its searched value adds beyond its first order: for a dead band, the band itself.
    The equations it acts in stay those it changes against `ref`. The reference holds its own
    link friction law (nominal.with_link_law), searched on its design with the limit, as the
    extended model holds its own (_own_law): the limit and the law near zero speed share the
    rows where the link sticks.

    The column is kept apart on two sets of instants, each with its own coefficient, and is
    zero elsewhere:
    - where the axis stands (`standing`: motor and link each within one encoder count over a
      segment): the deflection takes one value there, so the spring law is seen at one
      deflection only, and the link's friction holds whatever the spring carries, up to FS,
      where the law claims none (tanh(0) = 0). An axis that comes to rest with the spring
      holding a few encoder counts of deflection leaves the link equation a constant misfit
      over every segment it stands in, which a dead band just under that deflection removes
      (K dz(d, b) = K (d - b s(d)) there); the held-out test counts each such segment as one
      more where the band explains most of the residual. Its level is the friction's at
      rest, not the spring's torque at its reversals: a column of its own. Kept beside any
      named cause, a cause of the spring included: one deflection tells no spring law apart.
      Where the link stands while the motor moves (through a dead band) the deflection
      changes and the segment is not standing.
    - where the deflection reverses (`reversing`), the link moving: the column stands for the
      spring's torque at its reversals, on top of causes none of which acts in the spring
      (Effect.in_spring). Beside a named cause of the spring, the spring's torque at its
      reversals is that cause's model, whose own first order (a dead band's K b s(qm - q)) or
      reversal torque (a damping's) the column would duplicate. On the segments where the
      deflection does not reverse it is zero: where a static load holds the deflection on
      one side for a whole segment (a pendulum resting on its spring against gravity, the
      link following the sweep), the spring's sign is that load's sign on every row, the
      column is a constant torque there, an offset, and it takes up K's misfit at the static
      deflection K (qm - q), which a spring law stiffer at large deflections leaves (the
      nominal's K fitted where the stiffer spring acts is too stiff at rest): the hardening's
      own image, not the misfit near zero speed the column is for."""
    named = ref.base.effects
    if e.limit is None or not c.testable or c.heldout_errors is None or not named:
        return c
    sig = nom.sig
    still = standing(nom)
    # the reversals' column only on top of causes none of which acts in the spring
    on = ~still & (np.zeros_like(still) if any(EFFECTS[name].in_spring for name, _ in named)
                   else reversing(nom))
    cols = tuple((f"{name}{label}", _kept(stack(sig, m, li), rows))
                 for label, rows in (("", on), ("_standing", still)) if rows.any()
                 for name, m, li in e.limit(nom))
    if not cols:
        return c
    base = dataclasses.replace(ref.base, extra=ref.base.extra + cols)
    law = with_link_law(nom, base.design())
    if law is not nom:
        under = _on(law, ref)
        base = dataclasses.replace(under, extra=under.extra + cols)
    y, W, _ = base.design()
    lim = replace(ref, base=base, scores=scores(law, ref.folds, y, W))
    ev, views, rows = _test(e, lim, c.heldout_errors, len(sig.index), c.acts,
                            _units(nom, e, c.fold_values))
    if not ev.p > c.p_heldout:
        return c
    rss0 = lim.scores.full
    return replace(c, reference_errors=lim.scores.errors,
                   explained_pct=100 * (rss0 - c.rss) / rss0 if rss0 > 0 else 0.0,
                   heldout_pct=ev.explained_pct, acts_pct=ev.acts_pct, t_stat=ev.t,
                   p_heldout=ev.p, views=views, rows=rows, segments=ev.segments)


def reversing(nom: Nominal) -> np.ndarray:
    """The instants (a mask over `nom`'s rows of one block) of the segments (heldout.
    segment_of_rows) where the deflection qm - q takes both signs: where the spring's torque
    reverses (beyond_limit); every instant for a log without the link."""
    sig = nom.sig
    n = len(sig.index)
    if sig.q is None:
        return np.ones(n, bool)
    s = np.sign((sig.qm - sig.q)[sig.index])
    seg = segment_of_rows(n)
    up = np.bincount(seg, s > 0, SEGMENTS) > 0
    down = np.bincount(seg, s < 0, SEGMENTS) > 0
    return (up & down)[seg]


def standing(nom: Nominal) -> np.ndarray:
    """The instants (a mask over `nom`'s rows of one block) of the segments (heldout.
    segment_of_rows) where the axis stands: the motor's and the link's positions over the
    whole segment each within one count of its encoder (Signals.qm_step, q_step, read from
    the log), so that the deflection qm - q takes one value there as far as the log tells
    (beyond_limit); no instant for a log without the link."""
    sig = nom.sig
    n = len(sig.index)
    if sig.q is None:
        return np.zeros(n, bool)
    seg = segment_of_rows(n)
    still = np.ones(SEGMENTS, bool)
    for x, step in ((sig.qm, sig.qm_step), (sig.q, sig.q_step)):
        top, low = np.full(SEGMENTS, -np.inf), np.full(SEGMENTS, np.inf)
        np.maximum.at(top, seg, x[sig.index])
        np.minimum.at(low, seg, x[sig.index])
        still &= top - low <= step
    return still[seg]


def _kept(column: np.ndarray, instants: np.ndarray) -> np.ndarray:
    """A stacked column (signals.stack: one block of rows per equation) zero outside
    `instants` (a mask over one block's rows)."""
    return column * np.tile(instants, len(column) // len(instants))


# The effects that act in parallel with the spring without a searched value of their own
# (_beside).
PARALLEL = ("spring_damping",)
# The effects whose searched value leads the motor equation's columns, the spring's K (qm - q)
# among them (effects.torque_lag: T K (qm' - q'), a PARALLEL effect's motor column; _beside).
LEADS = ("torque_lag",)


def _beside(e: Effect, base: tuple[tuple[str, dict], ...]) -> list[int]:
    """The named causes of the spring law (spring_law: a backlash's width, a hardening's
    engagement) whose value is searched again beside a candidate that acts in parallel with
    the spring (PARALLEL: a spring damping D (qm' - q')). A dead band fitted alone under a
    spring damping comes out narrower than it is (the damping's torque at the reversals,
    where the deflection crosses the band, reads as a spring torque there): on an arm axis
    with a backlash of 0.30 mrad and a spring damping, the width fitted alone is 0.265 mrad,
    and the damping tested on top of it leaves three times the held-out residual it leaves on
    top of 0.30 mrad, the width searched beside it, so that a hardening engaged near the band
    with a damping beside it predicts better than the dead band with one. Against the causes
    refitted alone (_refitted), as a coupled candidate is.

    A named torque lag too (LEADS): its led motor equation (1 + T d/dt) of Jm qm'' + FVm qm'
    + K (qm - q) holds T K (qm' - q'), the damping's own motor column D (qm' - q'). A lag
    searched alone beside an unmodelled damping takes that column up, T too long by about
    D / K (on the balanced family a 9.0 ms lag beside D = 0.73 N m s/rad, D / K = 2.3 ms,
    comes out 11.6 ms), and the damping tested on top of it is credited only with its link
    column. Searched again beside the damping, T returns to the lag's own part."""
    if e.name not in PARALLEL:
        return []
    return [i for i, (name, _) in enumerate(base)
            if spring_law(EFFECTS[name]) or name in LEADS]


def _own_law(nom: Nominal, e: Effect, ref: Reference, c: Candidate) -> Nominal:
    """`nom` with the link friction's law (nominal.link_law) searched again on the design of
    `ref`'s causes extended by `c` at its values, for an effect whose model holds its own law
    (Effect.own_link_law); `nom` itself otherwise, or when the law is the same.

    The law is part of each model, never a cause, and the nominal's was searched on the
    nominal alone. A dead band's misfit sits in the link equation at the link-torque
    reversals, where the deflection crosses the band and the link, held by no spring, coasts
    on its friction and sticks: the nominal, which claims a spring torque K (qm - q) there,
    takes part of that misfit up with a sharper friction law near zero speed (on a soft axis
    whose sweep passes the mode early, a law of tanh(q' / 0.3 mrad/s) where the simulator's
    is tanh(q' / 1 mrad/s), and a dead band of 7 % visibility tested against it explains
    55 % of the held-out residual with t = 3.2; with the law searched beside the dead band,
    0.9 mrad/s, 73 % with t = 6.7). Tested against the nominal's law, the dead band is
    credited only with what that law left. So the extended model has the law that fits it
    best, as the reference has the one that fits it best: each model with its own, the
    held-out test against `ref` unchanged (the reference keeps its law). The extended model's
    law is searched on all its rows, as the nominal's is, not on each fold's."""
    if not (e.own_link_law and nom.link_friction and c.testable):
        return nom
    return with_link_law(nom, apply(_on(nom, ref), e.name, c.fixed)[1])


def _on(rows: Nominal, ref: Reference) -> Stacked:
    """`ref`'s causes applied to `rows` (the same log's rows, maybe with another link law)."""
    return ref.base if ref.base.nom is rows else stacked(rows, ref.base.effects)


def _searched(nom: Nominal, e: Effect, ref: Reference, coupled: list[int],
              beside: list[int] = ()) -> Candidate:
    """The effect searched and fitted on `nom`'s rows (ref's causes applied to them: _on),
    its evidence against `ref` (candidate); the values of the causes `beside` (_beside)
    searched again beside it, in turn."""
    fixed = e.reference(nom) if e.reference else {}
    records: list[Scores] = []
    trials: list[tuple[float | None, Stacked]] = []
    base = _on(nom, ref)

    def cost(v: float | None, under: Stacked = base) -> float:
        fx = fixed if v is None else {**fixed, e.search: v}
        y, W, _ = apply(under, e.name, fx)[1]
        records.append(scores(nom, ref.folds, y, W))
        trials.append((v, under))
        return records[-1].full

    def best() -> tuple[float | None, Stacked]:
        # the trial of least weighted RSS on all rows among every one (grid and refinement)
        return trials[int(np.argmin([r.full for r in records]))]

    def again(i: int, v: float | None, under: Stacked) -> None:
        # the value of `under`'s cause i searched again, this effect at `v`
        name, fx = under.effects[i]
        c = EFFECTS[name]
        effects = list(under.effects)

        def at(w: float) -> float:
            effects[i] = (name, {**fx, c.search: float(w)})
            return cost(v, stacked(nom, effects))

        _search(at, c.grid(nom))

    under = base
    if e.search:
        grid = e.grid(_Left(nom, base) if base.effects else nom)
        _search(cost, grid)
        for i in coupled:
            v, under = best()
            again(i, v, under)
            under = best()[1]
            _search(lambda w: cost(w, under), grid)
        v, under = best()
        fixed = {**fixed, e.search: float(v)}
    else:
        cost(None)
        for i in beside:
            again(i, None, best()[1])
        under = best()[1]
        if e.reference:
            # the values it is built with from the fit with it, not from the nominal that
            # lacked it: once more (a fixed point in one step on the bench)
            names = apply(base, e.name, fixed)[1][2]
            fixed = e.reference(_Fitted(nom, names, records[-1].X))
            records.clear()
            cost(None)
    values = (tuple(float(trials[j][0]) for j in preferred(records)) if e.search else ())
    return _evaluate(nom, ref, e, fixed, records, under, values)


class _Left:
    """`nom`'s rows with the residual that the causes of `base` (a round's reference, the
    nominal extended by the causes named before it) leave: its design fitted on every row
    with the nominal's block weights, r = y - W X. What an effect's search grid reads from
    a residual (torque_ripple's periodogram of the motor equation's residual over the motor
    angle) is what the round's candidate is fitted to explain, the residual of its reference,
    not the nominal's: there a named cause's own torque (a hardening's K misfit at large
    deflections, a function of the deflection that the binned periodogram spreads over every
    wavenumber) sits beside the ripple and may take the periodogram's highest peaks, so
    that the period of a ripple tested second is missing from its grid. Every other
    attribute (the signals, the nominal's parameters) is `nom`'s."""

    def __init__(self, nom: Nominal, base: Stacked):
        y, W, _ = base.design()
        self._nom = nom
        self.residual = y - W @ nom.fit(y, W)[0]

    def __getattr__(self, name: str):
        return getattr(self._nom, name)


class _Fitted:
    """`nom`'s rows with the parameter values of another fit (names, X): what an effect's
    `reference` reads."""

    def __init__(self, nom: Nominal, names: Sequence[str], X: np.ndarray):
        self.sig, self._nom = nom.sig, nom
        self._values = dict(zip(names, (float(x) for x in X)))

    def value(self, name: str) -> float:
        return self._values[name] if name in self._values else self._nom.value(name)


def predict(nom: Nominal, c: Candidate | None) -> np.ndarray:
    """The residual on `nom`'s rows (possibly another log's) of the nominal model (c None,
    with nom.X) or of candidate c, with the causes named before it, with its own parameters
    and fixed values: cross-validation."""
    if c is None:
        return nom.residual
    y, W, _ = design_many(nom, c.base + ((c.effect, c.fixed),))
    return y - W @ np.asarray(c.X)


def joint_parameters(nom: Nominal, causes: Sequence[Candidate]) -> list[tuple[str, dict]]:
    """Every named cause with its parameters from one fit of the nominal extended by all of
    them (the last cause's, whose design stacks the ones before it): a cause named earlier
    was fitted without the later ones, and its own values would count twice what they share
    (EMPS: an asymmetric friction fitted alone takes up part of the offset)."""
    if not causes:
        return []
    last = causes[-1]
    values = dict(zip(last.names, last.X))
    return [(name, EFFECTS[name].params(values, fixed, nom))
            for name, fixed in last.base + ((last.effect, last.fixed),)]
