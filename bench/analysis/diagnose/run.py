"""`jointbench diagnose`: what the simulation gets wrong on a log, the named cause, the extended
model and the gain (docs/cli.md and docs/effects.md).

1. Nominal model from the data (identification.discrepancy.nominal) and its MuJoCo axis.
2. Two views of the error: inverse (predicted torque and link-equation residual on the measured
   motion) and forward (the logged experiment replayed in closed loop in MuJoCo).
3. Every effect of docs/effects.md tested; the best one named only when significant.
4. The named effect written into the MJCF (DIR/extended.xml) with its identified parameter.
5. Both views again with the extended model: the gain, figures and DIR/report.md.
"""

from __future__ import annotations

from dataclasses import replace

import math
from pathlib import Path
from typing import Callable

from jointbench.bench.analysis.diagnose.clipped import ClippedViews, clipped_inverse
from jointbench.bench.analysis.diagnose.forward import add_forward_view
from jointbench.bench.analysis.diagnose.report import write
from jointbench.bench.analysis.diagnose.types import Diagnosis, ForwardView
from jointbench.bench.analysis.diagnose.verdict import (clipped_reason, every_row_reason,
                                                        cycle_only, loop_cycle, masked_reason,
                                                        gain_reason, nominal_reason,
                                                        with_clipping)
from jointbench.identification.band_choice import excitation_capped
from jointbench.identification.filter_choice import choose_filter
from jointbench.identification.discrepancy import (NUMERICS, Candidate, InverseDiagnosis, Nominal,
                                                   diagnose_inverse)
from jointbench.identification.discrepancy.candidates import joint_parameters
from jointbench.identification.discrepancy.inverse import NotNamed, one_of
from jointbench.identification.effects import EFFECTS
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log, unit_warnings
from jointbench.identification.saturation import clipped_samples, clipping_warnings


def diagnosis_settings(log: Log) -> tuple[FilterSettings, str]:
    """The bandpass of section 3.2 for this log, and how it was chosen: the one chooser
    (identification.filter_choice.choose_filter: the first mode measured on the log, eqs. 28-29,
    the paper's filter for the prototype, a stated generic band when no resonance is found,
    its decimated cutoff brought down to the excitation's top measured on the log:
    identification.band_choice.excitation_capped)."""
    c = choose_filter(log)
    # the effects' columns (identification/effects) pair samples as eq. (22) does: the band
    # follows the mode, the differences stay the paper's 3-point ones
    s, mode = replace(c.settings, stencil=3), c.first_mode
    if mode is not None and mode.found:
        how = (f"first mode {mode.f1_hz:.3g} +- {mode.sigma_hz:.2g} Hz measured ({mode.method});"
               f" wn = {s.wn:.4g} rad/s, Nd = {s.Nd} (decimated cutoff "
               f"{s.decimated_cutoff_hz:.3g} Hz), eq. (22)")
    else:
        # no mode: the generic band (a tenth of the rate) may reach far past what the log
        # excites; it stops at the excitation's top (band_choice.excitation_capped)
        s, capped = excitation_capped(log, s)
        how = "; ".join(c.warnings + ((capped,) if capped else ())) or "generic band"
    return s, how


def nominal_parameters(nom: Nominal) -> dict[str, float]:
    """Physical parameters of the nominal axis; gravity as MX, MY of eq. 13 (rest at qs)."""
    p = {n: float(v) for n, v in zip(nom.names, nom.X) if n not in NUMERICS}
    if "P" in p:
        P = p.pop("P")
        p["MX"], p["MY"] = -P * math.sin(nom.sig.qs), P * math.cos(nom.sig.qs)
    return p


def extended_parameters(c: Candidate | None, nom: Nominal) -> dict[str, float]:
    """The named effect's parameter under its docs/effects.md name (identification.effects), its
    other identified parameters, and the refitted nominal parameters of the extended model."""
    if c is None:
        return {}
    out = {k: float(v) for k, v in c.parameters.items()}
    refit = {n: float(v) for n, v in zip(c.names, c.X)
             if n in nom.names and n not in NUMERICS}
    for n, v in refit.items():
        if n != "P":
            out.setdefault(n, v)
    if "P" in refit and c.effect != "gravity":
        out["MX"] = -refit["P"] * math.sin(nom.sig.qs)
        out["MY"] = refit["P"] * math.cos(nom.sig.qs)
    return out


