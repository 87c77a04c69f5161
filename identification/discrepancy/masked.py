"""Two effects that mask each other: what the inverse view says when no effect passes alone.

A round tests each effect against a reference that lacks the others. Two effects that act on
the same rows can then hide each other: on a soft axis swept through its mode, a backlash's
dead band and a spring damping D (qm' - q') both shape the link equation in the few segments
where the deflection and its rate are large, and there each one's misfit dominates what the
other would remove. Each alone explains little in a typical segment (the segment test asks a
typical one for more than MATERIAL, identification.discrepancy.heldout), together they
explain half of the held-out residual. "No effect is significant" would be silence on a
discrepancy the log carries.

So when the rounds name nothing and the best physical candidate of the first round explains
more than MATERIAL of the held-out residual (the discrepancy silence would hide; on a log
without one the look costs nothing), it and its partner are fitted together (`masked_pair`),
and three tests are run:

- the pair against the nominal (the segment test with its margin over the equations either
  acts in), at ALPHA / C(m, 2): Bonferroni over the m (m - 1) / 2 pairs of the m effects the
  round tested, whichever two the ranking picks, so that on a log without any unmodelled
  effect the chance that a pair passes stays under ALPHA / 2 whatever the ranking;
- each of the two on top of the other (the other's value searched against the nominal, held),
  at ALPHA / (m (m - 1)): Bonferroni over the ordered pairs (split again over the views its
  test has there: a second cause of the spring's law on top of a cause of the spring over
  both equations and the link equation, identification.discrepancy.candidates._test). An
  effect that passes on top of a reference holding another explains something that
  reference, and so the nominal, cannot.

When the pair passes and each of the two passes on top of the other (and explains more than
MATERIAL of the held-out residual of the equations it acts in there, the rounds' floor), both
are named (`named`, `causes`): each with its own passing test, on top of the other, at the
ordered pairs' level. A prototype with an offset and a torque ripple whose motor rests for
the last quarter of the log is such a case: at rest the residual is the offset plus the
ripple frozen at the resting angle, so against the nominal (no ripple) the offset loses in
those segments and wins in the others, and the ripple tested without the offset fails the
same way; each on top of the other passes.

**The partner.** The partner is the physical candidate that explains the most of what the
best leaves: each other candidate fitted on top of the best, its nonlinear value searched
there. Not the second best alone: masking hides the partner's value from its own search
too. A backlash beside a spring damping is such a pair: the damper D (qm' - q') also carries
torque inside the dead band, where a dead band alone carries none, so alone the width's
search ends at b = 0, where the column is the nominal spring's and the share is 0 by
construction; on top of the damping it finds the width. Whichever partner the data picks,
the pair is one of the m (m - 1) / 2 and each order one of the m (m - 1) ordered pairs, so
the levels above hold.

**The stronger, then the weaker on top of it.** When the pair passes and one of the two
passes on top of the other while the other does not (`lead`), the one that passes is named
with that test: it explains, at the ordered pairs' level, something a reference holding the
other cannot, and so something the nominal cannot (the Bonferroni over the ordered pairs
holds whichever two the ranking picks). The rounds then go on on top of it
(identification.discrepancy.inverse), and the other is tested there with every effect left,
against the model holding the stronger, at the next round's Holm level, in the view where it
is visible (lag_band: a lag at the top of the sweep, a hardening at large deflections, a
backlash or a spring damping where its prediction changes most). A soft axis's backlash and
spring damping are such a pair: against the nominal the damping's misfit, in the few
segments of the mode, hides the dead band, and the reverse. When the pair passes but neither
passes on top of the other, or one does but not the pair, the answer is "inconclusive"
(bench.analysis.diagnose.verdict), with the pair's share and every test: the log carries a
discrepancy that the two describe together, and not one named with its own test against
the other.

**An effect and the one it reduces to are one description here.** While the motor moves,
an asymmetric friction's Coulomb part a FSm sign(qm') is a constant torque on each stretch
of one direction, the offset's column; only its viscous part a FVm |qm'| differs (registry
`reduces_to`: asymmetric_friction reduces to offset). Fitted together the two explain
little more than either alone, and a pair of them says nothing the better one does not. So a
candidate that reduces to another candidate of the look is left out of it (`skipped`, with
why): the simpler stands for the two, the richer's own part being the rounds' question (a
richer effect is named over the one it reduces to only when what it adds is significant,
identification.discrepancy.inverse._which), and neither the best nor its partner is a
candidate left out. The pair is still one of the m (m - 1) / 2, so the levels above
hold.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from jointbench.identification.discrepancy.candidates import (Candidate, HeldOutTest, candidate,
                                                              reference)
from jointbench.identification.discrepancy.heldout import ALPHA, MATERIAL, evidence
from jointbench.identification.discrepancy.nominal import Nominal
from jointbench.identification.effects import EFFECTS


@dataclass(frozen=True)
class MaskedPair:
    """Two first-round candidates, none named alone, fitted together: `first` and `second`
    (ranked by their held-out shares alone), the pair's test against the nominal (`pair`)
    and each one's test on top of the other (`second_on_first`, `first_on_second`);
    `skipped`, the candidates left out of the look as the same description as one in it
    (effect, why); `on_top`, the two fits on top of the other (first on second, second on
    first), the causes when both are named."""

    first: str
    second: str
    pair: HeldOutTest
    second_on_first: HeldOutTest
    first_on_second: HeldOutTest
    skipped: tuple[tuple[str, str], ...] = ()
    on_top: tuple[Candidate, ...] = field(default=(), repr=False, compare=False)

    @property
    def passes(self) -> bool:
        return any(t.passes for t in (self.pair, self.second_on_first, self.first_on_second))

    @property
    def named(self) -> bool:
        """Both named: the pair passes, and each passes on top of the other above the floor
        (MATERIAL of the held-out residual of the equations it acts in)."""
        return self.pair.passes and all(t.passes and t.own_share > 100 * MATERIAL
                                        for t in (self.second_on_first, self.first_on_second))

    @property
    def lead(self) -> Candidate | None:
        """The stronger of the two, named first (module docstring: the stronger, then the
        weaker on top of it): the pair passes and it alone passes on top of the other, above
        the floor (MATERIAL of the held-out residual of the equations it acts in); its fit on
        top of the other, with that test, its own values the reference of the next round
        (`base` empty: the other is tested there, not held). None when both are named, the
        pair fails or neither passes on top of the other."""
        if self.named or not self.pair.passes:
            return None
        ok = [c for c, t in zip(self.on_top, (self.first_on_second, self.second_on_first))
              if t.passes and t.own_share > 100 * MATERIAL]
        return replace(ok[0], base=()) if len(ok) == 1 else None

    def other(self, effect: str) -> str:
        """The other of the two."""
        return self.second if effect == self.first else self.first

    @property
    def causes(self) -> tuple[Candidate, ...]:
        """The named causes (() when not `named`): `first` fitted on top of `second`, then
        `second` on top of `first` (its fit the joint one), each at its test's level."""
        return self.on_top if self.named else ()

    def describe(self) -> str:
        head = (f"no effect passes alone; {self.first} and {self.second} together explain "
                f"{self.pair.heldout_pct:.3g} % of the held-out residual")
        lead = self.lead
        what = ("each passes on top of the other: both are named" if self.named else
                f"{lead.effect} passes on top of {self.other(lead.effect)}: {lead.effect} "
                f"is named, and {self.other(lead.effect)} tested on top of it with the "
                f"others" if lead is not None else
                "they mask each other" if self.passes else
                "neither that nor either on top of the other passes")
        left = "".join(f"; {e} left out of the pair: {why}" for e, why in self.skipped)
        return (f"{head}: {what}; the pair against the nominal, "
                f"{_line(self.pair)}; {self.second} on top of {self.first}, "
                f"{_line(self.second_on_first)}; {self.first} on top of {self.second}, "
                f"{_line(self.first_on_second)}{left}")

    def to_json(self) -> dict:
        return {"first": self.first, "second": self.second, "passes": self.passes,
                "named": self.named,
                "lead": None if (lead := self.lead) is None else lead.effect,
                "pair": self.pair.to_json(),
                "second_on_first": self.second_on_first.to_json(),
                "first_on_second": self.first_on_second.to_json(),
                "skipped": [{"effect": e, "why": why} for e, why in self.skipped],
                "text": self.describe()}


