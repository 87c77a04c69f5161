"""The inverse view's verdict: every effect tested against the nominal model of a log and
ranked; then, once a cause is named, the others tested again against the nominal extended by
it, and every one that passes named in turn.

A round tests every remaining effect against its reference (identification.discrepancy.
heldout: held-out folds, a one-sided segment test at ALPHA / m, m the number of effects left
to test: Holm's step-down Bonferroni, so that the chance of naming any effect the log does not
carry stays under about ALPHA. The effects the log does not carry are all among those left
until one of them is named, so the round where that would first happen tests each at ALPHA / m
or less, m at least their number. (A bar of ALPHA / (every test run so far), 15 tests in the
second round of a log with q, 7 of one without, asked EMPS's offset for t > 4.18 where it has
3.93; Holm asks 3.86.) A torque lag's hypothesis is tested in two bands on a log with a wide
band, each test at half its level, and so are a hardening's, its second view at large
deflections, and a backlash's (identification.discrepancy.lag_band). The named cause of a
round is, among the significant ones, the one that explains the most of the held-out
residual, unless a simpler significant
one explains it as well: the richer is then named only if what it adds to the simpler is
significant (_simplest_first), and where the log cannot tell them apart the answer says
"one of A or B": the named cause carries the other as its alternative (Alternative);
between an effect and the one it reduces to (an asymmetric friction and an offset) the choice,
once one of them is significant, is a two-way decision at its own level (_which).

**Naming is a claim with its test.** A cause is named only with a test that passes at the
level of the round it entered (Candidate.test: the chooser's band's, or the second band's
that confirmed a lag), and every path that names keeps that: the parsimony choices name a
candidate that is itself significant; a cause refitted after another is dropped (_chain)
is tested again and named only if it passes again.

**Stopping rule.** The rounds stop when the next cause does not pass at its round's level,
or when, in a later round, it explains less than FLOOR of the held-out residual of the
equations it acts in, in the view its test passed (heldout.MATERIAL: the segment test asks a
typical segment of those rows for more than that share, and the share over the whole log is
the floor a cause must also reach: below
it the cause takes up what the mismatches of the log's own numerics remove, a dead band at
the encoder's resolution, a simulator's small damping, the first cause's residual misfit,
0.1 to 3 % of the held-out residual on the bench's logs, heldout's docstring).

**More than two causes** (_leave_one_out): each must pass on its own, against the model
holding all the others (their values from the joint fit), at the level of the round it
entered; the weakest that fails is dropped, the others fitted again in order (_chain: one
that fails against the ones before it is tried again on top of the ones kept after it; a
later cause that reduces to the dropped one takes its place, _in_place), and again until
all pass. The dropped are listed with their test.

**One of A or B** (_alternatives): a significant candidate of a round that is not named,
whose held-out errors the segment test without margin cannot separate from the named
cause's in either direction at DECIDE, explains the same thing; so does the other of a
parsimony choice that the log cannot make (_simplest_first: neither adds to the other, an
offset and an asymmetric friction while the motor moves). The answer says "one of A or B",
with the share each explains, in its text and as the named cause's alternative, rather than
choosing silently. So does the effect a named cause reduces to, where it passed its own test
in that round and the log holds no information on it beside the named cause's parts
(_shared: an offset beside an asymmetric friction whose motor never rests, the asymmetry's
Coulomb part then a constant on every row). So does the other of two laws of the spring that
differ only inside their band (a backlash and a hardening), fitted in the named one's round,
where the segment test does not find the named one's held-out errors smaller than its own at
DECIDE, whether it passed its own test or not (_spring_alternatives).

**The weaker of a pair against the model holding the stronger.** A round whose top ties
with another significant candidate (_tied: the test above cannot separate them), or with one
that acts only in equations the top does not (_elsewhere: each is measured where the other
acts only through the shared parameters' refit), cannot choose
alone, but the two may lead to different next rounds: a gravity torque left out shrinks the
homogeneous link equation, and the torque of the mean deflection then reappears in the motor
equation as a constant that an offset takes up as well as gravity does. The next round is
run on top of each (_ahead), and the tied candidate is named when it, with the cause its next
round names, predicts the held-out rows better than the top with its own, at DECIDE; the one
left is listed with why and is no "one of A or B". Likewise a parsimony choice the round
could not make (an offset named for an asymmetric friction) is made again once the rounds
stop, against the model holding the causes named beside it (_redecided).

**Two that pass only together** (identification.discrepancy.masked): when no round names
anything, the two best candidates are fitted together; where the pair passes and each passes
on top of the other, both are named, each with that test; where one alone passes on top of
the other, it is named with that test, and the rounds go on on top of it: the weaker of the
pair is tested against the model holding the stronger, in the view where it is visible
(_views).

Every effect tested and not named is listed apart with why (NotNamed).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np
from scipy import stats

from jointbench.identification.discrepancy.candidates import (Candidate, HeldOutTest, candidate,
                                                              reference, second_of_spring)
from jointbench.identification.discrepancy.heldout import (ALPHA, MATERIAL, evidence,
                                                           segment_log_ratios,
                                                           segment_t, t_bar)
from jointbench.identification.discrepancy.lag_band import (LagBand, second_view,
                                                           where_visible)
from jointbench.identification.discrepancy.masked import MaskedPair, masked_pair
from jointbench.identification.discrepancy.nominal import Nominal, nominal, with_link_law
from jointbench.identification.effects import EFFECTS, NONE
from jointbench.identification.effects.base import FOLD_FITS
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log

# The level of the two-way choice between an effect and the one it reduces to (_which): a
# single decision between two alternatives once one of them is established, not a search for
# effects, so neither Holm's division by m nor ALPHA's guard against a spurious effect applies.
DECIDE = 0.05

# The effects a log without q can test: those the registry says need no link position.
RIGID_TESTS = tuple(name for name, e in EFFECTS.items() if not e.needs_link)
WHY_NOT_RIGID = ("it acts between the motor and the link or on the link: without the link "
                 "position q the rigid motor-side model cannot separate it")
WHY_IN_NOMINAL = ("the nominal model holds it: eq. (13)'s link Coulomb friction FS is "
                  "identified with the nominal parameters (a diagnosis against a model "
                  "without link friction can name it)")


# A later round's cause must explain more than this share of the held-out residual in the view
# its test passed (module docstring: the stopping rule).
FLOOR = MATERIAL


@dataclass(frozen=True)
class NotNamed:
    """An effect tested and not named: why (`kind` one of "failed", "unphysical", "floor",
    "collinear", "alternative", "left_out", "untestable"), in words, and its last test."""

    effect: str
    kind: str
    why: str
    test: HeldOutTest | None = None
    round: int = 0

    def to_json(self) -> dict:
        out = {"effect": self.effect, "kind": self.kind, "why": self.why, "round": self.round}
        if self.test is not None:
            out["test"] = self.test.to_json()
        return out


def one_of(note: str) -> frozenset[str]:
    """The two effects a note or an alternative's text opens with ("one of A or B: ..." or
    "A or B: ..."); empty when it opens with no such pair."""
    head = note.split(":", 1)[0].removeprefix("one of ")
    pair = frozenset(head.split(" or "))
    return pair if len(pair) == 2 and all(x in EFFECTS for x in pair) else frozenset()


@dataclass(frozen=True)
class Alternative:
    """One of A or B: the named cause `named` and a candidate `other` of the same round that
    the log cannot tell from it, with their shares of the held-out residual. Either their
    held-out errors, compared directly, cannot be separated in either direction at DECIDE
    (_alternatives: t, the named's errors smaller than the other's, t_back the converse), or
    the parsimony choice between them could not be made (`how` "nested", _simplest_first: t
    what the named adds on top of the other, NaN where not computed, t_back the converse;
    `text` the note that says so)."""

    named: str
    other: str
    named_pct: float
    other_pct: float
    t: float        # the named's held-out errors smaller than the other's
    t_back: float   # the converse
    round: int = 1
    how: str = "direct"   # "direct" (_alternatives), "nested" (the parsimony choice),
    #                       "shared" (the part two effects share, _shared) or "same_law"
    #                       (two laws of the spring, _spring_alternatives)
    text: str = ""        # the note, for "nested", "shared" and "same_law"

    def describe(self) -> str:
        if self.text:
            return self.text
        return (f"one of {self.named} or {self.other}: held out {self.named} explains "
                f"{self.named_pct:.3g} %, {self.other} {self.other_pct:.3g} % of the residual, "
                f"and the segment test cannot separate them (t = {self.t:.3g} and "
                f"{self.t_back:.3g}, the bar t > {t_bar(DECIDE):.3g}); {self.named} is named")

    def stated_in(self, notes: tuple[str, ...]) -> bool:
        """A parsimony note (_apart, "one of A or B: ..." or "A or B: ...") already says it."""
        return any(one_of(n) == {self.named, self.other} for n in notes)

    def to_json(self) -> dict:
        return {"named": self.named, "other": self.other, "named_heldout_pct": self.named_pct,
                "other_heldout_pct": self.other_pct, "t": self.t, "t_back": self.t_back,
                "alpha": DECIDE, "round": self.round, "how": self.how,
                "text": self.describe()}

    def of_cause(self) -> dict:
        """The named cause's entry for it (diagnose --json: causes[].alternatives)."""
        return {"effect": self.other, "heldout_pct": self.other_pct,
                "named_heldout_pct": self.named_pct, "round": self.round, "how": self.how,
                "text": self.describe()}