def diagnose(log: Log, out_dir: Path | None = None, forward: bool = True,
             progress: Callable[[str], None] | None = None) -> Diagnosis:
    """The whole analysis of one log. Writes nothing unless `out_dir` is given. The best
    candidate is not named ("inconclusive", bench.analysis.diagnose.verdict) when the nominal
    is not a physical model of the axis or the extended model is worse."""
    say = progress or (lambda msg: None)
    settings, how = diagnosis_settings(log)
    say(f"nominal model and {len(EFFECTS)} effects, inverse view ({how})")
    first = diagnose_inverse(log, settings)
    inv, clipped = clipped_inverse(log, settings, first)
    d = _answer(log, settings, how, inv, clipped, forward, say)
    kept = set() if d.overruled else {c.effect for c in d.inverse.causes}
    if clipped is not None and clipped.named_by and not kept >= {c.effect for c in first.causes}:
        # the every-row view named more than the first view's causes (clipped.stopped_short),
        # but its answer, judged, keeps not all of them: the first view's causes stand on
        # their own rows, judged as they would have been without that view
        d = _answer(log, settings, how, first, replace(clipped, named_by=""), forward, say)
    if out_dir is not None:
        d = write(d, Path(out_dir), say)
    return d


def _answer(log: Log, settings: FilterSettings, how: str, inv: InverseDiagnosis,
            clipped: ClippedViews | None, forward: bool,
            say: Callable[[str], None]) -> Diagnosis:
    """The answer on the inverse view `inv` (clipped: what a clipped log's views found): its
    extended model, its forward view and the verdict, the causes the replay rejects left out
    in turn."""
    nom_p = nominal_parameters(inv.nominal)
    clip_note = clipping_warnings(log, refuse=False)
    if clipped is not None and clipped.named_by:
        clip_note = [clipped_samples(log).message(log.path) + ": the answer rests on every "
                     "row, the torque at tau_max taken as the one applied (the controller's "
                     "own clip)"]
    d = Diagnosis(log=log, settings=settings, settings_note=how, inverse=inv,
                  nominal_parameters=nom_p, extended_parameters={},
                  warnings=tuple(unit_warnings(log) + clip_note), clipped=clipped)
    replayed = _replayed(d, forward, say)
    judged = _verdict(replayed)
    notes: list[str] = []
    # Several causes whose extended model the forward view rejects: the later ones are left
    # out in turn, not the whole answer (each named cause keeps its own
    # gain; a worse replay of the last one says nothing of the ones named before it).
    # The last cause is judged against the replay of the model holding the ones before it,
    # when the forward view accepts that model: its inverse test was against that model,
    # and the nominal's replay lacks the earlier causes too (verdict.gain_reason).
    # (Not the masked pair's two: each was tested on top of the other, and neither stands
    # alone, identification.discrepancy.masked.)
    while (_replay_rejects(judged) and len(judged.inverse.causes) > 1
           and not (judged.inverse.masked is not None and judged.inverse.masked.named)):
        why = judged.overruled
        earlier = _replayed(replace(d, inverse=_without_last(judged.inverse, why)), forward,
                            say, judged.forward_nominal)
        prior = _verdict(earlier)
        if not prior.overruled and prior.forward_extended is not None:
            why = gain_reason(replayed, prior.forward_extended)
            if not why:   # the replay accepts the last cause on top of the ones before it
                judged = _verdict(replayed, prior.forward_extended)
                held = ", ".join(c.effect for c in prior.inverse.causes)
                notes.append(
                    f"{judged.inverse.causes[-1].effect} judged against the replay of the model "
                    f"holding {held}: torque error {prior.forward_extended.tau_rel_pct:.3g} % "
                    f"-> {replayed.forward_extended.tau_rel_pct:.3g} %")
                break
            inv = _without_last(replayed.inverse, why)
            earlier, prior = (replace(x, inverse=inv) for x in (earlier, prior))
        notes.append(f"{judged.inverse.causes[-1].effect} left out: {why}")
        replayed, judged = earlier, prior
    while cycle_only(judged) and judged.inverse.causes[-1].effect != "torque_lag" and \
            not (judged.inverse.masked is not None and judged.inverse.masked.named):
        why = ("the log sits in a limit cycle that the loop's stability with the lag "
               "explains; no replay reaches the cycle, and at it every state is periodic in "
               "time, so a later cause can take what the lag's model leaves there "
               "(verdict.cycle_only)")
        notes.append(f"{judged.inverse.causes[-1].effect} left out: {why}")
        judged = _judged(replace(d, inverse=_without_last(judged.inverse, why, "")),
                         forward, say, judged.forward_nominal)
    d = replace(judged, overruled=with_clipping(judged))
    if notes and not d.overruled:
        d = replace(d, forward_note="; ".join(n for n in (d.forward_note, *notes) if n))
    return d


