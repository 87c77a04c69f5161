"""Plug-in estimators in a campaign (`campaign --method [LABEL=]TARGET`, `jb.campaign(methods=)`).

A method is a callable `f(log: jointbench.Log) -> {name: value}` or `{name: (value, sigma)}`
with the paper's parameter names (identification.parameters.PARAMETERS). TARGET is
`package.module:function` (the current folder is importable) or `path/to/file.py:function`.
The campaign imports it before any run, in a host process under the call's deadline (a bad
one is bad input, exit 2), and, in every process that runs experiments, by name again in
that process's hosts: only the text travels to the workers, and the campaign process never
imports a method's module (bench.campaign.host).

Each call sees the run's log *blind* (`blind`): the metadata a measured file would hold (the
sample rate, the controller's gains and limits, gravity, the joint, its axis type and gear
ratio, the encoders' resolution, the torque noise, the saturation counts, and the simulated
plant's time step and friction time constant that the built-in identification reads too),
and nothing that names the experiment: no `truth_*`, no seed, no source, no chirp, no
locked configuration, no effect. It runs under a deadline (bench.campaign.host); an
exception, a timeout or a result that is not a dict of finite numbers by known names is that
method's failure on that run, with the reason in the table, and the campaign goes on.
"""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import json
import math
import numbers
import os
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

from jointbench.bench.campaign.settings import ID_MODELS, CampaignError
from jointbench.bench.campaign.spec import PARAMS, CampaignSpec
from jointbench.identification.log import Log
from jointbench.bench.sim.plant_keys import (PLANT_INTEGRATOR_KEY, PLANT_STEPS_KEY,
                                             PLANT_TIMECONST_KEY)
from jointbench.identification.log.schema import BOOLEAN_META, FORMAT_KEY, NUMERIC_META
from jointbench.identification.parameters import PARAMETERS

# The names a campaign scores (those with ground truth in a virtual log): table columns
# `LABEL.NAME` and `LABEL.NAME.sigma` per method. J and offset (the rigid model's) are valid
# names without a truth: accepted, not scored.
SCORED = PARAMS["joint-motor"]
# The metadata a plug-in sees (`blind`): what a drive's log of a measured axis holds, and the
# simulated plant's keys that the built-in bias correction reads (so that a plug-in wrapping
# jointbench.identify sees what the built-in sees).
BLIND_META = frozenset(NUMERIC_META) | frozenset(BOOLEAN_META) | {
    FORMAT_KEY, PLANT_STEPS_KEY, PLANT_INTEGRATOR_KEY, PLANT_TIMECONST_KEY, "joint", "axis",
    "motor_encoder_resolution_rad", "link_encoder_resolution_rad", "torque_noise_std",
    "saturated_samples", "actuator_clamped_samples"}
DEFAULT_TIMEOUT_S = 60.0
_LABEL = re.compile(r"[A-Za-z][A-Za-z0-9_-]*\Z")
RESERVED = set(ID_MODELS) | set(ID_MODELS.values()) | {"truth", "run", "status", "reason"}


@dataclass(frozen=True)
class Method:
    """A plug-in estimator: its `label` (table columns, summary, gates) and `ref`, the text
    that finds it in any process (`module:attr` or `/abs/file.py:attr`), or None for a callable
    that cannot be found by name (then `fn`, usable in this process only)."""

    label: str
    ref: str | None
    fn: Callable[[Log], Any] | None = field(default=None, compare=False, repr=False)

    @property
    def source(self) -> str:
        name = getattr(self.fn, "__qualname__", type(self.fn).__name__)
        return self.ref or f"callable {name} (this process only)"

    def __getstate__(self):
        # Only the name travels to other processes; the callable is resolved there.
        return {"label": self.label, "ref": self.ref, "fn": None if self.ref else self.fn}

    def __setstate__(self, state):
        for k, v in state.items():
            object.__setattr__(self, k, v)

    def callable(self) -> Callable[[Log], Any]:
        return self.fn if self.ref is None else resolve(self.ref)


# --------------------------------------------------------------------------------------------
# Finding a method by name


_RESOLVED: dict[str, Callable] = {}