@dataclass(frozen=True)
class InverseDiagnosis:
    nominal: Nominal
    candidates: tuple[Candidate, ...]   # first round, ranked, best first; untestable last
    causes: tuple[Candidate, ...] = ()  # every named cause in order, each against the ones
    #                                     before it (causes[0] is candidates[0])
    notes: tuple[str, ...] = ()         # ambiguities of the named causes (_simplest_first)
    rounds: tuple[tuple[Candidate, ...], ...] = ()   # every round's candidates, ranked
    not_named: tuple[NotNamed, ...] = ()   # every effect tested and not named, with why
    alternatives: tuple[Alternative, ...] = ()   # one of A or B (_alternatives)
    stopped: str = ""                   # why the rounds stopped
    masked: MaskedPair | None = None    # nothing named: the two best fitted together (masked)

    @property
    def named(self) -> Candidate | None:
        return self.causes[0] if self.causes else None

    @property
    def named_cause(self) -> str:
        return self.named.effect if self.named else NONE

    @property
    def why_none(self) -> str:
        """Why no effect is named ("" when one is): the best testable candidate's failed bar."""
        if self.named is not None:
            return ""
        tested = [c for c in self.candidates if c.testable]
        if not tested:
            return "no effect is testable on this log"
        best = tested[0]
        pair = f"; {self.masked.describe()}" if self.masked is not None else ""
        return (f"no effect is significant: the best, {best.effect} (explains "
                f"{best.heldout_pct:.3g} % of the held-out residual, {best.explained_pct:.3g} % "
                f"in sample), fails: {best.why_not}{pair}")


def _rank(cands: list[Candidate]) -> list[Candidate]:
    # Significant ones first, by the share of the held-out residual they remove; then the
    # physical fits, then the unphysical, each by the same share.
    return sorted(cands, key=lambda c: (not c.testable, not c.significant, bool(c.unphysical),
                                        -c.heldout_pct))


def _model(causes: tuple[Candidate, ...]) -> tuple[tuple[str, dict], ...]:
    """The named causes with their values as the last one's fit has them (a cause that shapes
    the same law as one before it searches that one's value again: candidates._coupled)."""
    if not causes:
        return ()
    last = causes[-1]
    return last.base + ((last.effect, last.fixed),)


def _round(nom: Nominal, names: list[str], causes: tuple[Candidate, ...],
           band: LagBand, k: int = 1) -> tuple[list[Candidate], str, Alternative | None]:
    """One round: the candidates ranked, the one to name first at the top, a note when the
    log cannot tell a richer candidate from it ("" otherwise: _simplest_first) and, when it
    cannot, that candidate as the alternative of the one to name; the lag tested in the wide
    band too (lag_band)."""
    m = len(names)
    model = _model(causes)
    ref = reference(nom, model, m=m)
    if model:   # the link friction's law with the causes in the model (nominal.with_link_law)
        nom = with_link_law(nom, ref.base.design())
        ref = reference(nom, model, m=m)
    n = len(nom.sig.index)
    cands = [replace(_views(band, candidate(nom, name, ref), model, n), round=k)
             for name in names]
    return _simplest_first(_rank(cands), nom, m)


Round = tuple[list[Candidate], str, Alternative | None]   # _round's answer


def _tied(top: Candidate, b: Candidate, n: int, later: bool) -> bool:
    """`b` explains the same thing as the round's `top`: it passes its own test (in a later
    round, above the floor too), neither reduces to the other (_which decides those), and
    the segment test without margin cannot separate their held-out errors in either
    direction at DECIDE."""
    if not b.significant or (later and not b.test.own_share > 100 * FLOOR):
        return False
    if top.heldout_errors is None or b.heldout_errors is None:
        return False
    if top.effect == EFFECTS[b.effect].reduces_to or b.effect == EFFECTS[top.effect].reduces_to:
        return False
    return _better(b, top, n)[1] >= DECIDE and _better(top, b, n)[1] >= DECIDE


def _elsewhere(top: Candidate, b: Candidate, later: bool) -> bool:
    """`b` passes its own test (in a later round, above the floor too) and acts only in
    equations the round's `top` does not (a gravity torque on the link, an offset on the
    motor): neither reduces to the other, and each is measured on rows the other changes
    only through the shared parameters' refit. The round's reference holds neither, so the
    misfit the one left out leaves in the shared parameters is what the other takes up (the
    link equation shrunk by a gravity left out puts its mean deflection's torque in the
    motor equation as a constant): the round's ranking alone does not choose between them,
    and the next round on top of each does (_ahead)."""
    if not b.significant or (later and not b.test.own_share > 100 * FLOOR):
        return False
    if not top.acts or not b.acts or set(top.acts) & set(b.acts):
        return False
    return not (top.effect == EFFECTS[b.effect].reduces_to
                or b.effect == EFFECTS[top.effect].reduces_to)


def _chain_errors(nom: Nominal, first: Candidate, after: Round) -> tuple[np.ndarray, str]:
    """The held-out errors of `first` with the cause the next round names on top of it (if
    its test passes there, above the floor, and `first` stays a physical instance of its
    effect in their joint fit: _still_physical), and that cause's name ("" for none)."""
    r = after[0]
    if (r and r[0].significant and r[0].test.own_share > 100 * FLOOR
            and _still_physical(nom, first, r[0])):
        return r[0].heldout_errors, r[0].effect
    return first.heldout_errors, ""


def _turned(nom: Nominal, first: Candidate, after: Round) -> str:
    """Why `first` fails its own check in the joint fit with the cause its next round names
    (`after`'s top, when that passes there above the floor: _still_physical); "" when it
    does not, or when that round names nothing."""
    r = after[0]
    if not (r and r[0].significant and r[0].test.own_share > 100 * FLOOR):
        return ""
    return _check(nom, first, r[0])


def _check(nom: Nominal, first: Candidate, then: Candidate) -> str:
    """`first`'s effect's own check (Effect.check) with the values of `then`'s fit: its
    searched value as `then`'s base has it, its columns as the joint fit has them, and each
    held-out fold's training fit of them (FOLD_FITS), so that the check weighs an overshoot
    of its bound against the joint fit's own standard errors, as it does on `first`'s own
    fit (candidates._evaluate); "" when it passes or has none."""
    check, values = EFFECTS[first.effect].check, _joint_values(first, then)
    return "" if check is None or values is None else check(values, nom)


def _joint_values(first: Candidate, then: Candidate) -> dict | None:
    """`first`'s values in `then`'s joint fit, as its own check reads them on its own fit
    (candidates._evaluate): the searched value as `then`'s base has it, the columns, and each
    held-out fold's training fit of them; None when `then`'s base does not hold it."""
    fixed = dict(then.base).get(first.effect)
    if fixed is None:
        return None
    return {**fixed, **dict(zip(then.names, then.X)), FOLD_FITS: then.fold_fits}


def _beyond_se(nom: Nominal, first: Candidate, then: Candidate) -> float:
    """How many of its own standard errors `first`'s fit lies beyond its physical bound in
    `then`'s joint fit (Effect.beyond, the values as _check's); inf where it gives none."""
    far, values = EFFECTS[first.effect].beyond, _joint_values(first, then)
    return float("inf") if far is None or values is None else float(far(values, nom))