def _judged(d: Diagnosis, forward: bool, say: Callable[[str], None],
            nominal_view: ForwardView | None = None) -> Diagnosis:
    """`d` with its extended parameters (every named cause, one fit), its forward view and
    the verdict: overruled when the nominal is unphysical or the extended model worse."""
    return _verdict(_replayed(d, forward, say, nominal_view))


def _replayed(d: Diagnosis, forward: bool, say: Callable[[str], None],
              nominal_view: ForwardView | None = None) -> Diagnosis:
    """`d` with its extended parameters (every named cause, one fit) and its forward view;
    overruled only when the nominal is unphysical."""
    inv = d.inverse
    ext = extended_parameters(inv.causes[-1] if inv.causes else None, inv.nominal)
    for _, params in joint_parameters(inv.nominal, inv.causes):   # all causes, one fit
        ext.update(params)
    d = replace(d, overruled=nominal_reason(d, ext))
    d = replace(d, extended_parameters={} if d.overruled else ext)
    if forward:
        d = add_forward_view(d, say, nominal_view)
    return d


def _verdict(d: Diagnosis, before: ForwardView | None = None) -> Diagnosis:
    """The verdict on `_replayed`'s `d`: overruled when the extended model is worse (the
    last cause judged against `before`, the replay of the model holding the causes before
    it, when given: verdict.gain_reason), when a clipped log's reading is not confirmed,
    or when none cannot be said."""
    if not d.overruled:
        d = replace(d, overruled=gain_reason(d, before) or every_row_reason(d)
                    or clipped_reason(d) or masked_reason(d))
    cycle = loop_cycle(d) if not d.overruled else None
    if cycle is not None and cycle.confirms:   # what confirms a lag named on every row
        held = d.clipped.held_text()
        d = replace(d, forward_note="; ".join(n for n in (d.forward_note, cycle.text(), held)
                                              if n),
                    clipped=replace(d.clipped, loop=cycle.to_json()))
    if d.overruled:   # nothing named: no extended model
        d = replace(d, extended_parameters={})
    return d


def _replay_rejects(d: Diagnosis) -> bool:
    """Overruled by the forward view alone: the first cause improves the inverse view and
    the nominal is physical, but the extended model's replay is worse or does not run."""
    c = d.inverse.named
    return (bool(d.overruled) and c is not None and c.after_pct < c.before_pct
            and d.forward_nominal is not None and not nominal_reason(d))


def _without_last(inv: InverseDiagnosis, why: str = "",
                  head: str = "the forward view rejects it: ") -> InverseDiagnosis:
    """`inv` without its last named cause, and without the ambiguity notes about it (a
    note's head "A or B:" or "one of A or B:" names the cause it is about: inverse.one_of); the cause listed as not named, left
    out for `why` (the forward view rejects its extended model)."""
    causes = inv.causes[:-1]
    kept = {c.effect for c in causes}
    notes = tuple(n for n in inv.notes if kept & one_of(n))
    last = inv.causes[-1]
    out = NotNamed(last.effect, "left_out", f"{head}{why}", last.test,
                   last.round)
    return replace(inv, causes=causes, notes=notes,
                   alternatives=tuple(a for a in inv.alternatives if a.named in kept),
                   not_named=(out,) + inv.not_named)