def _import_file(path: Path):
    """The module of a .py file, loaded once under a name derived from its path."""
    name = "jointbench_method_" + re.sub(r"\W", "_", str(path.with_suffix("")))
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def check_ref(ref: str) -> tuple[str, str]:
    """(target, attr) of `ref` (`module:attr` or `file.py:attr`), checked without importing
    anything: the form, and that a FILE.py exists. Raises CampaignError."""
    target, sep, attr = ref.rpartition(":")
    if not sep or not target or not attr:
        raise CampaignError(f"--method {ref}: expected MODULE:FUNCTION or FILE.py:FUNCTION")
    if target.endswith(".py") and not Path(target).is_file():
        raise CampaignError(f"--method {ref}: no such file {target}")
    return target, attr


def resolve(ref: str) -> Callable:
    """The callable that `ref` (`module:attr` or `file.py:attr`, attr may be dotted) names.
    Raises CampaignError saying what is missing."""
    if ref in _RESOLVED:
        return _RESOLVED[ref]
    target, attr = check_ref(ref)
    try:
        if target.endswith(".py"):
            module = _import_file(Path(target).resolve())
        else:
            if "" not in sys.path and os.getcwd() not in sys.path:
                sys.path.insert(0, os.getcwd())   # like `python -m`: the current folder
            module = importlib.import_module(target)
    except CampaignError:
        raise
    except BaseException as err:  # noqa: BLE001 - the user's module: anything can happen
        if isinstance(err, KeyboardInterrupt):
            raise
        raise CampaignError(f"--method {ref}: cannot import {target}: "
                            f"{type(err).__name__}: {err}") from None
    obj: Any = module
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise CampaignError(f"--method {ref}: {target} has no attribute {attr!r}")
        obj = getattr(obj, part)
    if not callable(obj):
        raise CampaignError(f"--method {ref}: {attr} is a {type(obj).__name__}, not callable")
    _RESOLVED[ref] = obj
    return obj


def check_label(label: str, flag: str = "--method") -> str:
    if not _LABEL.match(label):
        raise CampaignError(f"{flag}: label {label!r} must start with a letter and hold only "
                            "letters, digits, '_' and '-'")
    if label in RESERVED or label.endswith("+bc"):
        raise CampaignError(f"{flag}: label {label!r} is taken by the campaign itself")
    return label


def parse_method(text: str) -> Method:
    """`[LABEL=]TARGET` -> Method, TARGET's form checked now (check_ref); its module is
    imported by the campaign in a host process before any run (host.check_refs), never in
    this one. The default label is the function's name. Raises CampaignError."""
    text = text.strip()
    label, sep, target = text.partition("=")
    if not sep:
        label, target = "", text
    target = target.strip()
    attr = target.rpartition(":")[2]
    check_ref(target)   # a FILE.py stays as given (the table's spec line): workers share the cwd
    label = label.strip() or attr.split(".")[-1]
    return Method(check_label(label), target)


def method_of(obj: str | Callable | Method, label: str | None = None) -> Method:
    """A Method from the Python API's `methods=`: a Method, a `[LABEL=]TARGET` text, or a
    callable (found again by `module:qualname` when it can be, else run in this process)."""
    if isinstance(obj, Method):
        return obj
    if isinstance(obj, str):
        m = parse_method(obj)
        return dataclasses.replace(m, label=check_label(label)) if label else m
    if not callable(obj):
        raise CampaignError(f"methods: {obj!r} is not callable")
    name = label or getattr(obj, "__name__", None) or type(obj).__name__
    if not label and not _LABEL.match(name):
        raise CampaignError(f"methods: {name} needs a label: methods={{'name': function}}")
    module, qual = getattr(obj, "__module__", None), getattr(obj, "__qualname__", "")
    ref = f"{module}:{qual}" if module and "<" not in qual and module != "__main__" else None
    if ref is not None:
        try:
            ref = ref if resolve(ref) is obj else None
        except CampaignError:
            ref = None
    return Method(check_label(name, "methods"), ref, None if ref else obj)