def _still_physical(nom: Nominal, first: Candidate, then: Candidate) -> bool:
    """`first`'s effect passes its own check (Effect.check) with the values of the fit of
    `then`, the cause named on top of it: its searched value as `then`'s base has it, its
    columns as the joint fit has them. A next cause that passes only where the first turns
    into another effect (a hardening whose stiffness below the engagement falls to 0 once a
    spring damping beside it takes the torque at the reversals: a dead band, which is
    backlash) does not continue the first's chain: that pair is not the first cause and a
    second one, and it cannot outpredict a chain whose first cause stays what it is."""
    return not _check(nom, first, then)


def _ahead(nom: Nominal, round_: list[Candidate], note: str, alt: Alternative | None,
           causes: tuple[Candidate, ...], band: LagBand,
           k: int) -> tuple[list[Candidate], str, Alternative | None, Round | None,
                            list[NotNamed]]:
    """The round's top against the candidates it ties with (_tied: a constant torque on the
    motor and a gravity whose rest is not the start, while the link stays near it): the
    round alone cannot choose, but each leads to a different next round. The weaker cause
    of a pair is visible only against a model holding the stronger one, and the round's
    reference without either is not that model: a gravity torque left out shrinks the
    homogeneous link equation (K, JL, ... scaled down together), whose mean deflection's
    torque then reappears in the motor equation as a constant; an offset takes it up, and a
    spring damping tested on top of that offset finds the link equation still shrunk. So
    the next round is run on top of each, and a tied candidate is named in the top's place
    when it with the cause its next round names predicts the held-out rows better than the
    top with its own (the segment test without margin over every row, at DECIDE, and the
    converse not). So is a significant candidate that acts only in equations the top does not
    (_elsewhere: an offset on the motor, gravity on the link): each is measured where the
    other acts only through the refit, and the round's ranking cannot choose between them;
    where neither chain does better and neither holds the other, the answer says "one of A
    or B" with the share each explains. So are the round's other significant candidates
    when the cause the top's next round names passes only by turning the top into another
    effect (_still_physical: that chain is the top alone). Returns the round (the chosen
    first), its note and alternative (dropped when about the top left), the next round on
    the chosen and the top left, listed with why."""
    top, n = round_[0], len(nom.sig.index)
    later = bool(causes)
    tied = any(_tied(top, b, n, later) or _elsewhere(top, b, later) for b in round_[1:])

    def after(c: Candidate) -> Round:
        rest = [x.effect for x in round_ if x is not c and x.testable]
        return _round(nom, rest, causes + (c,), band, k + 1) if rest else ([], "", None)

    chains: dict[str, tuple[Round, np.ndarray, str]] = {}

    def chain(c: Candidate) -> tuple[Round, np.ndarray, str]:
        if c.effect not in chains:
            a = after(c)
            chains[c.effect] = (a, *_chain_errors(nom, c, a))
        return chains[c.effect]

    def compare(a: Candidate, b: Candidate) -> tuple[float, float, float, float]:
        """t, p that b's chain predicts better than a's, and the converse."""
        (_, ea, _), (_, eb, _) = chain(a), chain(b)
        return (*segment_t(segment_log_ratios(ea, eb, n)),
                *segment_t(segment_log_ratios(eb, ea, n)))

    # the top's next round, which the rounds run anyway: where the cause it names passes
    # only by turning the top into another effect (_still_physical), the round's other
    # significant candidates are weighed against it as tied ones are
    broken = not tied and _turned(nom, top, chain(top)[0])
    if not (tied or broken):
        return round_, note, alt, chains[top.effect][0], []

    def rival(best: Candidate, b: Candidate) -> bool:
        return (_tied(best, b, n, later) or _elsewhere(best, b, later)
                or (broken and best is top and b.significant))

    best = top
    while True:   # the candidates tied with the one chosen so far, until none does better
        better = None
        for b in round_:
            if b.effect in chains and b is not best or b is best or not rival(best, b):
                continue
            t, p, t2, p2 = compare(best, b)
            if p < DECIDE <= p2:
                better = b
                break
        chain(best)
        if better is None:
            break
        best = better
    # the candidates whose chain did worse than the chosen one's: the tie is resolved
    out: list[NotNamed] = []
    _, _, next_best = chain(best)
    for b in round_:
        if b is best or b.effect not in chains:
            continue
        t, p, t2, p2 = compare(b, best)
        if (p >= DECIDE and p2 >= DECIDE and alt is None and not note
                and _elsewhere(best, b, later)
                and best.effect != chains[b.effect][2] and b.effect != next_best):
            # neither chain predicts the held-out rows better, and neither holds the other:
            # the log cannot say which of the two equations carries what they explain, and
            # the answer says so
            note = (f"one of {best.effect} or {b.effect}: they act in different equations, "
                    f"held out {best.effect} explains {best.heldout_pct:.3g} %, {b.effect} "
                    f"{b.heldout_pct:.3g} % of the residual (round {k}), and neither, with "
                    f"the cause its next round names, predicts the held-out rows better "
                    f"(t = {t:.3g}, the converse t = {t2:.3g}, the bar t > "
                    f"{t_bar(DECIDE):.3g}); {best.effect} is named")
            alt = _nested(best, b, t2, t, note)
            continue
        if not p < DECIDE <= p2:
            continue
        next_b = chains[b.effect][2]
        turned = _turned(nom, b, chains[b.effect][0])
        if turned and _near_bound(nom, b, best, chains[b.effect][0]):
            # the log does not exclude it as a description with the strength naming asks:
            # one of the two, as in the parsimony choice (_simplest_first, _near)
            nxt = chains[b.effect][0][0][0]
            note = (f"one of {best.effect} or {b.effect}: with {nxt.effect} on top of it, "
                    f"{b.effect}'s fit lies beyond its physical bound by "
                    f"{_beyond_se(nom, b, nxt):.3g} of its standard errors, within the "
                    f"round's bar t > {_beyond_bar(b.alpha, len(nxt.fold_fits)):.3g} "
                    f"({turned}); {best.effect}"
                    f"{f' and {next_best}' if next_best else ''} predict the held-out rows "
                    f"better than {b.effect} alone (t = {t:.3g}, the converse t = {t2:.3g}); "
                    f"{best.effect} is named for the two")
            alt = _nested(best, b, float("nan"), float("nan"), note)
            continue
        alone = (f"with {chains[b.effect][0][0][0].effect} on top of it, its fit is not a "
                 f"{b.effect} ({turned})" if turned else
                 f"alone the log cannot tell it from {best.effect}" if _tied(best, b, n, later)
                 else f"alone it acts in other equations than {best.effect}, whose misfit "
                 f"left out it takes up")
        out.append(NotNamed(b.effect, "left_out", (
            f"round {k}: {alone} (held out "
            f"{b.effect} explains {b.heldout_pct:.3g} %, {best.effect} {best.heldout_pct:.3g} "
            f"%), but {best.effect}{f' and {next_best}' if next_best else ''} predict the "
            f"held-out rows better than {b.effect}{f' and {next_b}' if next_b else ''} (t = "
            f"{t:.3g}, the converse t = {t2:.3g}, the bar t > {t_bar(DECIDE):.3g})"),
            b.test, k))
    if best is top:
        return round_, note, alt, chains[top.effect][0], out
    ordered = [best] + [c for c in round_ if c is not best]
    keep_note = note if best.effect in one_of(note) else ""
    keep_alt = alt if alt is not None and alt.named == best.effect else None
    return ordered, keep_note, keep_alt, chains[best.effect][0], out


def _near_bound(nom: Nominal, b: Candidate, best: Candidate, after: Round) -> bool:
    """`b`, whose joint fit with the cause its next round names (`after`'s top) fails its
    own check, reduces to the chosen `best` (an asymmetric friction and an offset) and lies
    beyond its bound there by no more than the round's bar (_beyond_bar) of its own standard
    errors: the tolerance under which an unphysical fit stays the alternative of the effect
    it reduces to (_near), applied to the joint fit as to its own."""
    return (EFFECTS[b.effect].reduces_to == best.effect
            and _beyond_se(nom, b, after[0][0])
            <= _beyond_bar(b.alpha, len(after[0][0].fold_fits)))


def _better(worse: Candidate | np.ndarray, better: Candidate, n: int) -> tuple[float, float]:
    """The segment test without margin (identification.discrepancy.heldout) that `better`'s
    held-out errors are smaller than `worse`'s, on the equations `better` acts in, or on the
    link equation where both are second causes of the spring's law beside a first cause of
    the spring (_of_spring: each tested over the link equation too, where the motor torque's
    noise does not dilute them): t and its one-sided p-value."""
    e0 = worse.heldout_errors if isinstance(worse, Candidate) else worse
    rows = better.acts
    if isinstance(worse, Candidate) and _of_spring(worse) and _of_spring(better):
        rows = (EFFECTS[better.effect].block,)
    return segment_t(segment_log_ratios(e0, better.heldout_errors, n, rows))


