"""A log whose loop reaches its torque limit: which rows the inverse view may use, and what the
answer says when neither view can decide (docs/effects.md, identification.saturation).

**Two inverse views.** A clipped torque sample may not be the torque the axis received (a
current sensor or an ADC at the end of its range, a flat top), so by default the rows within
reach of one are left out (identification.saturation.exclude_clipped's reach). At the
metadata's `tau_max` the clip is the controller's own (docs/controller.md: tau_m[k] =
clip(kv e[k] + I[k], -tau_max, tau_max)): the logged torque there is the command the drive
applied, the input the closed-loop replay gives its plant too (bench.sim.replay), and the
equations of eqs. (5)-(6) hold on those rows as on any other. A torque lag that drives the loop
into its limit clips a third of the samples and more, in every period of the limit cycle:
the rows out of reach of them are a few percent of the experiment, too few for the nominal
model itself (Jm three times off on a pendulum's 31 rows of 820), and nothing passes on them.

So when the first view cannot decide (nothing passes and its rows are under
verdict.USABLE_MIN of the experiment's) and the clip is at the metadata's `tau_max`, the
inverse view is run again on every row (`limit_applied`), each of its tests at half its
level: the two views split the level as a lag's two bands do (identification.discrepancy.
lag_band), and the chance that a clean clipped log names anything is at most ALPHA from the
first view plus ALPHA / 2 from the second.

**A cause beside the clip's.** On those few rows the clip leaves the slow part of the
experiment (the motor far from its limit), where a lag, whose evidence grows with frequency,
has nothing to show; a cause that acts at low speed or at the mode (a spring damping) can
pass there. So when causes pass on under USABLE_MIN of the experiment's rows and the clip is
at `tau_max` (`stopped_short`), the rounds' stop there does not say that the experiment holds
no further cause either, and the every-row view is run too, with the same split level. Its
answer is taken when it names every cause the first view names and more (`names_more`), and
its judged answer keeps them all (bench.analysis.diagnose.run); otherwise the first view's
causes stand on their own rows, as they were named without it. The bound above holds: the
second view's tests, and their level, are those it runs when the first view names nothing.

A lag or a hardening tested in two bands
(identification.discrepancy.lag_band) runs its wide band's view only where the chooser's band
fails; one whose chooser's band passed at the whole level but fails at half of it gets that
view now, at half the level too (split_level's `band`): the tests are those the every-row view
would have run at half its level from the start, so the bound above holds. A lag shows at the
top of the sweep, which the chooser's band cuts: on every row of a pendulum clipped by its lag
the wide band's t is several times the chooser's. A cause the second view names is then judged by
the forward view as any other (bench.analysis.diagnose.verdict.gain_reason: the replay
applies the same clip), and must be confirmed there: the extended model's replay reaches the
limit more as the log does than the nominal's, or, for a lag named first (or after the
causes below), the loop
linearised with it grows where the nominal's decays, at the frequency of the log's clipped
oscillation (verdict.every_row_reason, bench.analysis.diagnose.stability).

**A cause before the lag.** On every row a cause whose column the lag's leaves nearly
untouched (a constant torque) can pass first, against the nominal, and the lag after it: the
two describe the log together, and a replay from rest that does not reach the limit cycle
judges the cause before the lag no better than the lag itself. Tested against the nominal, that
cause might have taken part of the lag's own misfit at the cycle; so each cause the every-row
view names before its lag, and the first view does not name, is fitted and tested again on
top of the model holding the lag and the other named causes, at the same split level
(`held_before_lag`, identification.discrepancy.inverse.against_others: the rule for a set of
causes, each against the model holding all the others). When each passes there, the loop's
stability with the lag confirms the set as it confirms a lag named first; otherwise it
confirms nothing. The bound above holds: the set is named only when its every-row
tests pass at their split level, and the on-top tests add a condition to those.

When the second
view names nothing either, or cannot be run (a flat
top, no `tau_max`), the answer is "inconclusive" with the share of clipped samples, the rows
each view used, and the held-out share each candidate explains in each.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from jointbench.identification.discrepancy import InverseDiagnosis, diagnose_inverse
from jointbench.identification.discrepancy.candidates import Candidate
from jointbench.identification.discrepancy.inverse import (NotNamed, against_others, not_named,
                                                           passes)
from jointbench.identification.discrepancy.lag_band import LagBand, second_view
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log
from jointbench.identification.saturation import at_limit, clipped_samples

USABLE_MIN = 0.5   # the first view decides "none" on at least half of the experiment's rows
VIEWS = 2          # the inverse views a clipped log's hypotheses are split over


@dataclass(frozen=True)
class ClippedViews:
    """What a clipped log's inverse views used and found: the clipped share, the rows of the
    first view (out of reach of the clip) and of the second (every row, the clip taken as
    applied; None when it did not run, `why` says why), and each view's held-out share per
    candidate."""

    clipped_pct: float
    how: str
    rows_kept: int
    rows: int
    first: dict[str, float]
    second: dict[str, float] | None = None
    why: str = ""        # why the second view did not run ("" when it did)
    named_by: str = ""   # "every row" when the answer's causes come from the second view
    # the loop's stability that confirms a lag named on every row (diagnose.stability)
    loop: dict | None = None
    first_named: tuple[str, ...] = ()   # the causes the first view names (stopped_short)
    # the causes named on every row before a torque lag, not by the first view, each passing
    # on top of the model holding the lag and the others: (effect, t, t_bar) (held_before_lag)
    before_lag: tuple[tuple[str, float, float], ...] = ()

    def text(self) -> str:
        """The shares in words, for the inconclusive reason and the report."""
        out = (f"{self.clipped_pct:.3g} % of the torque samples are clipped ({self.how}); on "
               f"the {self.rows_kept} of {self.rows} regression rows out of their reach "
               f"({100 * self.rows_kept / max(1, self.rows):.3g} %) the candidates explain "
               f"{_shares(self.first)} of the held-out residual")
        if self.second is not None:
            out += (f"; on every row, the torque at tau_max taken as applied (each test at "
                    f"1/{VIEWS} of its level), {_shares(self.second)}")
        elif self.why:
            out += f"; {self.why}"
        if self.named_by:
            out += f"; the named causes are named on {self.named_by}"
        return out

    def held_text(self) -> str:
        """The causes named before the lag on every row, each on top of the model holding
        the lag and the others (held_before_lag), in words; "" when there are none."""
        if not self.before_lag:
            return ""
        tests = ", ".join(f"{e} t = {t:.3g} (bar {bar:.3g})" for e, t, bar in self.before_lag)
        return (f"named before the lag on every row, {tests} on top of the model holding the "
                f"lag and the other named causes: the loop's stability with the lag confirms "
                f"the set")

    def to_json(self) -> dict:
        out: dict = {"clipped_pct": self.clipped_pct, "how": self.how,
                     "rows_kept": self.rows_kept, "rows": self.rows,
                     "heldout_pct": self.first}
        if self.second is not None:
            out["heldout_pct_every_row"] = self.second
        if self.why:
            out["why_not_every_row"] = self.why
        if self.named_by:
            out["named_by"] = self.named_by
        if self.loop is not None:
            out["loop_stability"] = self.loop
        if self.before_lag:
            out["before_lag"] = [{"effect": e, "t": t, "t_bar": bar}
                                 for e, t, bar in self.before_lag]
        return out


def _shares(shares: dict[str, float]) -> str:
    return ", ".join(f"{e} {v:.3g} %" for e, v in shares.items()) or "nothing (none testable)"


def heldout_shares(inv: InverseDiagnosis) -> dict[str, float]:
    """Each testable first-round candidate's held-out share [%], in the ranking's order."""
    return {c.effect: float(c.heldout_pct) for c in inv.candidates if c.testable}


def _few_rows(inv: InverseDiagnosis) -> bool:
    """The first view's rows are under USABLE_MIN of the experiment's."""
    keep = inv.nominal.sig.keep
    return keep is not None and len(keep) > 0 and keep.mean() < USABLE_MIN


def undecided(inv: InverseDiagnosis) -> bool:
    """The first view names nothing from under USABLE_MIN of the experiment's rows."""
    return not inv.causes and _few_rows(inv)