def methods_of(methods) -> list[Method]:
    """The API's `methods=`: a sequence of methods (method_of) or a {label: method} dict."""
    if isinstance(methods, Mapping):
        return check_methods([method_of(m, label) for label, m in methods.items()])
    if isinstance(methods, (str, Method)) or callable(methods):
        methods = [methods]
    return check_methods([method_of(m) for m in methods])


def check_methods(methods: list[Method]) -> list[Method]:
    labels = [m.label for m in methods]
    repeated = sorted({x for x in labels if labels.count(x) > 1})
    if repeated:
        raise CampaignError(f"--method: label(s) {', '.join(repeated)} given twice; name them "
                            "LABEL=MODULE:FUNCTION")
    return methods


# --------------------------------------------------------------------------------------------
# The campaign spec with methods


@dataclass(frozen=True)
class MethodsSpec(CampaignSpec):
    """A CampaignSpec whose runs also call plug-in methods: `methods` holds `LABEL=SOURCE` per
    method (in the table's `# spec:` line, so a table is resumed only by the same methods)."""

    methods: tuple[str, ...] = ()

    def to_json(self) -> str:
        d = json.loads(super().to_json())
        if not self.methods:
            d.pop("methods", None)
        return json.dumps(d, sort_keys=True, separators=(",", ":"))

    def columns(self) -> list[str]:
        return super().columns() + [c for label in method_labels(self)
                                    for c in method_columns(label)]


def with_methods(spec: CampaignSpec, methods: list[Method]) -> CampaignSpec:
    """`spec` running `methods` too (itself when there are none)."""
    if not methods:
        return spec
    base = {f.name: getattr(spec, f.name) for f in dataclasses.fields(CampaignSpec)}
    return MethodsSpec(**base, methods=tuple(f"{m.label}={m.source}" for m in methods))


def method_labels(spec: CampaignSpec) -> list[str]:
    return [m.split("=", 1)[0] for m in getattr(spec, "methods", ())]


def method_columns(label: str) -> list[str]:
    cols = [f"{label}.status", f"{label}.reason"]
    for p in SCORED:
        cols += [f"{label}.{p}", f"{label}.{p}.sigma"]
    return cols


# --------------------------------------------------------------------------------------------
# A method's answer


class BadResult(ValueError):
    """A method's return value is not {name: value} or {name: (value, sigma)}."""


def _number(x, what: str) -> float:
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise BadResult(f"{what} is a {type(x).__name__}, not a number")
    v = float(x)
    if not math.isfinite(v):
        raise BadResult(f"{what} = {v} is not finite")
    return v


def check_estimates(value) -> tuple[dict[str, float], dict[str, float]]:
    """(estimates, sigmas) of a method's return value. Raises BadResult naming what is wrong:
    not a dict, no entries, an unknown name, a value that is not a finite number, a sigma that
    is negative."""
    if not isinstance(value, Mapping):
        raise BadResult(f"returned a {type(value).__name__}, expected a dict "
                        "{name: value} or {name: (value, sigma)}")
    if not value:
        raise BadResult("returned no estimates")
    unknown = [str(k) for k in value if k not in PARAMETERS]
    if unknown:
        raise BadResult(f"unknown parameter name(s) {', '.join(map(repr, unknown))} "
                        f"(known: {', '.join(PARAMETERS)})")
    est: dict[str, float] = {}
    sig: dict[str, float] = {}
    for name, v in value.items():
        if isinstance(v, (tuple, list)):
            if len(v) != 2:
                raise BadResult(f"{name}: expected (value, sigma), got {len(v)} items")
            est[name] = _number(v[0], name)
            if v[1] is not None:
                sig[name] = _number(v[1], f"sigma of {name}")
                if sig[name] < 0:
                    raise BadResult(f"sigma of {name} = {sig[name]} is negative")
        else:
            est[name] = _number(v, name)
    return est, sig


def blind(log: Log) -> Log:
    """The log as a measured file would be: only the BLIND_META keys of its metadata (no
    truth, no seed or anything else from which the experiment could be simulated again)."""
    meta = {k: v for k, v in log.meta.items() if k in BLIND_META}
    lines = {k: v for k, v in log.meta_lines.items() if k in meta}
    return dataclasses.replace(log, meta=meta, meta_lines=lines, path=None)
