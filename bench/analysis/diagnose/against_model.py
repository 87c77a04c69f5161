"""`jointbench diagnose LOG --model ROBOT.xml`: what the user's own simulation gets wrong.

The user's MJCF (axis convention of models/__init__.py) is the nominal:
1. its values of eqs. (5)-(7) for the moving axis, in the log's locked configuration
   (`bench.analysis.diagnose.model_edit.spec_truth`);
2. the values the log supports: the log's identification (joint-motor model, eq. 13) with
   its autocorrelation-corrected sigma;
3. for each of K, Jm, JL, FVm, FSm, FV, FS, MX, MY the error of the model in % of the data's
   value, significant by the rule of `significant` (stated there, not tuned on any case);
   the value of a significant one is then estimated again with every parameter the log does
   not contradict (within 3 sigma) held at the model's value (`refit`: the model stands where
   the log does not contradict it), which the report gives as its data value (the free
   identification's stays as `identified`);
4. DIR/corrected.xml: the user's MJCF with the significant errors corrected;
   DIR/extended.xml: corrected + the structural effects the log names
   (`bench.effects.write_effects`); `link_coulomb` is named when the MJCF has no link
   friction and the data shows some;
5. the forward view: the logged experiment replayed in closed loop (bench.sim.replay, the
   log's reference, gains and encoder resolutions) on the user's model, the corrected and
   the extended one: the torque error before and after, and the same on a `validate` log.
   The replay adds no torque noise: the log's noise realisation is unknown, and another one
   would add its own closed-loop response to every model alike. What even a perfect model
   leaves, the closed-loop response to the log's own noise, is estimated from the log
   (`model_floor`: the replay's noise floor) and each error's excess over it reported.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import mujoco
import numpy as np

from jointbench.bench.analysis.diagnose.model_checks import compiled, load_spec, log_axis
from jointbench.bench.analysis.diagnose.model_edit import (EDITABLE, GRAVITY, Corrected,
                                                           corrected_spec, spec_truth)
from jointbench.bench.analysis.diagnose.model_floor import (excess, replay_floor, replay_model,
                                                            torque_noise_std)
from jointbench.bench.analysis.diagnose.model_precision import Coarse, coarse
from jointbench.bench.analysis.diagnose.run import diagnose, extended_parameters
from jointbench.bench.effects import write_effects
from jointbench.bench.sim.nominal import write_xml
from jointbench.bench.sim.replay import ReplayError, forward_errors
from jointbench.identification.discrepancy.candidates import joint_parameters
from jointbench.identification.identify import Identification, identify
from jointbench.identification.log import Log
from jointbench.identification.parameters import FRICTIONS, STIFFNESS_AND_INERTIAS
from jointbench.models import find_axes, model_path

# The physical parameters of eq. (13) (identification.parameters.TWO_MASS), in the report's order.
COMPARED = STIFFNESS_AND_INERTIAS + FRICTIONS + GRAVITY
SIGMAS = 3.0        # |model - data| beyond this many corrected sigmas ...
FLOOR_PCT = 5.0     # ... and beyond this share of the data's value
# Effects a user's MJCF carries as parameters, not as extra elements.
AS_PARAMETERS = {"gravity": "MX, MY (the MJCF's masses and centres of mass)",
                 "link_coulomb": "FS (frictionloss of the link joint)"}
MODELS = ("model", "corrected", "extended")


@dataclass(frozen=True)
class ParameterError:
    """One parameter: the MJCF's value, the log's, the log's sigma (autocorrelation-corrected,
    identification.uncertainty), the error in % and whether it is significant."""

    name: str
    model: float
    data: float
    sigma: float
    error_pct: float
    significant: bool
    identified: float = math.nan   # the free identification's value, when `data` is a refit
    error_sigma_pct: float = math.nan   # sigma carried into error_pct (points of %)

    def to_json(self) -> dict:
        out = {"model": self.model, "data": self.data, "sigma": self.sigma,
               "error_pct": self.error_pct, "error_sigma_pct": self.error_sigma_pct,
               "significant": self.significant}
        if math.isfinite(self.identified):
            out["identified"] = self.identified
        return out


def significant(model: float, data: float, sigma: float, scale: float) -> tuple[float, bool]:
    """(error %, significant) of a model value against the data's.

    error % = 100 (model - data) / scale, scale = |data| (for MX and MY: the gravity moment
    sqrt(MX^2 + MY^2) of the data, as either may be near zero). Significant when both hold:
    - |model - data| > SIGMAS x sigma: the log itself rules the model's value out (3 sigma,
      the usual bar; sigma is the corrected one, which holds for coloured residuals);
    - |error| > FLOOR_PCT: a physical floor, the accuracy one expects of a catalogue or CAD
      value, under which editing the model is not worth it however precise the log is.
    A sigma that is not finite (not identified) makes nothing significant."""
    if not scale > 0:
        return (0.0 if model == data else math.inf), False
    err = 100.0 * (model - data) / scale
    if not math.isfinite(sigma):
        return err, False
    return err, abs(model - data) > SIGMAS * sigma and abs(err) > FLOOR_PCT


def error_sigma(model: float, data: float, sigma: float, scale: float, gravity: bool) -> float:
    """The sigma of `significant`'s error % [points] that the data's sigma carries: for
    100 (model - data) / |data|, 100 |model| sigma / data^2; for MX, MY (a fixed scale, the
    gravity moment) 100 sigma / scale."""
    if not scale > 0:
        return math.nan
    return 100.0 * sigma / scale if gravity else 100.0 * abs(model) * sigma / data ** 2


def compare(model: dict[str, float], data: dict[str, float],
            sigma: dict[str, float]) -> dict[str, ParameterError]:
    """ParameterError for every name of COMPARED both sides know with a finite value
    (`significant`'s rule)."""
    out = {}
    g = math.hypot(data.get("MX", 0.0), data.get("MY", 0.0))
    for name in COMPARED:
        if name not in model or name not in data:
            continue
        m, d, s = float(model[name]), float(data[name]), float(sigma.get(name, math.nan))
        if not (math.isfinite(m) and math.isfinite(d)):   # K of a rigid MJCF: not comparable
            continue
        scale = g if name in GRAVITY else abs(d)
        err, sig = significant(m, d, s, scale)
        out[name] = ParameterError(name, m, d, s, err, sig,
                                   error_sigma_pct=error_sigma(m, d, s, scale, name in GRAVITY))
    return out


@dataclass(frozen=True)
class ModelDiagnosis:
    """The diagnosis of a log against the user's MJCF (module docstring)."""

    log: Log
    source: Path
    joint: str
    config: dict[str, float]
    identification: Identification
    errors: dict[str, ParameterError]
    corrected: Corrected
    effects: tuple[tuple[str, dict[str, float]], ...]   # structural effects, in order
    named_causes: tuple[str, ...]
    forward: dict[str, dict] = field(default_factory=dict)     # label -> forward_errors
    validation: dict[str, dict] = field(default_factory=dict)  # same on the validate log
    validate_path: str = ""
    notes: tuple[str, ...] = ()
    xml: dict[str, str] = field(default_factory=dict)   # corrected.xml, extended.xml texts
    files: tuple[str, ...] = ()
    log_diagnosis: object = None    # the log-only Diagnosis the structural effects come from

    @property
    def wrong_parameters(self) -> tuple[str, ...]:
        return tuple(n for n, e in self.errors.items() if e.significant)

    @property
    def coarse(self) -> dict[str, Coarse]:
        """The parameters whose error this log cannot tell within 2 points, with the
        duration that would (model_precision)."""
        return coarse(self.errors, len(self.log) * self.log.ts, SIGMAS)

    @property
    def named_cause(self) -> str:
        return self.named_causes[0] if self.named_causes else "none"

    def gain(self, views: dict[str, dict] | None = None) -> dict:
        """Forward torque error (% RMS) of each model, the ratios model / corrected and
        model / extended, and with the replay's noise floor (model_floor) the floor, each
        model's excess over it and the largest gain a perfect model could show,
        model / floor."""
        views = self.forward if views is None else views
        out: dict = {"metric": "forward view, torque error % RMS (closed-loop replay)"}
        for label in MODELS:
            if label in views and "torque_rel_pct" in views[label]:
                out[label] = views[label]["torque_rel_pct"]
        base = out.get("model")
        for label in ("corrected", "extended"):
            if base is not None and out.get(label):
                out[f"ratio_{label}"] = base / out[label]
        floor = views.get("floor", {}).get("torque_rel_pct")
        if floor is not None and base is not None:
            out["floor"] = floor
            out["noise_std"] = views["floor"].get("torque_noise_std")
            for label in MODELS:
                if label in out:
                    out[f"excess_{label}"] = excess(out[label], floor)
            out["ratio_ceiling"] = base / floor
        return out


def _config(log: Log, given: dict[str, float] | None, axes: Sequence[str]) -> dict[str, float]:
    """The locked configuration: the log's `locked_config` metadata (a bench log's) for the
    model's axes, overridden by `given` (--config)."""
    out: dict[str, float] = {}
    for item in log.meta.get("locked_config", "").split():
        key, _, value = item.partition("=")
        try:
            if key in axes:
                out[key] = float(value)
        except ValueError:
            continue
    out.update(given or {})
    return out


def contradicted(e: ParameterError) -> bool:
    """The log rules the model's value out: |model - data| > SIGMAS sigma (every significant
    parameter, and those under the FLOOR_PCT floor that the log still rules out). The sigma
    holds the log's noise, not the identification's own model error, which shows once the
    noise is small (a long log of a true model can contradict its frictions)."""
    return abs(e.model - e.data) > SIGMAS * e.sigma


def refit(ident: Identification, model: dict[str, float],
          free: Sequence[str]) -> dict[str, float]:
    """The parameters `free` estimated again with every other parameter held at the model's
    value: the identification's estimate X^ (eq. 13) conditioned on the held ones with the
    paper's covariance C (white residuals),

        X_f = X^_f + C_fh C_hh^-1 (X_model,h - X^_h),

    for least squares, C = sigma^2 (W^T W)^-1, exactly the regression with the held columns
    moved to the left-hand side (with the identification's instruments nearly so). Fewer free
    parameters: less of the log's noise, and none of the held ones' own small biases, reaches
    them through their correlation. The held values must be ones the log does not
    contradict (the caller frees every `contradicted` one): a held value's error reaches the
    free ones through C_fh C_hh^-1. That is also why C is the white one: the corrected
    (HAC) covariance couples the parameters far more, so a held value's error reaches the
    free ones more. {} when the identification is not the joint-motor model or nothing
    is free."""
    ls = ident.ls
    names = [n for n in ls.names if n not in ls.unidentifiable]
    f = [ls.names.index(n) for n in names if n in free]
    h = [ls.names.index(n) for n in names if n not in free]
    C = ls.cov
    if (ident.model != "joint-motor" or not f or any(n not in model for n in names)
            or not np.all(np.isfinite(C[np.ix_(f + h, f + h)]))):
        return {}
    held = np.array([model[ls.names[k]] for k in h]) - ls.X[h]
    x = ls.X[f] + (C[np.ix_(f, h)] @ np.linalg.solve(C[np.ix_(h, h)], held) if h else 0.0)
    return {ls.names[k]: float(v) for k, v in zip(f, x)}


def _refitted(errors: dict[str, ParameterError], values: dict[str, float],
              data: dict[str, float]) -> dict[str, ParameterError]:
    """`errors` with each refitted parameter's data value and error replaced. The sigma stays
    the free identification's, and so does the significance it decided: the refit's own
    conditional sigma is smaller than the refit's spread, and claims more than the log
    knows; the free sigma covers that spread."""
    out = dict(errors)
    g = math.hypot(data.get("MX", 0.0), data.get("MY", 0.0))
    for n, v in values.items():
        e = errors[n]
        scale = g if n in GRAVITY else abs(v)
        err, _ = significant(e.model, v, e.sigma, scale)
        out[n] = ParameterError(n, e.model, v, e.sigma, err, e.significant, identified=e.data,
                                error_sigma_pct=error_sigma(e.model, v, e.sigma, scale,
                                                            n in GRAVITY))
    return out


def _identify(log: Log) -> tuple[Identification, dict[str, float], dict[str, float]]:
    ident = identify(log, "joint-motor" if log.q is not None else "auto")
    sigma = dict(ident.physical_sigma)
    sigma.update(ident.physical_sigma_corrected)
    return ident, dict(ident.physical), sigma


def _structural(log: Log, errors: dict[str, ParameterError], model_fs: float,
                say: Callable[[str], None]) -> tuple[list, list[str], list[str], object]:
    """The structural effects the log names (the log-only diagnosis), to write on top of the
    corrected model; `link_coulomb` first when the MJCF lacks the link friction the data
    shows. Returns (effects with parameters, named causes, notes, the log's Diagnosis)."""
    say("structural effects: the log's own diagnosis (inverse view)")
    d = diagnose(log, forward=False)
    named, effects, notes = [], [], []
    fs = errors.get("FS")
    if fs is not None and fs.significant and model_fs == 0 and fs.data > 0:
        named.append("link_coulomb")
    # the causes the diagnosis names (none when it is overruled: an unphysical nominal, an
    # extended model that does not improve the inverse view), each with its passing test
    causes = d.causes
    # each cause's values from the one fit of all of them (a cause's own fit may predate a
    # later one that searched its value again: identification.discrepancy.candidates)
    joint = dict(joint_parameters(d.inverse.nominal, [c for c in causes if c is not None]))
    for c in causes:
        if c is None or c.effect in named:
            continue
        named.append(c.effect)
        if c.effect in AS_PARAMETERS:
            notes.append(f"{c.effect}: carried by {AS_PARAMETERS[c.effect]}; see the "
                         "parameter errors")
            continue
        effects.append((c.effect, {**extended_parameters(c, d.inverse.nominal),
                                   **joint.get(c.effect, {})}))
    return effects, named, notes, d


def _forward(paths: dict[str, Path], joint: str, config: dict[str, float], log: Log,
             noise_std: float, say: Callable[[str], None]) -> dict[str, dict]:
    """forward_errors of each model's replay of `log`, and under "floor" the replay's noise
    floor (model_floor.replay_floor, with the corrected model and torque noise `noise_std`)."""
    out: dict[str, dict] = {}
    for label, path in paths.items():
        say(f"forward view: {label} replay of {log.path or 'the log'}")
        try:
            r = replay_model(path, joint, config, log)
        except (ReplayError, ValueError) as err:
            out[label] = {"error": str(err)}
            continue
        out[label] = forward_errors(log, r)
        if label != "corrected":
            continue
        say("forward view: the replay's noise floor")
        try:
            floor = replay_floor(path, joint, config, log, r, noise_std)
        except (ReplayError, ValueError) as err:
            out["floor"] = {"error": str(err)}
            continue
        if math.isfinite(floor):
            out["floor"] = {"torque_rel_pct": floor, "torque_noise_std": noise_std}
    return out


def _extended(source: Path, joint: str, config: dict[str, float], corrections: dict,
              effects: list, K: float) -> mujoco.MjSpec:
    spec = corrected_spec(source, joint, config, corrections).spec
    write_effects(spec, joint, effects, K)
    return spec


def diagnose_against_model(log: Log, model: str | Path, joint: str | None = None,
                           config: dict[str, float] | None = None, forward: bool = True,
                           validate: Log | None = None,
                           progress: Callable[[str], None] | None = None) -> ModelDiagnosis:
    """The whole analysis of `log` against the MJCF `model` (module docstring). `joint`:
    the axis (name or index from 1; default the log's `joint` metadata, else the first);
    `config`: locked angles of the other axes (default the log's `locked_config`). The
    corrected and extended MJCF texts are in `xml` (bench.analysis.diagnose.model_report
    writes them). Raises ModelStructureError for a model off the axis convention,
    LogError for an unusable log."""
    say = progress or (lambda msg: None)
    source = model_path(model)
    spec = load_spec(source)
    compiled_model = compiled(spec, source)
    axes = find_axes(compiled_model, str(source))
    names = [a.name for a in axes]
    joint, checked = log_axis(log, compiled_model, axes, joint, source)
    config = _config(log, config, names)
    truth = spec_truth(spec, joint, config, str(source))[0]
    say(f"model {source.name}, axis {joint}; identification of {log.path or 'the log'}")
    ident, data, sigma = _identify(log)
    errors = compare(truth.as_dict(), data, sigma)
    wrong = [n for n, e in errors.items() if e.significant]
    values = refit(ident, truth.as_dict(), [n for n, e in errors.items() if contradicted(e)])
    errors = _refitted(errors, {n: v for n, v in values.items() if n in wrong}, data)
    corrections = {n: e.data for n, e in errors.items() if e.significant and n in EDITABLE}
    corrected = corrected_spec(source, joint, config, corrections)
    effects, named, notes, d = _structural(log, errors, truth.FS, say)
    notes = checked + list(corrected.notes) + notes
    K = spec_truth(corrected.spec, joint, config)[0].K
    with tempfile.TemporaryDirectory() as tmp:   # the replays read files
        folder = Path(tmp)
        paths = {"model": source, "corrected": folder / "corrected.xml"}
        write_xml(corrected.spec, paths["corrected"])
        if effects:
            paths["extended"] = folder / "extended.xml"
            write_xml(_extended(source, joint, config, corrections, effects, K),
                      paths["extended"])
        noise = torque_noise_std(log, ident)
        views = _forward(paths, joint, config, log, noise, say) if forward else {}
        checks = (_forward(paths, joint, config, validate, noise, say)
                  if validate is not None else {})
        xml = {p.name: p.read_text() for label, p in paths.items() if label != "model"}
    return ModelDiagnosis(log=log, source=source, joint=joint, config=config,
                          identification=ident, errors=errors, corrected=corrected,
                          effects=tuple(effects), named_causes=tuple(named), forward=views,
                          validation=checks,
                          validate_path=str(validate.path or "") if validate else "",
                          notes=tuple(notes), xml=xml, log_diagnosis=d)