def stopped_short(inv: InverseDiagnosis) -> bool:
    """The first view names causes, and stops its rounds, from under USABLE_MIN of the
    experiment's rows (module docstring: a cause beside the clip's)."""
    return bool(inv.causes) and _few_rows(inv)


def names_more(every: InverseDiagnosis, first: InverseDiagnosis) -> bool:
    """The every-row view names every cause the first view names, and more."""
    a, b = ({c.effect for c in x.causes} for x in (first, every))
    return a < b


def _split(c: Candidate) -> Candidate:
    return replace(c, views=c.views * VIEWS) if c.testable else c


def _split_cause(c: Candidate, band: LagBand | None) -> Candidate:
    """A named cause `c` at 1/VIEWS of its level. A torque lag or a hardening whose chooser's
    band passed at the unsplit level was named without its wide band's view (lag_band.
    second_view runs it only where the chooser's band fails): when the chooser's band fails
    at the split level, that view is run now, at the same split level, as it would have been
    had the inverse view been run at that level from the start."""
    s = _split(c)
    if s.significant or band is None or c.second is not None:
        return s
    w = second_view(band, c, c.base, split=VIEWS)
    return s if w is c else w


def split_level(inv: InverseDiagnosis, band: LagBand | None = None) -> InverseDiagnosis:
    """`inv` with every test at 1/VIEWS of its level: the causes kept while each, in order,
    still passes (a later cause was tested on top of the ones before it), the others not
    named (kind "failed", with why). `band`: the wide band of `inv`'s log (lag_band.LagBand,
    every row), where a named lag or hardening gets its second view at the split level
    (_split_cause); None: none."""
    causes: tuple[Candidate, ...] = ()
    dropped: list[NotNamed] = []
    for c in inv.causes:
        s = _split_cause(c, band) if not dropped else _split(c)
        if s.significant and not dropped:
            causes += (s,)
        else:
            why = (s.why_not or "a cause before it is not named") + \
                f" (every row, each test at 1/{VIEWS} of its level)"
            dropped.append(NotNamed(c.effect, "failed", why, s.test, c.round))
    if dropped and inv.masked is not None and inv.masked.named:
        # the masked pair's two, each tested on top of the other: both or neither
        pair = {inv.masked.first, inv.masked.second}
        dropped = [NotNamed(c.effect, "failed", f"it was tested on top of "
                            f"{(pair - {c.effect}).pop()}, which is not named (every row, "
                            f"each test at 1/{VIEWS} of its level)", s.test, c.round)
                   for c, s in zip(inv.causes, causes)] + dropped
        causes = ()
    kept = {c.effect for c in causes}
    given = tuple(n for n in inv.not_named if n.kind in ("floor", "left_out"))
    # the causes as split above (a second view run), every other candidate split alone
    named = {id(c): s for c, s in zip(inv.causes, causes)}
    out = replace(inv, causes=causes,
                  candidates=tuple(named.get(id(c)) or _split(c) for c in inv.candidates),
                  rounds=tuple(tuple(named.get(id(c)) or _split(c) for c in r)
                               for r in inv.rounds),
                  notes=tuple(n for n in inv.notes
                              if kept & set(n.split(":", 1)[0].split(" or "))),
                  alternatives=tuple(a for a in inv.alternatives if a.named in kept))
    return replace(out, not_named=not_named(out, tuple(dropped) + given))


