"""The results of `jointbench diagnose` as data: the diagnosis of one log and the forward view
of one model (docs/cli.md and docs/effects.md), with the JSON answer of `diagnose --json`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointbench.bench.analysis.diagnose.clipped import ClippedViews
from jointbench.bench.effects import axis_keys
from jointbench.identification.discrepancy import Candidate, InverseDiagnosis
from jointbench.identification.discrepancy.inverse import FLOOR, Alternative, NotNamed
from jointbench.identification.effects import NONE
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log
from jointbench.identification.output_values import finite_json

BLOCK_NAMES = ("motor equation (eq. 6): torque residual, % of the measured torque RMS",
               "link equation (eq. 5): residual, % of the spring torque K (qm - q) RMS")


@dataclass(frozen=True)
class ForwardView:
    """Replay errors (docs/controller.md closed loop) of one model against the log."""

    q_m_rms: float           # [rad or m]
    q_rms: float | None
    tau_rel_pct: float       # 100 ||tau_sim - tau|| / ||tau||
    q_m_rel_pct: float       # 100 ||q_m_sim - q_m|| / ||q_m - mean||
    t: np.ndarray
    q_m: np.ndarray
    q: np.ndarray | None
    tau_m: np.ndarray


@dataclass(frozen=True)
class Diagnosis:
    """One log's diagnosis: the filter, the inverse view's ranking and named cause, the
    nominal and extended parameters, the forward views and the files written."""

    log: Log
    settings: FilterSettings
    settings_note: str
    inverse: InverseDiagnosis
    nominal_parameters: dict[str, float]
    extended_parameters: dict[str, float]
    forward_nominal: ForwardView | None = None
    forward_extended: ForwardView | None = None
    forward_note: str = ""
    files: tuple[str, ...] = ()
    # why the inverse view's best candidate is NOT named (bench.analysis.diagnose.verdict):
    # an unphysical nominal, or an extended model that is worse; "" when nothing overrules
    overruled: str = ""
    warnings: tuple[str, ...] = ()   # units, clipped torque (stderr and JSON "warnings")
    # a clipped log's inverse views (bench.analysis.diagnose.clipped; None when none clipped)
    clipped: ClippedViews | None = None

    @property
    def named(self) -> Candidate | None:
        return None if self.overruled else self.inverse.named

    @property
    def named_cause(self) -> str:
        return self.named.effect if self.named is not None else NONE

    @property
    def causes(self) -> tuple[Candidate, ...]:
        """Every named cause in order, each tested on top of the ones
        before it; () when nothing is named."""
        return () if self.overruled else self.inverse.causes

    @property
    def ambiguities(self) -> tuple[str, ...]:
        """What this log cannot tell apart about the named causes (an offset from a
        Coulomb-dominated asymmetric friction: identification.discrepancy.inverse), and
        every "one of A or B" (inverse._alternatives)."""
        if self.overruled:
            return ()
        notes = self.inverse.notes
        return notes + tuple(a.describe() for a in self.inverse.alternatives
                             if not a.stated_in(notes))

    def alternatives_of(self, effect: str) -> tuple[Alternative, ...]:
        """The named cause `effect`'s alternatives: "one of `effect` or B", B an effect the
        log cannot tell from it (identification.discrepancy.inverse.Alternative)."""
        if self.overruled:
            return ()
        return tuple(a for a in self.inverse.alternatives if a.named == effect)

    @property
    def not_named(self) -> tuple[NotNamed, ...]:
        """Every effect considered and not named, with why (inverse.NotNamed); when the
        answer is overruled, the inverse view's causes first, with the reason."""
        over = tuple(NotNamed(c.effect, "overruled", self.overruled, c.test, c.round)
                     for c in self.inverse.causes) if self.overruled else ()
        return over + self.inverse.not_named

    @property
    def verdict(self) -> str:
        """'named', 'none' or 'inconclusive' (the best candidate overruled)."""
        return "inconclusive" if self.overruled else ("named" if self.named else "none")

    @property
    def reason(self) -> str:
        """Why the answer is none or inconclusive ("" when an effect is named)."""
        return self.overruled or self.inverse.why_none

    @property
    def view_block(self) -> int:
        return self.named.block if self.named else 0

    @property
    def inverse_before_after(self) -> tuple[float, float]:
        nom = self.inverse.nominal
        before = nom.relative_error_pct(nom.residual, self.view_block)
        if not self.named:
            return before, before
        return before, self.named.after_pct

    def to_json(self) -> dict:
        before, after = self.inverse_before_after
        out = {
            "named_cause": self.named_cause,
            "named_causes": [c.effect for c in self.causes],
            "verdict": self.verdict,
            "candidates": [_candidate_json(c, self.log.prismatic)
                           for c in self.inverse.candidates],
            "causes": [_cause_json(c, self.log.prismatic, self.alternatives_of(c.effect))
                       for c in self.causes],
            "extended_parameters": axis_keys(self.extended_parameters, self.log.prismatic),
            "gain": {"metric": "inverse view, " + BLOCK_NAMES[self.view_block],
                     "before": before, "after": after,
                     "ratio": before / after if after > 0 else None},
            "nominal_parameters": self.nominal_parameters,
            "filter": {"wn_rad_s": self.settings.wn, "order": self.settings.m,
                       "decimate": self.settings.Nd, "how": self.settings_note},
        }
        if self.forward_nominal is not None:
            fwd = {"nominal": _forward_json(self.forward_nominal)}
            if self.forward_extended is not None:
                fwd["extended"] = _forward_json(self.forward_extended)
            out["forward"] = fwd
        if self.forward_note:
            out["forward_note"] = self.forward_note
        if self.reason:
            out["reason"] = self.reason
        if self.ambiguities:
            out["ambiguity"] = list(self.ambiguities)
        if self.inverse.alternatives and not self.overruled:
            out["alternatives"] = [a.to_json() for a in self.inverse.alternatives]
        out["not_named"] = [n.to_json() for n in self.not_named]
        out["stopped"] = self.inverse.stopped
        if self.inverse.masked is not None:
            out["masked_pair"] = self.inverse.masked.to_json()
        out["floor_pct"] = 100 * FLOOR
        if self.overruled and self.inverse.named is not None:
            out["rejected_cause"] = self.inverse.named.effect
        out["warnings"] = list(self.warnings)
        if self.clipped is not None:
            out["clipped"] = self.clipped.to_json()
        untested = {c.effect: c.reason for c in self.inverse.candidates if not c.testable}
        if untested:
            out["untested"] = untested
        if self.files:
            out["files"] = list(self.files)
        return finite_json(out)