def _on_top(nom: Nominal, richer: Candidate, simpler: Candidate,
            m: int) -> tuple[float, float, bool]:
    """Does `richer` add to `simpler` what the log supports? `richer` fitted on top of
    `simpler` and the causes under it (as `simpler`'s fit has them), and the segment test
    without margin (_better) of its held-out errors against `simpler`'s: t, p (p = 1 for
    an unphysical fit) and whether that fit on top is physical."""
    c = candidate(nom, richer.effect, reference(nom, _model((simpler,)), m=m))
    t, p = _better(simpler, c, len(nom.sig.index))
    return t, (1.0 if c.unphysical else p), not c.unphysical


def beyond(richer: Candidate, simpler: Candidate, n: int = 0) -> float:
    """The share of `simpler`'s held-out residual that `richer` removes beyond it (both
    against the same reference): 1 - (1 - h_richer) / (1 - h_simpler), h the held-out shares
    (heldout_pct / 100); <= 0 when `richer` explains no more. Where both are second causes
    of the spring's law beside a first cause of the spring (candidates.second_of_spring:
    each tested over the link equation too), h the shares over the link equation, where the
    motor torque's noise does not dilute them (`n` the instants of a block, 0 when not
    given: every row)."""
    hs, hr = simpler.heldout_pct, richer.heldout_pct
    if n and all(_of_spring(c) for c in (richer, simpler)):
        hs, hr = (evidence(c.reference_errors, c.heldout_errors, n,
                           (EFFECTS[c.effect].block,)).acts_pct for c in (simpler, richer))
    left = 1.0 - hs / 100.0
    return 1.0 - (1.0 - hr / 100.0) / left if left > 0 else 0.0


def _of_spring(c: Candidate) -> bool:
    """`c` is a second cause of the spring's law, tested over the link equation too
    (candidates.second_of_spring), with its held-out errors."""
    return (c.effect in EFFECTS and second_of_spring(EFFECTS[c.effect], c.base)
            and c.heldout_errors is not None and c.reference_errors is not None)


def _material(richer: Candidate, simpler: Candidate, physical: bool, n: int = 0) -> bool:
    """Parsimony yields to the naming rule (the named cause explains the most held-out):
    `richer` explains materially more than `simpler` (it removes more than MATERIAL of what
    `simpler` leaves, the margin of identification.discrepancy.heldout) and its fit on top
    of `simpler` is physical. The segment test of what it adds can then miss it because it
    acts in a few segments (a hardening engaging only at the large deflections near the
    mode)."""
    return physical and beyond(richer, simpler, n) > MATERIAL


def _simplest_first(ranked: list[Candidate], nom: Nominal,
                    m: int) -> tuple[list[Candidate], str, Alternative | None]:
    """Parsimony among the significant: the best is named over a simpler significant
    candidate S (fewer parameters) only if what it adds to S predicts the held-out rows
    significantly better (it fitted on top of S, the segment test without margin at the
    round's level: the claim is its own part) or materially better (_material); otherwise S
    goes first, and the note says that the log cannot tell them apart. Between an effect and
    the one it reduces to (registry `reduces_to`: an asymmetric friction and an offset), in
    either order, the choice is two-way (_which): while the motor moves the Coulomb part of
    an asymmetry is a constant torque, and only its viscous part a FVm |qm'| differs, so
    compared directly, not nested, the share that differs goes either way by chance.

    Where the log cannot tell them apart (neither adds to the other), the one named carries
    the other as its alternative, "one of A or B" (Alternative, how "nested")."""
    if not ranked or not ranked[0].significant:
        return ranked, "", None
    best = ranked[0]
    sig = [c for c in ranked if c.significant]
    alpha = best.alpha
    first, note, alt = best, "", None
    # a richer effect that reduces to the best, significant or not (while the motor moves a
    # Coulomb-dominated asymmetric friction is an offset, and may explain a hair less), its
    # own fit physical or beyond its bound by less than the round's bar (_near): such an
    # asymmetry is never named (_which names only a significant one), but where the log
    # cannot tell the two apart it is the alternative of the offset named
    richer = next((c for c in ranked if c.testable and _near(c)
                   and EFFECTS[c.effect].reduces_to == best.effect), None)
    if richer is not None:
        named, note, alt = _which(nom, best, richer, m)
        if named:
            return [richer] + [c for c in ranked if c is not richer], note, alt
    for s in sig:
        if EFFECTS[first.effect].reduces_to == s.effect:
            named, why, which = _which(nom, s, first, m)
            if why:
                note, alt = why, which
            first = first if named else s
            continue
        if not s.k < first.k:
            continue
        t, p, physical = _on_top(nom, first, s, m)
        if p < alpha:
            continue
        if _material(first, s, physical, len(nom.sig.index)):
            note, alt = _apart(s, first, t, alpha, more=True, n=len(nom.sig.index)), None
            continue
        note = _apart(s, first, t, alpha, unphysical=not physical)
        alt = _nested(s, first, t, float("nan"), note)
        first = s
    if alt is not None and alt.named != first.effect:
        alt = None
    return [first] + [c for c in ranked if c is not first], note, alt


def _near(c: Candidate) -> bool:
    """Physical, or unphysical by less than the round's bar (_beyond_bar at its alpha) of its
    own standard errors (Candidate.beyond_se): an asymmetric friction at its bound (one
    direction's Coulomb friction near zero) overshoots the bound by noise, and a log that
    excludes it as a description must do so with the strength that naming a cause asks."""
    return not c.unphysical or c.beyond_se <= _beyond_bar(c.alpha, len(c.fold_fits))


def _beyond_bar(alpha: float, folds: int) -> float:
    """The bar at level `alpha` for a fit's distance beyond its physical bound in its own
    standard errors (Effect.beyond): that standard error is the delete-a-group jackknife over
    the `folds` training fits (effects.base.spread), whose variance has folds - 1 degrees of
    freedom, so the distance is a Student t with folds - 1 of them, not with the segment
    test's (t_bar); t_bar where there are no folds."""
    return float(stats.t.isf(alpha, folds - 1)) if folds > 1 else t_bar(alpha)


def _nested(simpler: Candidate, richer: Candidate, t: float, t_back: float,
            note: str) -> Alternative:
    """`richer` as the alternative of the named `simpler` where the parsimony choice cannot
    tell them apart: t what `richer` adds to `simpler`, t_back the converse (NaN where not
    computed); `note` says so."""
    return Alternative(simpler.effect, richer.effect, simpler.heldout_pct, richer.heldout_pct,
                       t_back, t, simpler.round, how="nested", text=note)


def _which(nom: Nominal, simpler: Candidate, richer: Candidate,
           m: int) -> tuple[bool, str, Alternative | None]:
    """The two-way choice between `richer` and the effect it reduces to, `simpler` (an
    asymmetric friction and an offset), once one of them is established (significant at the
    round's Holm level): is `richer` named, the note, and `richer` as the alternative of the
    named `simpler` when the log cannot tell them apart. Both nest in the model with both
    columns; the segment test without margin (_on_top) of that model against each gives t,
    what `richer` adds to `simpler`, and t2, what `simpler` adds to `richer`. `richer` is
    named when it is significant itself, its fit on top of `simpler` is physical, and what it
    adds passes at DECIDE while the converse does not; or, as any richer candidate, when what
    it adds passes at the round's level or is material (_material). Otherwise `simpler` is
    named: with the note that the log cannot tell them apart when neither adds to the other
    at DECIDE; without it when `simpler` adds and `richer` does not (an offset the
    asymmetry's shape cannot follow); with the note that the log carries a part of each when
    both add (`richer` is then tested on top of `simpler` in the next round, at that round's
    level).

    Why DECIDE = 0.05 and not the round's ALPHA / m: the round's level guards the family of "is anything
    there" tests, so that a log without an unmodelled effect names one with a chance under
    ALPHA. Once one of the two is significant at that level the guard is spent, and what is
    left is which of two descriptions of one torque the log supports: an offset named for an
    asymmetric friction and an asymmetry named for an offset are errors of the same cost, so
    the rule is symmetric (each is tested on top of the other at the same level, the
    simpler kept unless the richer's own part passes and the simpler's does not), and its
    level is the conventional one of a single test. Under the null (the richer's own part
    absent) the test without margin is conservative (the extra column only adds estimation variance to
    the held-out prediction): an offset is called an asymmetry with a chance under 5 %.
    The round's level asked the asymmetry's viscous part for t > 4.23, a bar for discovering
    an effect, where only the choice between two established descriptions was at stake."""
    alpha = simpler.alpha
    t, p, physical = _on_top(nom, richer, simpler, m)
    t2, p2, _ = _on_top(nom, simpler, richer, m)
    if richer.significant and physical and (p < DECIDE <= p2 or p < alpha):
        return True, "", None
    if richer.significant and _material(richer, simpler, physical):
        return True, _apart(simpler, richer, t, alpha, more=True), None
    if p2 < DECIDE <= p:
        return False, "", None
    both = p < DECIDE and p2 < DECIDE
    note = _apart(simpler, richer, t, DECIDE, t2, unphysical=not physical, both=both)
    if richer.unphysical:   # what keeps it from being named where its part adds
        note += f"; {richer.effect}'s own fit is unphysical ({richer.unphysical})"
    return False, note, None if both else _nested(simpler, richer, t, t2, note)