def held_before_lag(every: InverseDiagnosis, first_named: tuple[str, ...],
                    band: LagBand) -> tuple[tuple[str, float, float], ...]:
    """The causes the every-row view `every` names before its torque lag that the first view
    does not name, each fitted and tested again on top of the model holding the lag and the
    other named causes (inverse.against_others) at 1/VIEWS of its round's level
    (_split_cause): (effect, t, t_bar) of each, () when there is no lag after such a cause or
    one of them does not pass there (module docstring: a cause before the lag)."""
    names = [c.effect for c in every.causes]
    if "torque_lag" not in names:
        return ()
    i = names.index("torque_lag")
    out = []
    for j in (j for j in range(i) if names[j] not in first_named):
        s = _split_cause(against_others(every.nominal, every.causes, j, band), band)
        if not passes(s):
            return ()
        out.append((names[j], float(s.test.t), float(s.test.bar)))
    return tuple(out)


def clipped_inverse(log: Log, settings: FilterSettings,
                    inv: InverseDiagnosis) -> tuple[InverseDiagnosis, ClippedViews | None]:
    """The inverse view the answer rests on, and what the clipped log's views found (None
    for a log without clipped samples): the first view `inv` (rows out of reach of the
    clip), or, when it cannot decide or stops short and the clip is at the metadata's
    tau_max, the second (every row) if it names a cause at its split level and every cause
    the first names, and more (module docstring)."""
    clip = clipped_samples(log)
    if not clip.count:
        return inv, None
    keep = inv.nominal.sig.keep
    rows = len(keep) if keep is not None else len(inv.nominal.sig.index)
    kept = int(np.count_nonzero(keep)) if keep is not None else rows
    views = ClippedViews(clipped_pct=100 * clip.share, how=clip.how, rows_kept=kept, rows=rows,
                         first=heldout_shares(inv),
                         first_named=tuple(c.effect for c in inv.causes))
    if not (undecided(inv) or stopped_short(inv)):
        return inv, views
    if not at_limit(log).any():
        if inv.causes:   # they stand on their own rows
            return inv, views
        return inv, replace(views, why="the clip is not at the metadata's tau_max (a flat "
                            "top, not the controller's own clip): its torque is not known to "
                            "be the one applied, so its rows stay out")
    band = LagBand(log, settings, limit_applied=True)
    every = split_level(diagnose_inverse(log, settings, limit_applied=True), band)
    views = replace(views, second=heldout_shares(every))
    if every.causes and (not inv.causes or names_more(every, inv)):
        return every, replace(views, named_by="every row",
                              before_lag=held_before_lag(every, views.first_named, band))
    return inv, views