def _line(t: HeldOutTest) -> str:
    return (f"held out {t.heldout_pct:.3g} %, t = {t.t:.3g} (p = {t.p:.2g}, the bar "
            f"t > {t.bar:.3g}: {'passes' if t.passes else 'fails'})")


def _on_top(nom: Nominal, under: Candidate, c: Candidate, alpha: float) -> tuple[Candidate,
                                                                                   HeldOutTest]:
    """`c`'s effect fitted on top of `under` (its value held), at the level `alpha` of the
    first round's look, and its test there."""
    ref = reference(nom, ((under.effect, under.fixed),))
    x = replace(candidate(nom, c.effect, ref), alpha=alpha, round=1,
                view=f"the masked pair, on top of {under.effect}")
    return x, x.own_test


def _same(c: Candidate, others: list[Candidate]) -> str:
    """Why `c` is left out of the look ("" when it is not): it reduces to another of its
    candidates (registry `reduces_to`, module docstring)."""
    simpler = EFFECTS[c.effect].reduces_to if c.effect in EFFECTS else ""
    if not simpler or not any(o.effect == simpler for o in others):
        return ""
    return (f"it reduces to {simpler}, a candidate of the look (while the motor moves its "
            f"Coulomb part is a constant torque, {simpler}'s column; only its viscous part "
            f"differs, and what that adds is the rounds' question), so {simpler} stands for "
            f"the two")