def _apart(simpler: Candidate, richer: Candidate, t: float, alpha: float,
           converse: float | None = None, more: bool = False, unphysical: bool = False,
           both: bool = False, n: int = 0) -> str:
    """The ambiguity note: `simpler` named (or `richer`, with `more`: it removes more than
    MATERIAL of `simpler`'s held-out residual, _material); `unphysical`: `richer` fitted on
    top of `simpler` is not physical, whatever its t; `both`: each adds to the other (_which),
    `simpler` named first. Where the log cannot choose (neither), the note opens with "one of
    A or B". `n`: the instants of a block, for the share `richer` removes beyond `simpler`
    (beyond)."""
    back = ("" if converse is None else
            f", what {simpler.effect} adds to {richer.effect} t = {converse:.3g}")
    fit = " (an unphysical fit)" if unphysical else ""
    link = (" over the link equation" if n and _of_spring(richer) and _of_spring(simpler)
            else "")
    named = (f"{richer.effect}, which removes {100 * beyond(richer, simpler, n):.3g} % of what "
             f"{simpler.effect} leaves{link}, is named" if more else
             f"the simpler, {simpler.effect}, is named" + (" first" if both else
                                                            " for the two"))
    what = ("this log carries a part of each that the other cannot follow" if both else
            "this log cannot tell them apart")
    head = "" if more or both else "one of "   # the log cannot choose: one of the two
    return (f"{head}{simpler.effect} or {richer.effect}: {what} "
            f"({richer.effect} explains {richer.heldout_pct:.3g} % of the held-out residual, "
            f"{simpler.effect} {simpler.heldout_pct:.3g} %; what {richer.effect} adds to "
            f"{simpler.effect} has t = {t:.3g}{fit}{back}, the bar t > {t_bar(alpha):.3g}); "
            f"{named}")


def diagnose_inverse(log: Log, settings: FilterSettings, effects: tuple[str, ...] | None = None,
                     link_friction: bool = True, limit_applied: bool = False) -> InverseDiagnosis:
    """Evaluate every effect of docs/effects.md against the nominal model of `log` (with the
    link Coulomb friction FS unless `link_friction` is False) and rank them; name the best
    significant one, then test the others on top of it, and so on (module docstring: the
    stopping rule, the leave-one-out test of more than two causes, one of A or B).

    ValueError when the log has q and the deflection q_m - q never changes (to the text's
    precision, 12 digits): the link then moves with the motor as one body, and nothing acting
    between them (eq. 5) is testable."""
    nom = nominal(log, settings, link_friction, limit_applied)
    if log.q is not None and (np.ptp(log.q_m - log.q)
                              <= 1e-9 * max(1.0, float(np.max(np.abs(log.q_m))))):
        raise ValueError(f"{log.path or 'the log'}: the deflection q_m - q never changes: "
                         "the link moves with the motor as one rigid body, so nothing between "
                         "them (the spring of eq. 5) can be tested; diagnose the log without "
                         "its column q (a rigid axis)")
    first: list[Candidate] = []
    names: list[str] = []
    for name in effects or tuple(EFFECTS):
        if not nom.sig.has_link and name not in RIGID_TESTS:
            first.append(Candidate(effect=name, testable=False, reason=WHY_NOT_RIGID))
        elif name in EFFECTS and EFFECTS[name].parameter in nom.names:   # FS of link_coulomb
            first.append(Candidate(effect=name, testable=False, reason=WHY_IN_NOMINAL))
        else:
            names.append(name)
    band = LagBand(log, settings, link_friction, limit_applied)
    ranked, note, alt = _round(nom, names, (), band, 1)
    causes, notes, nested, rounds, stopped, dropped, settled = _rounds(
        nom, (ranked, note, alt), (), band, [ranked])
    masked = None if causes else masked_pair(nom, ranked, len(names))
    lead = masked.lead if masked is not None else None
    if lead is not None:   # the stronger of a masked pair, then the weaker on top of it
        rest = [c.effect for c in ranked if c.testable and c.effect != lead.effect]
        nxt = _round(nom, rest, (lead,), band, 2)
        causes, notes, nested, rounds, after, dropped, settled = _rounds(
            nom, nxt, (lead,), band, [ranked, nxt[0]])
        stopped += (f"; {lead.effect} passes on top of {masked.other(lead.effect)} (the "
                    f"masked pair) and is named, the others tested on top of it; {after}")
    causes, left, again = _redecided(nom, causes, nested, rounds, band)
    dropped += left
    settled |= again
    notes = tuple(x for x in notes if x[0] in {c.effect for c in causes}
                  and one_of(x[1]) not in settled)
    causes, notes, left = _pruned(nom, causes, notes, band)
    dropped += left
    if len(causes) > 2:
        causes, left = _leave_one_out(nom, causes, band)
        dropped += left
        notes = tuple(x for x in notes if x[0] in {c.effect for c in causes})
    kept = {c.effect for c in causes}
    # a "one of A or B" note whose two effects are both named in the end says no more
    notes = tuple(x for x in notes if not (x[1].startswith("one of ") and one_of(x[1]) <= kept))
    alternatives = tuple(a for a in nested if a.named in kept and a.other not in kept
                         and any(one_of(n) == {a.named, a.other} for _, n in notes))
    alternatives += tuple(a for a in _alternatives(rounds, causes, len(nom.sig.index))
                          if not any({a.named, a.other} == {b.named, b.other}
                                     for b in alternatives)
                          and frozenset((a.named, a.other)) not in settled)
    alternatives += tuple(a for a in _spring_alternatives(rounds, causes, len(nom.sig.index))
                          if not any({a.named, a.other} == {b.named, b.other}
                                     for b in alternatives)
                          and frozenset((a.named, a.other)) not in settled)
    alternatives += _shared(nom, causes, rounds, alternatives)
    if masked is not None and masked.named:   # two that pass only together (masked)
        causes = masked.causes
        stopped += (f"; {masked.first} and {masked.second} pass together and each on top "
                    f"of the other (the masked pair): both are named")
        alone = {c.effect: c for c in ranked}
        dropped += [NotNamed(e, "failed", f"{alone[e].why_not}; in the masked pair, {why}",
                             alone[e].test, 1) for e, why in masked.skipped]
    # the first round's ranking, with the first named cause at the top
    top = [c for c in ranked if causes and c.effect == causes[0].effect] or ranked[:1]
    inv = InverseDiagnosis(nominal=nom, causes=causes, notes=tuple(n for _, n in notes),
                           candidates=tuple(top + _rank([c for c in ranked if c not in top]
                                                        + first)),
                           rounds=tuple(tuple(r) for r in rounds), alternatives=alternatives,
                           stopped=stopped, masked=masked)
    inv = replace(inv, not_named=not_named(inv, tuple(dropped)))
    nom.sig.release()
    band.release()
    return inv


