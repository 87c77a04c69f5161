"""`jointbench diagnose`: what the simulation gets wrong on a log, the named cause, the extended
model and the gain (CONTRACT sections 3 and 4).

1. Nominal model from the data (identification.discrepancy.nominal) and its MuJoCo axis.
2. Two views of the error: inverse (predicted torque and link-equation residual on the measured
   motion) and forward (the logged experiment replayed in closed loop in MuJoCo).
3. Every effect of CONTRACT section 4 tested; the best one named only when significant.
4. The named effect written into the MJCF (DIR/extended.xml) with its identified parameter.
5. Both views again with the extended model: the gain, figures and DIR/report.md.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from jointbench.identification.discrepancy import Candidate, InverseDiagnosis, Nominal, diagnose_inverse
from jointbench.identification.effects import EFFECTS
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.defaults import default_settings, PAPER_RATE
from jointbench.identification.frequency import first_mode_hz, measured_frf
from jointbench.identification.log import Log

BLOCK_NAMES = ("motor equation (eq. 6): torque residual, % of the measured torque RMS",
               "link equation (eq. 5): residual, % of the spring torque K (qm - q) RMS")


def diagnosis_settings(log: Log) -> tuple[FilterSettings, str]:
    """The bandpass of section 3.2 for this log, and how it was chosen. At the paper's rate:
    the paper's wn and Nd. Otherwise, with `q`: the first mode from the measured link response
    (identification.frequency.first_mode_hz) and eqs. (28)-(29). Without `q`: generic."""
    rate = log.sample_rate_hz
    if abs(rate / PAPER_RATE - 1) < 0.01:
        return default_settings(rate), "the paper's wn = 176 rad/s, Nd = 26 (section 4)"
    if log.q is not None:
        frf = measured_frf(log, output="q")
        f1 = first_mode_hz(frf, fmin=0.5, fmax=min(60.0, 0.2 * rate))
        return (default_settings(rate, f1),
                f"first mode {f1:.2f} Hz from the measured q / tau_m response; wn and Nd "
                "from eqs. (28)-(29)")
    from jointbench.identification.defaults import generic_settings
    return (generic_settings(rate),
            "no link position: generic band (Butterworth at 0.1 Fs, Nd = 10)")


@dataclass(frozen=True)
class ForwardView:
    """Replay errors (CONTRACT section 2 closed loop) of one model against the log."""

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

    @property
    def named(self) -> Candidate | None:
        return self.inverse.named

    @property
    def named_cause(self) -> str:
        return self.inverse.named_cause

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
            "candidates": [_candidate_json(c) for c in self.inverse.candidates],
            "extended_parameters": self.extended_parameters,
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
        untested = {c.effect: c.reason for c in self.inverse.candidates if not c.testable}
        if untested:
            out["untested"] = untested
        if self.files:
            out["files"] = list(self.files)
        return _finite_json(out)


def _forward_json(f: ForwardView) -> dict:
    out = {"tau_rel_pct": f.tau_rel_pct, "q_m_rms": f.q_m_rms, "q_m_rel_pct": f.q_m_rel_pct}
    if f.q_rms is not None:
        out["q_rms"] = f.q_rms
    return out


def _candidate_json(c: Candidate) -> dict:
    out = {"effect": c.effect, "significant": c.significant, "testable": c.testable}
    if c.testable:
        out.update({"explained_pct": c.explained_pct, "score": c.delta_bic,
                    "p_value": c.p_value, "size_pct": c.size_pct,
                    "before_pct": c.before_pct, "after_pct": c.after_pct,
                    "parameters": c.parameters})
        if c.unphysical:
            out["unphysical"] = c.unphysical
    else:
        out["reason"] = c.reason
    return out


def _finite_json(x):
    """JSON has no NaN or inf: they become null."""
    if isinstance(x, dict):
        return {k: _finite_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite_json(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def nominal_parameters(nom: Nominal) -> dict[str, float]:
    """Physical parameters of the nominal axis; gravity as MX, MY of eq. 13 (rest at qs)."""
    p = {n: float(v) for n, v in zip(nom.names, nom.X)}
    if "P" in p:
        P = p.pop("P")
        p["MX"], p["MY"] = -P * math.sin(nom.sig.qs), P * math.cos(nom.sig.qs)
    return p


def extended_parameters(c: Candidate | None, nom: Nominal) -> dict[str, float]:
    """The named effect's parameter under its CONTRACT name (identification.effects), its
    other identified parameters, and the refitted nominal parameters of the extended model."""
    if c is None:
        return {}
    out = {k: float(v) for k, v in c.parameters.items()}
    refit = {n: float(v) for n, v in zip(c.names, c.X) if n in nom.names}
    for n, v in refit.items():
        if n != "P":
            out.setdefault(n, v)
    if "P" in refit and c.effect != "gravity":
        out["MX"] = -refit["P"] * math.sin(nom.sig.qs)
        out["MY"] = refit["P"] * math.cos(nom.sig.qs)
    return out


def diagnose(log: Log, out_dir: Path | None = None, forward: bool = True,
             progress: Callable[[str], None] | None = None) -> Diagnosis:
    """The whole analysis of one log. Writes nothing unless `out_dir` is given."""
    say = progress or (lambda msg: None)
    settings, how = diagnosis_settings(log)
    say(f"nominal model and {len(EFFECTS)} effects, inverse view ({how})")
    inv = diagnose_inverse(log, settings)
    nom_p = nominal_parameters(inv.nominal)
    ext_p = extended_parameters(inv.named, inv.nominal)
    d = Diagnosis(log=log, settings=settings, settings_note=how, inverse=inv,
                  nominal_parameters=nom_p, extended_parameters=ext_p)
    if forward:
        from jointbench.bench.analysis.diagnose import forward as diagnose_forward
        d = diagnose_forward.add_forward_view(d, say)
    if out_dir is not None:
        from jointbench.bench.analysis.diagnose import report as diagnose_report
        d = diagnose_report.write(d, Path(out_dir), say)
    return d


def dumps(d: Diagnosis) -> str:
    return json.dumps(d.to_json(), indent=2)


def summary_text(d: Diagnosis) -> str:
    """What `jointbench diagnose` prints: the ranking, the named cause and the gain."""
    inv = d.inverse
    nom = inv.nominal
    L = [f"filter: wn = {d.settings.wn:.1f} rad/s, Nd = {d.settings.Nd} ({d.settings_note})",
         "nominal model: " + ", ".join(f"{k} = {v:.5g}" for k, v in d.nominal_parameters.items()),
         "inverse view, nominal: " + "; ".join(
             f"{BLOCK_NAMES[b].split(':')[0]} {nom.relative_error_pct(nom.residual, b):.2f} %"
             for b in np.unique(nom.block))]
    if d.forward_nominal is not None:
        f = d.forward_nominal
        L.append(f"forward view, nominal: torque {f.tau_rel_pct:.2f} % RMS, q_m {f.q_m_rms:.3g} "
                 "RMS" + (f", q {f.q_rms:.3g} RMS" if f.q_rms is not None else ""))
    elif d.forward_note:
        L.append(f"forward view: {d.forward_note}")
    L += ["", f"{'effect':20s} {'signif.':>7s} {'explained %':>11s} {'delta BIC':>10s} "
              f"{'size %':>7s}  parameters"]
    for c in inv.candidates:
        if not c.testable:
            L.append(f"{c.effect:20s} {'-':>7s}  not testable: {c.reason}")
            continue
        pars = ", ".join(f"{k} = {v:.4g}" for k, v in c.parameters.items())
        if c.unphysical:
            pars += " (unphysical)"
        L.append(f"{c.effect:20s} {'yes' if c.significant else 'no':>7s} {c.explained_pct:11.1f} "
                 f"{c.delta_bic:10.1f} {c.size_pct:7.2f}  {pars}")
    L += ["", f"named cause: {d.named_cause}"]
    if d.named is not None:
        info = EFFECTS[d.named_cause]
        before, after = d.inverse_before_after
        L.append(f"{info.parameter} = {d.extended_parameters[info.parameter]:.5g} {info.unit}")
        L.append(f"gain, inverse view ({BLOCK_NAMES[d.view_block].split(':')[0]}): "
                 f"{before:.2f} % -> {after:.2f} % ({before / after:.2f}x)")
        if d.forward_nominal is not None and d.forward_extended is not None:
            a, b = d.forward_nominal, d.forward_extended
            L.append(f"gain, forward view: torque {a.tau_rel_pct:.2f} % -> {b.tau_rel_pct:.2f} %, "
                     f"q_m {a.q_m_rms:.3g} -> {b.q_m_rms:.3g}"
                     + (f", q {a.q_rms:.3g} -> {b.q_rms:.3g}" if a.q_rms is not None
                        and b.q_rms is not None else ""))
    if d.files:
        L.append("wrote: " + ", ".join(Path(f).name for f in d.files))
    return "\n".join(L)