def masked_pair(nom: Nominal, ranked: list[Candidate] | tuple[Candidate, ...],
                m: int) -> MaskedPair | None:
    """The physical first-round candidate with the largest positive held-out share and its
    partner (module docstring: the partner), one that reduces to another of the look left
    out (module docstring), fitted together and tested; None when there is no partner, the
    best explains no more than MATERIAL, or fewer than two effects were tested (m)."""
    fit = sorted((c for c in ranked if c.testable and not c.unphysical
                  and c.heldout_errors is not None), key=lambda c: -c.heldout_pct)
    skipped = tuple((c.effect, why) for c in fit if (why := _same(c, fit)))
    pool = [c for c in fit if c.effect not in dict(skipped)]
    if len(pool) < 2 or m < 2 or not pool[0].heldout_pct > 100 * MATERIAL:
        return None
    a = pool[0]
    ordered = ALPHA / (m * (m - 1))
    # each other candidate on top of the best (its value searched there): the partner is
    # the one that explains the most of what the best leaves, a physical fit there
    tops = [_on_top(nom, a, c, ordered) for c in pool[1:]]
    tops = [(x, t) for x, t in tops if not x.unphysical and t.heldout_pct > 0]
    if not tops:
        return None
    ba, t_ba = max(tops, key=lambda xt: xt[1].heldout_pct)
    ab, t_ab = _on_top(nom, ba, a, ordered)   # the best on top of the partner at its value
    n = len(nom.sig.index)
    acts = tuple(sorted(set(a.acts) | set(ba.acts))) if a.acts and ba.acts else ()
    ev = evidence(reference(nom).scores.errors, ba.heldout_errors, n, acts)
    pair = HeldOutTest("the pair against the nominal", ev.explained_pct, ev.t, ev.p,
                       2 * ordered, acts_pct=ev.acts_pct)
    # skipped only where the pair it would have been in differs (the richer ranked in it)
    ranked_two = fit[:2]
    skipped = tuple((e, why) for e, why in skipped if any(c.effect == e for c in ranked_two))
    return MaskedPair(a.effect, ba.effect, pair, t_ba, t_ab, skipped, (ab, ba))