def _rounds(nom: Nominal, first: Round, causes: tuple[Candidate, ...], band: LagBand,
            rounds: list[list[Candidate]]) -> tuple[
                tuple[Candidate, ...], tuple[tuple[str, str], ...], list[Alternative],
                list[list[Candidate]], str, list[NotNamed], set[frozenset[str]]]:
    """The rounds from `first` (the last of `rounds`, tested on top of `causes`) on: each
    names its top when it passes (a later round's above the floor too, module docstring: the
    stopping rule), after the look-ahead of a tie (_ahead), and the next round tests the
    rest on top of the causes named. Returns the causes, the notes (the cause each is about,
    the note), the parsimony choices the log could not make, the rounds, why they stopped,
    the effects left with why, and the ties the next round resolved."""
    round_, note, alt = first
    notes: tuple[tuple[str, str], ...] = ()   # (the cause it is about, the note)
    nested: list[Alternative] = []   # the parsimony choices the log could not make
    stopped, dropped = "", []
    settled: set[frozenset[str]] = set()   # ties the next round resolved (_ahead)
    while round_:
        top, k = round_[0], len(rounds)
        if not top.significant:
            stopped = (f"round {k}: no effect passes its test" if top.testable else
                       f"round {k}: no effect is testable")
            break
        if causes and not top.test.own_share > 100 * FLOOR:
            stopped = (f"round {k}: {top.effect} passes its test but explains "
                       f"{top.test.own_share:.3g} % of the held-out residual of the "
                       f"equations it acts in, under the floor of {100 * FLOOR:g} %")
            dropped.append(NotNamed(top.effect, "floor", stopped, top.test, k))
            break
        round_, note, alt, after, told = _ahead(nom, round_, note, alt, causes, band, k)
        top = round_[0]
        rounds[-1] = round_
        dropped += told
        settled |= {frozenset((top.effect, d.effect)) for d in told}
        causes += (top,)
        notes += ((top.effect, note),) if note else ()
        nested += [alt] if alt is not None and alt.named == top.effect else []
        rest = [c.effect for c in round_[1:] if c.testable]
        if not rest:
            stopped = f"round {k}: every effect is named"
            break
        round_, note, alt = after or _round(nom, rest, causes, band, k + 1)   # Holm
        rounds.append(round_)
    return causes, notes, nested, rounds, stopped, dropped, settled


def _redecided(nom: Nominal, causes: tuple[Candidate, ...], nested: list[Alternative],
               rounds: list[list[Candidate]],
               band: LagBand) -> tuple[tuple[Candidate, ...], list[NotNamed],
                                       set[frozenset[str]]]:
    """The parsimony choices the log could not make in their round (an offset named for an
    asymmetric friction, "one of A or B", how "nested"), made again once the rounds stop,
    against the model holding the causes named beside it (their values from the joint fit):
    the weaker of a pair is tested against the model holding the stronger. A torque lag left
    out of the reference leaves a phase error in the motor equation that the asymmetry's
    viscous part, a torque in phase with the speed, cannot follow, and the two-way choice
    (_which) then sees only the constant they share. Where, with the others held, the richer
    is named (_which at the level of the round the cause entered), it takes the simpler's
    place and every cause is fitted again in order (_chain), or, where that order cannot
    hold them, each on top of all the others (_held); the swap stands only if all of them
    pass there. Returns the causes, the simpler causes left with why, and the pairs
    settled (no longer "one of A or B")."""
    out: list[NotNamed] = []
    settled: set[frozenset[str]] = set()
    for alt in nested:
        names = [c.effect for c in causes]
        if (len(causes) < 2 or alt.named not in names or alt.other in names
                or EFFECTS[alt.other].reduces_to != alt.named):
            continue
        i = names.index(alt.named)
        values = dict(_model(causes))
        others = tuple((o, values[o]) for o in names if o != alt.named)
        m = _level_m(causes[i])
        ref = reference(nom, others, m=m)
        simpler, richer = candidate(nom, alt.named, ref), candidate(nom, alt.other, ref)
        if not _which(nom, simpler, richer, m)[0]:
            continue
        first = next((c for c in rounds[max(causes[i].round, 1) - 1] if c.effect == alt.other),
                     None)
        if first is None:
            continue
        chain, lost = _chain(nom, causes[:i] + (first,) + causes[i + 1:], band)
        if lost or len(chain) != len(causes):
            chain = _held(nom, others[:i] + ((richer.effect, richer.fixed),) + others[i:],
                          causes[:i] + (first,) + causes[i + 1:], band)
        if len(chain) != len(causes):
            continue
        t, p, _ = _on_top(nom, richer, simpler, m)
        t2, _, _ = _on_top(nom, simpler, richer, m)
        out.append(NotNamed(alt.named, "left_out", (
            f"round {causes[i].round} named it for the two, the log not telling it from "
            f"{alt.other} against the causes before it; against the model holding "
            f"{', '.join(o for o, _ in others)}, what {alt.other} adds to {alt.named} has "
            f"t = {t:.3g} (p = {p:.2g}), what {alt.named} adds to {alt.other} t = {t2:.3g}: "
            f"{alt.other} is named in its place"), simpler.test, causes[i].round))
        settled.add(frozenset((alt.named, alt.other)))
        causes = chain
    return causes, out, settled


def _held(nom: Nominal, model: tuple[tuple[str, dict], ...], causes: tuple[Candidate, ...],
          band: LagBand) -> tuple[Candidate, ...]:
    """`causes` where each, fitted again on top of all the others (`model`: their values as
    the two-way choice held them), passes its own test at the level of the round it entered
    (_against, _passes); () when one does not. The order of _chain asks the first cause to
    pass against the nominal alone, and a pair can describe the log only together: an
    asymmetric friction whose Coulomb part exceeds the Coulomb friction fitted without the
    torque lag beside it (the lag's phase error in the motor equation takes the friction's
    odd part down, the direction-dependent even part stays), and a lag that passes only once
    the constant torque is held. Each passing on top of the others is the rule for more than
    two causes (_leave_one_out)."""
    out = []
    for j, c in enumerate(causes):
        again = _against(nom, c, model[:j] + model[j + 1:], band)
        if not _passes(again):
            return ()
        out.append(again)
    return tuple(out)


def _level_m(c: Candidate) -> int:
    """The number of effects of the round `c` was tested in (its Holm level ALPHA / m)."""
    return max(1, round(ALPHA / c.alpha)) if c.alpha > 0 else len(EFFECTS)


def _against(nom: Nominal, c: Candidate, others: tuple[tuple[str, dict], ...],
             band: LagBand) -> Candidate:
    """`c`'s effect fitted and tested again on top of `others` (name, values), at the level
    of the round it entered, with the lag's second band: its own test there."""
    ref = reference(nom, others, m=_level_m(c))
    return replace(_views(band, candidate(nom, c.effect, ref), others, len(nom.sig.index)),
                   round=c.round)


def _views(band: LagBand, c: Candidate, model: tuple[tuple[str, dict], ...],
           n: int) -> Candidate:
    """`c` with its second view: a lag's or a hardening's in the wide band (lag_band.
    second_view); against a model holding another effect of the spring's law or damping, a
    backlash's or a spring damping's where it is visible (lag_band.where_visible: the weaker
    of a pair against the model holding the stronger)."""
    return where_visible(second_view(band, c, model), n, model)


def _passes(c: Candidate) -> bool:
    """Significant and, for a cause of a later round, above the floor in its test."""
    return c.significant and (c.round <= 1 or c.test.own_share > 100 * FLOOR)


def _at_bound(c: Candidate) -> Candidate:
    """`c`, a fit unphysical by less than the round's bar of its own standard errors (_near),
    as a physical one: the standard error of its distance beyond the bound holds the folds'
    noise alone, not the error of the split the bound is read from (an asymmetric friction's
    Coulomb part against the Coulomb friction, whose viscous-to-Coulomb split the log
    identifies worst), and a cause the rounds named is dropped as no physical instance of it
    only with the strength that naming a cause asks."""
    return replace(c, unphysical="") if c.unphysical and _near(c) else c


def _why_fails(c: Candidate) -> str:
    if not c.significant:
        return c.why_not
    return (f"it explains {c.test.own_share:.3g} % of the held-out residual of the "
            f"equations it acts in, under the floor of {100 * FLOOR:g} %")


