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
without one the look costs nothing), the two physical candidates that explain the most of
it (a positive share each) are fitted together (`masked_pair`), and three tests are run:

- the pair against the nominal (the segment test with its margin over the equations either
  acts in), at ALPHA / C(m, 2): Bonferroni over the m (m - 1) / 2 pairs of the m effects the
  round tested, whichever two the ranking picks, so that on a log without any unmodelled
  effect the chance that a pair passes stays under ALPHA / 2 whatever the ranking;
- each of the two on top of the other (the other's value searched against the nominal, held),
  at ALPHA / (m (m - 1)): Bonferroni over the ordered pairs. An effect that passes on top of
  a reference holding another explains something that reference, and so the nominal, cannot.

When any passes, the answer is "inconclusive" (bench.analysis.diagnose.verdict), with the
pair's share and every test: the log carries a discrepancy that the two describe together,
and not one named with its own test against the causes before it. Nothing here names a cause:
the rounds' rule (inverse) is unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

from jointbench.identification.discrepancy.candidates import (Candidate, HeldOutTest, candidate,
                                                              reference)
from jointbench.identification.discrepancy.heldout import ALPHA, MATERIAL, evidence
from jointbench.identification.discrepancy.nominal import Nominal


@dataclass(frozen=True)
class MaskedPair:
    """Two first-round candidates, none named, fitted together: `first` and `second` (ranked
    by their held-out shares alone), the pair's test against the nominal (`pair`) and each
    one's test on top of the other (`second_on_first`, `first_on_second`)."""

    first: str
    second: str
    pair: HeldOutTest
    second_on_first: HeldOutTest
    first_on_second: HeldOutTest

    @property
    def passes(self) -> bool:
        return any(t.passes for t in (self.pair, self.second_on_first, self.first_on_second))

    def describe(self) -> str:
        head = (f"no effect passes alone; {self.first} and {self.second} together explain "
                f"{self.pair.heldout_pct:.3g} % of the held-out residual")
        what = ("they mask each other" if self.passes else
                "neither that nor either on top of the other passes")
        return (f"{head}: {what}; the pair against the nominal, "
                f"{_line(self.pair)}; {self.second} on top of {self.first}, "
                f"{_line(self.second_on_first)}; {self.first} on top of {self.second}, "
                f"{_line(self.first_on_second)}")

    def to_json(self) -> dict:
        return {"first": self.first, "second": self.second, "passes": self.passes,
                "pair": self.pair.to_json(), "second_on_first": self.second_on_first.to_json(),
                "first_on_second": self.first_on_second.to_json(), "text": self.describe()}


def _line(t: HeldOutTest) -> str:
    return (f"held out {t.heldout_pct:.3g} %, t = {t.t:.3g} (p = {t.p:.2g}, the bar "
            f"t > {t.bar:.3g}: {'passes' if t.passes else 'fails'})")


def _on_top(nom: Nominal, under: Candidate, c: Candidate, alpha: float) -> tuple[Candidate,
                                                                                   HeldOutTest]:
    """`c`'s effect fitted on top of `under` (its value held) and its test there."""
    ref = reference(nom, ((under.effect, under.fixed),))
    x = candidate(nom, c.effect, ref)
    return x, HeldOutTest(f"on top of {under.effect} (not named)", x.heldout_pct, x.t_stat,
                          x.p_heldout, alpha, x.explained_pct, x.acts_pct)


def masked_pair(nom: Nominal, ranked: list[Candidate] | tuple[Candidate, ...],
                m: int) -> MaskedPair | None:
    """The two physical first-round candidates with the largest positive held-out shares,
    fitted together and tested (module docstring); None when there are not two, the best
    explains no more than MATERIAL, or fewer than two effects were tested (m)."""
    two = sorted((c for c in ranked if c.testable and not c.unphysical and c.heldout_pct > 0
                  and c.heldout_errors is not None), key=lambda c: -c.heldout_pct)[:2]
    if len(two) < 2 or m < 2 or not two[0].heldout_pct > 100 * MATERIAL:
        return None
    a, b = two
    ordered = ALPHA / (m * (m - 1))
    ba, t_ba = _on_top(nom, a, b, ordered)
    _, t_ab = _on_top(nom, b, a, ordered)
    n = len(nom.sig.index)
    acts = tuple(sorted(set(a.acts) | set(ba.acts))) if a.acts and ba.acts else ()
    ev = evidence(reference(nom).scores.errors, ba.heldout_errors, n, acts)
    pair = HeldOutTest("the pair against the nominal", ev.explained_pct, ev.t, ev.p,
                       2 * ordered, acts_pct=ev.acts_pct)
    return MaskedPair(a.effect, b.effect, pair, t_ba, t_ab)
