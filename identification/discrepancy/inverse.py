"""The inverse view's verdict: every effect tested against the nominal model of a log and
ranked; the first is named when it is significant."""

from __future__ import annotations

from dataclasses import dataclass

from jointbench.identification.discrepancy.candidates import Candidate, candidate
from jointbench.identification.discrepancy.nominal import Nominal, nominal
from jointbench.identification.effects import EFFECTS, NONE
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log

# The effects a log without q can test: those the registry says need no link position.
RIGID_TESTS = tuple(name for name, e in EFFECTS.items() if not e.needs_link)
WHY_NOT_RIGID = ("it acts between the motor and the link or on the link: without the link "
                 "position q the rigid motor-side model cannot separate it")


@dataclass(frozen=True)
class InverseDiagnosis:
    nominal: Nominal
    candidates: tuple[Candidate, ...]   # ranked, best first; untestable ones last

    @property
    def named(self) -> Candidate | None:
        best = self.candidates[0] if self.candidates else None
        return best if best is not None and best.significant else None

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
        best = max(tested, key=lambda c: c.explained_pct)
        return (f"no effect is significant: the one that explains the most, {best.effect} "
                f"({best.explained_pct:.3g} % of the nominal residual), fails: {best.why_not}")


def diagnose_inverse(log: Log, settings: FilterSettings,
                     effects: tuple[str, ...] | None = None) -> InverseDiagnosis:
    """Evaluate every effect of docs/effects.md against the nominal model of `log` and rank
    them: significant ones (BIC and F-test, and a practical size) first, by delta BIC; the
    first is named when it is significant."""
    nom = nominal(log, settings)
    out: list[Candidate] = []
    for name in effects or tuple(EFFECTS):
        if not nom.sig.has_link and name not in RIGID_TESTS:
            out.append(Candidate(effect=name, testable=False, reason=WHY_NOT_RIGID))
            continue
        out.append(candidate(nom, name))
    # Significant effects first, by delta BIC; then the others. Ranking all by delta BIC alone
    # would let the link Coulomb friction every real link has (large delta BIC, small size)
    # hide a significant motor-side effect.
    out.sort(key=lambda c: (not c.testable, not c.significant, bool(c.unphysical),
                            -c.delta_bic))
    return InverseDiagnosis(nominal=nom, candidates=tuple(out))