def _chain(nom: Nominal, causes: tuple[Candidate, ...],
           band: LagBand) -> tuple[tuple[Candidate, ...], list[NotNamed]]:
    """`causes` fitted again in order, each against the ones kept before it at its own
    level; one whose test does not pass there is tried again once the others are kept, on
    top of them, until no more pass; one that never passes is not named (with why). A cause
    named on top of the one left out (a spring damping named on top of an offset that was
    an asymmetric friction's Coulomb part) is then tested against the causes that hold what
    that one held, not against a model that misses it. A fit beyond its physical bound by
    less than the round's bar of its standard errors counts as physical there (_at_bound)."""
    chain: tuple[Candidate, ...] = ()
    pending = list(causes)
    failed: dict[str, Candidate] = {}
    while pending:
        kept = []
        for o in pending:
            again = _at_bound(_against(nom, o, _model(chain), band))
            if _passes(again):
                chain += (again,)
                kept.append(o)
            else:
                failed[o.effect] = again
        if not kept:
            break
        pending = [o for o in pending if all(o is not k for k in kept)]
    out = [NotNamed(o.effect, "left_out", "fitted again once a cause before it was left out, "
                    f"it no longer passes: {_why_fails(failed[o.effect])}",
                    failed[o.effect].test, o.round) for o in pending]
    return chain, out


def _leave_one_out(nom: Nominal, causes: tuple[Candidate, ...],
                   band: LagBand) -> tuple[tuple[Candidate, ...], list[NotNamed]]:
    """More than two causes: each tested on its own against the model holding all the others
    (their values as the joint fit has them), at the level of the round it entered; the
    weakest that fails (least t) is dropped, the others fitted again in order (_chain), and
    so on while more than two are left."""
    out: list[NotNamed] = []
    while len(causes) > 2:
        fails = []
        for i in range(len(causes)):
            again = against_others(nom, causes, i, band)
            if not _passes(again):
                fails.append((again.test.t, i, again))
        if not fails:
            break
        _, i, again = min(fails, key=lambda f: f[0])
        others = ", ".join(o.effect for o in causes[:i] + causes[i + 1:])
        out.append(NotNamed(causes[i].effect, "left_out",
                            f"against the model holding all the others ({others}) it does "
                            f"not pass: {_why_fails(again)}", again.test, causes[i].round))
        causes, lost = _chain(nom, _in_place(causes, i), band)
        out += lost
    return causes, out


def against_others(nom: Nominal, causes: tuple[Candidate, ...], i: int,
                   band: LagBand) -> Candidate:
    """causes[i] fitted and tested again on its own against the model holding all the other
    causes (their values as the joint fit has them: _model), at the level of the round it
    entered (_against)."""
    values = dict(_model(causes))
    others = tuple((o.effect, values[o.effect]) for o in causes[:i] + causes[i + 1:])
    return _against(nom, causes[i], others, band)


def passes(c: Candidate) -> bool:
    """`c` passes its test: significant and, for a cause of a later round, above the floor
    (_passes)."""
    return _passes(c)


def _in_place(causes: tuple[Candidate, ...], i: int) -> tuple[Candidate, ...]:
    """`causes` without causes[i], a later cause that reduces to it (registry `reduces_to`:
    an asymmetric friction beside an offset) moved to its place in the order: the one left
    out was a part of it (the asymmetry's Coulomb part), and the causes named on top of that
    part are fitted again on top of it (_chain)."""
    rest = causes[:i] + causes[i + 1:]
    j = next((k for k in range(i, len(rest))
              if EFFECTS[rest[k].effect].reduces_to == causes[i].effect), None)
    return rest if j is None else rest[:i] + (rest[j],) + rest[i:j] + rest[j + 1:]



def _beside_named(rounds: list[list[Candidate]], causes: tuple[Candidate, ...]
                  ) -> Iterator[tuple[int, Candidate, Candidate]]:
    """(round, A, B): in each round whose first candidate A was named in the end, every
    other candidate B not named, both with held-out errors (the pairs a "one of A or B"
    statement can be about)."""
    named = {c.effect for c in causes}
    for k, r in enumerate(rounds, start=1):
        if not r or r[0].effect not in named or r[0].heldout_errors is None:
            continue
        for b in r[1:]:
            if b.effect not in named and b.heldout_errors is not None:
                yield k, r[0], b


def _alternatives(rounds: list[list[Candidate]], causes: tuple[Candidate, ...],
                  n: int) -> tuple[Alternative, ...]:
    """One of A or B: in each round that named a cause, every other significant candidate
    not named in the end whose held-out errors the segment test without margin (_better)
    cannot separate from the named cause's in either direction at DECIDE."""
    out: list[Alternative] = []
    for k, a, b in _beside_named(rounds, causes):
        if b.significant:
            t, p = _better(b, a, n)
            t2, p2 = _better(a, b, n)
            if p >= DECIDE and p2 >= DECIDE:
                out.append(Alternative(a.effect, b.effect, a.heldout_pct, b.heldout_pct,
                                       t, t2, k))
    return tuple(out)


def _same_law(a: str, b: str) -> bool:
    """`a` and `b` are two laws of the spring that differ only inside their band: their
    designs tend to the same columns as the band narrows (registry Effect.limit, a torque of
    the spring's sign: identification.effects.base.spring_sign)."""
    lim = EFFECTS[a].limit if a in EFFECTS else None
    return a != b and lim is not None and b in EFFECTS and EFFECTS[b].limit is lim


def _spring_alternatives(rounds: list[list[Candidate]], causes: tuple[Candidate, ...],
                         n: int) -> tuple[Alternative, ...]:
    """One of A or B for two laws of the spring (_same_law: a backlash and a hardening). A
    backlash of stiffness K + Kh and half-width (K b + Kh d0) / (K + Kh) is a hardening's
    spring law K d + Kh dz(d, d0) wherever |d| > d0 (identification.effects.base.deadzone):
    the log tells the two apart only by the rows inside the band, a dead zone near zero
    deflection that a hardening cannot make, or a stiffness K there that a backlash cannot.
    In each round that named a cause A, the candidate B of that law, not named in the end,
    its own fit physical (a hardening whose stiffness below the engagement falls to 0 is a
    dead band, which is backlash), is compared with A directly: where the segment test
    without margin (_better) does not find A's held-out errors smaller than B's at DECIDE,
    the log does not exclude B as the description of what A explains, and the answer says
    "one of A or B" with the share each explains, whether B passed its own test or not.
    Once A passes at its round's level, the guard against naming an effect the log does not
    carry is spent; which of two laws of one spring torque the log supports is a single
    two-way decision, at DECIDE (as _which). Where A's errors are the smaller there, the
    log shows the difference and A is named alone."""
    out: list[Alternative] = []
    for k, a, b in _beside_named(rounds, causes):
        if _same_law(a.effect, b.effect) and b.testable and not b.unphysical:
            t, p = _better(b, a, n)
            if p < DECIDE:
                continue
            t2, _ = _better(a, b, n)
            passes = "passes" if b.significant else "does not pass"
            text = (f"one of {a.effect} or {b.effect}: the two spring laws differ only "
                    f"inside the band, and held out {a.effect} explains {a.heldout_pct:.3g} "
                    f"%, {b.effect} fitted in its place {b.heldout_pct:.3g} % of the residual "
                    f"(round {k}); the segment test does not find {a.effect}'s errors "
                    f"smaller than {b.effect}'s (t = {t:.3g}, the converse t = {t2:.3g}, the "
                    f"bar t > {t_bar(DECIDE):.3g}); {a.effect} is named, {b.effect} "
                    f"{passes} its own test ({b.test.describe() if b.test else b.why_not})")
            out.append(Alternative(a.effect, b.effect, a.heldout_pct, b.heldout_pct, t, t2,
                                   k, how="same_law", text=text))
    return tuple(out)


def _apart_t(nom: Nominal, richer: str, simpler: str) -> float:
    """How many of its standard errors the one column of `simpler` lies from 0 beside the
    nominal's columns and `richer`'s parts (registry Effect.parts): its estimate over its
    standard error in the weighted least squares of the log's rows on all of them (the
    Cramer-Rao bound of a linear model, sigma from that fit's residual over its degrees of
    freedom). 0 where its column lies in the span of the others (numerical rank at
    np.linalg.matrix_rank's own tolerance, the columns scaled to unit norm): the log then
    holds no information on it beside `richer`'s parts; inf where the test does not apply
    (`richer` has no parts, `simpler` not one column)."""
    parts = EFFECTS[richer].parts
    y, W, names = EFFECTS[simpler].design(nom, {})
    own = [i for i, x in enumerate(names) if x not in nom.names]
    if parts is None or len(own) != 1:
        return float("inf")
    _, Wp, _ = nom.extend(*parts(nom))
    X = np.column_stack([Wp, W[:, own[0]]]) * nom.weights[:, None]
    yw = y * nom.weights
    scale = np.linalg.norm(X, axis=0)
    live = scale > 0
    live[-1] = True
    Xs = X[:, live] / np.where(scale[live] > 0, scale[live], 1.0)
    if scale[-1] == 0 or np.linalg.matrix_rank(Xs) < Xs.shape[1]:
        return 0.0
    b, *_ = np.linalg.lstsq(Xs, yw, rcond=None)
    dof = Xs.shape[0] - Xs.shape[1]
    r = yw - Xs @ b
    cov = float(r @ r) / dof * np.linalg.inv(Xs.T @ Xs)
    return float(abs(b[-1]) / np.sqrt(cov[-1, -1]))