def _cause_json(c: Candidate, prismatic: bool = False,
                alternatives: tuple[Alternative, ...] = ()) -> dict:
    """One named cause: its parameters, the held-out test it is named on (at the level of
    the round it entered: heldout_pct, t, p_heldout, alpha are that test's, `test` all of
    it), its own gain, against the causes before it, and its `alternatives` (the effects
    the log cannot tell from it: the claim is then "one of" them, with the share each
    explains)."""
    test = c.test
    return {"effect": c.effect, "alternatives": [a.of_cause() for a in alternatives], "after": [e for e, _ in c.base], "round": c.round,
            "parameters": axis_keys(c.parameters, prismatic),
            "heldout_pct": test.heldout_pct, "t": test.t, "p_heldout": test.p,
            "alpha": test.level, "test": test.to_json(),
            "block": BLOCK_NAMES[c.block].split(":")[0], "before_pct": c.before_pct,
            "after_pct": c.after_pct, "gain": c.gain}


def _forward_json(f: ForwardView) -> dict:
    out = {"tau_rel_pct": f.tau_rel_pct, "q_m_rms": f.q_m_rms, "q_m_rel_pct": f.q_m_rel_pct}
    if f.q_rms is not None:
        out["q_rms"] = f.q_rms
    return out


def _candidate_json(c: Candidate, prismatic: bool = False) -> dict:
    out = {"effect": c.effect, "significant": c.significant, "testable": c.testable}
    if c.testable:
        out.update({"heldout_pct": c.heldout_pct, "t": c.t_stat, "p_heldout": c.p_heldout,
                    "alpha": c.level, "explained_pct": c.explained_pct, "score": c.delta_bic,
                    "p_value": c.p_value, "size_pct": c.size_pct,
                    "before_pct": c.before_pct, "after_pct": c.after_pct,
                    "parameters": axis_keys(c.parameters, prismatic)})
        if c.unphysical:
            out["unphysical"] = c.unphysical
        if c.second is not None:   # the lag's test in the wide band (discrepancy.lag_band)
            out["second_view"] = c.second.to_json(c.level)
    else:
        out["reason"] = c.reason
    return out