def _shared(nom: Nominal, causes: tuple[Candidate, ...], rounds: list[list[Candidate]],
            alternatives: tuple[Alternative, ...]) -> tuple[Alternative, ...]:
    """One of A or B for the part two effects share: a named cause A (an asymmetric
    friction) that reduces to an effect B not named (an offset; registry `reduces_to`),
    where B passed its own test in the round A was named (the log carries the part they
    share) and the log holds no more on B beside A's parts than the two-way choice's level
    asks (_apart_t at t_bar(DECIDE)): while the motor moves the asymmetry's Coulomb part is
    a constant torque, and a log whose motor rests on no row cannot say whether the
    constant it carries is that part or an offset, whatever A's viscous part adds. The
    answer then says so, with the share each explains held out, rather than naming A alone
    (Alternative, how "shared")."""
    named = {c.effect for c in causes}
    stated = {frozenset((a.named, a.other)) for a in alternatives}
    out: list[Alternative] = []
    for c in causes:
        simpler = EFFECTS[c.effect].reduces_to if c.effect in EFFECTS else ""
        k = max(c.round, 1)
        if (not simpler or simpler in named or frozenset((c.effect, simpler)) in stated
                or k > len(rounds)):
            continue
        s = next((x for x in rounds[k - 1] if x.effect == simpler), None)
        if s is None or not s.significant:
            continue
        t = _apart_t(nom, c.effect, simpler)
        if t > t_bar(DECIDE):
            continue
        held = (f"its column lies in the span of {c.effect}'s parts and the nominal's on "
                "every row the inverse view fits, where the filtered motor speed is never 0"
                if t == 0 else
                f"beside {c.effect}'s parts and the nominal's columns it has t = {t:.3g}, "
                f"the bar t > {t_bar(DECIDE):.3g}")
        text = (f"one of {c.effect} or {simpler}: the part they share, which {simpler} "
                f"explains as well, cannot be told apart ({held}); held out {c.effect} "
                f"explains {c.heldout_pct:.3g} %, {simpler} {s.heldout_pct:.3g} % of the "
                f"residual (round {k}); {c.effect} is named, and the part they share may be "
                f"{simpler}")
        out.append(Alternative(c.effect, simpler, c.heldout_pct, s.heldout_pct, t,
                               float("nan"), k, how="shared", text=text))
    return tuple(out)


def not_named(inv: InverseDiagnosis, dropped: tuple[NotNamed, ...] = ()) -> tuple[NotNamed, ...]:
    """Every effect considered and not named, with why: its last test (the last round it was
    tested in), or what dropped it (`dropped`: the floor, the leave-one-out test), or why it
    could not be tested."""
    named = {c.effect for c in inv.causes}
    given = {d.effect: d for d in dropped}
    alt = {a.other: a for a in inv.alternatives}
    last: dict[str, Candidate] = {}
    passed: dict[str, Candidate] = {}   # the earliest round it passed in
    for r in inv.rounds:
        for c in r:
            last[c.effect] = c
            if c.significant and c.effect not in passed:
                passed[c.effect] = c
    out: list[NotNamed] = []
    for c in inv.candidates:
        e = c.effect
        if e in named:
            continue
        if not c.testable:
            out.append(NotNamed(e, "untestable", c.reason))
            continue
        if e in given:
            out.append(given[e])
            continue
        c = last.get(e, c)
        test, k = c.test, c.round
        before = _before(inv, k)
        if e in alt:
            out.append(NotNamed(e, "alternative", alt[e].describe(), test, k))
        elif c.unphysical:
            out.append(NotNamed(e, "unphysical", c.why_not, test, k))
        elif e in passed and not c.significant:
            p = passed[e]
            out.append(NotNamed(e, "collinear",
                                f"it passes against {_before(inv, p.round) or 'the nominal'} "
                                f"(round {p.round}, t = {p.test.t:.3g}) but not once "
                                f"{before} {'is' if ',' not in before else 'are'} held "
                                f"(round {k}): {c.why_not}", test, k))
        elif c.significant:
            out.append(NotNamed(e, "failed", f"it passes its own test in round {k} but is not "
                                f"named: {inv.stopped or 'another explains more'}", test, k))
        else:
            out.append(NotNamed(e, "failed", c.why_not, test, k))
    return tuple(out)


def _before(inv: InverseDiagnosis, k: int) -> str:
    """The causes a round-k candidate is tested on top of, in words."""
    return ", ".join(c.effect for c in inv.causes if 0 < c.round < k)


def _holds(c: Candidate, lost: list[NotNamed]) -> bool:
    """`c` holds a cause that reduces to it (registry `reduces_to`: an offset beside an
    asymmetric friction): without `c` that cause, fitted again on the others (_chain), no
    longer passes (its own fit unphysical: an asymmetry whose Coulomb part exceeds the
    fitted Coulomb friction, the constant `c` held). The model of all the others that `c`
    added nothing to then holds that cause as no physical instance of it, a reference the
    log's own causes cannot be, and `c` stays."""
    return any(EFFECTS[x.effect].reduces_to == c.effect for x in lost)


def _pruned(nom: Nominal, causes: tuple[Candidate, ...],
            notes: tuple[tuple[str, str], ...],
            band: LagBand) -> tuple[tuple[Candidate, ...], tuple[tuple[str, str], ...],
                                    list[NotNamed]]:
    """Once the rounds stop, a cause that a later one reduces to (registry `reduces_to`: an
    offset beside an asymmetric friction), fitted on top of all the others, must still
    predict the held-out rows significantly better than they do (the segment test without
    margin, at the level it was named at); if it does not, it is dropped, with its notes, and
    the others are fitted again in order: a first round dominated by another cause can name
    an asymmetry's Coulomb part an offset before its viscous part passes on top of that
    cause. Only such reducible causes are checked (checking every cause drops a true
    backlash under a spurious later hardening). Likewise an
    asymmetric friction named beside the offset it reduces to, in either order, must add
    to all the others, the offset included (an offset of 182 N m beside a backlash, with the
    evidence in the motor equation alone: asymmetric friction first, then backlash, offset
    and hardening). A cause is not dropped where the others, fitted again without it, lose
    the one that reduces to it (_holds: an asymmetry that took up the offset's constant as
    its Coulomb part is then unphysical): the model of all the others it was tested
    against held that cause as no physical instance of it."""
    n, i = len(nom.sig.index), 0
    out: list[NotNamed] = []
    while i < len(causes):
        c = causes[i]
        if not any(EFFECTS[r.effect].reduces_to == c.effect for r in causes[i + 1:]) and not (
                EFFECTS[c.effect].reduces_to in {r.effect for r in causes[:i] + causes[i + 1:]}):
            i += 1
            continue
        others = causes[:i] + causes[i + 1:]
        values = dict(_model(causes))
        ref = reference(nom, tuple((o.effect, values[o.effect]) for o in others))
        again = candidate(nom, c.effect, ref)
        t, p = _better(ref.scores.errors, again, n)
        if p < c.alpha and not again.unphysical:
            i += 1
            continue
        chain, lost = _chain(nom, _in_place(causes, i), band)
        if _holds(c, lost):
            i += 1
            continue
        out.append(NotNamed(c.effect, "left_out",
                            "fitted on top of all the other causes it adds nothing the log "
                            f"supports (what it adds has t = {t:.3g}, p = {p:.2g}, the bar "
                            f"p < {c.alpha:.2g})" + (f", unphysical ({again.unphysical})"
                                                     if again.unphysical else ""),
                            HeldOutTest("on top of all the others, no margin",
                                        again.heldout_pct, t, p, c.alpha,
                                        acts_pct=again.acts_pct), c.round))
        causes = chain
        out += lost
        kept = {o.effect for o in causes}
        notes, i = tuple(x for x in notes if x[0] in kept), 0
    return causes, notes, out
