"""`jointbench campaign`: N virtual experiments, each identified, one table row per run, and
the Monte Carlo summary (bias, empirical std, mean reported sigma, +-2 sigma coverage).

A campaign is a `CampaignSpec`: the settings of every run (model, joint, duration, chirp
amplitude, torque-noise level, encoder resolutions, parameter scatter, filter wn and Nd, hidden
effect, identification models), the number of runs and the campaign seed, and optionally one
setting swept over a list of values (`--sweep amplitude=0.05,0.1,0.2`). Run i is repeat
j = i mod runs of sweep point i // runs; its noise and scatter seeds derive from (campaign
seed, j) through numpy's SeedSequence, so every sweep point sees the same noise (paired
comparison) and a run's result does not depend on N, on the order runs finish in, or on the
number of workers.

The table (CSV) starts with `# jointbench-campaign: 1` and `# spec: {json}`, then a header and
one row per run: run, repeat, seed, status (ok / failed), reason, the run's settings, the truth
and, per identification model, each parameter's estimate, the paper's sigma and the corrected
sigma (`identification.uncertainty`, when the LS result carries one). Rows are appended as the
runs finish, each with one write, flush and fsync: a campaign killed part way is resumed by
running the same command again; the rows present are kept, a trailing partial line is dropped
and only the missing runs are done. When all runs are in, the table is rewritten sorted by run
(atomically): the same spec gives the same file, byte for byte, whatever the engine.

Engines (bench.executors): all local cores by default, `--workers N`, or an existing Dask
cluster with `--scheduler tcp://HOST:PORT`.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import os
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from jointbench.identification.log import atomic_write_text
from jointbench.identification.summary import NOMINAL_2SIGMA, ParameterStats, parameter_stats, stats_table

TABLE_MAGIC = "# jointbench-campaign: 1"

# Settings a campaign can sweep, with their types.
SWEEPABLE: dict[str, type] = {
    "amplitude": float,   # chirp amplitude [rad]
    "wn": float,          # Butterworth frequency [rad/s]
    "Nd": int,            # decimation factor
    "stencil": int,       # central-difference points: 3 (eq. 22) or 5
    "motor_bits": int,    # motor encoder bits per motor turn (joint side: / gear ratio)
    "link_bits": int,     # link encoder bits per turn
    "noise": float,       # current-loop torque noise, multiple of the default (1.25 % tau_max)
    "duration": float,    # experiment length [s]
    "scatter": float,     # relative std of the axis parameters around the model
}
ID_MODELS = {"joint-motor": "jm", "motor-only": "mo", "motor-only-printed": "mp"}
PARAMS = {"joint-motor": ("K", "Jm", "JL", "FVm", "FSm", "FV", "FS", "MX", "MY"),
          "motor-only": ("K", "Jm", "JL", "FVm", "FV", "FSm", "MX", "MY"),
          "motor-only-printed": ("K", "Jm", "JL", "FVm", "FV", "FSm")}
TRUTH = ("K", "Jm", "JL", "FVm", "FSm", "FV", "FS", "MX", "MY", "f1_hz")
SCATTERED = ("K", "Jm", "JL", "FVm", "FSm", "FV", "FS")
SIGMA_KINDS = {"sigma": "paper", "sigma_c": "corrected"}
DEBIASED_SIGMA_KINDS = {"sigma_c": "corrected", "sigma_r": "replicas"}
DEBIASED = "+bc"   # column prefix suffix of the bias-corrected estimates (bench.debias)
BIAS_CORRECTABLE = ("joint-motor", "motor-only")


def debiased_models(settings: "RunSettings") -> tuple[str, ...]:
    """The identification models whose estimates a run bias-corrects (--debias B > 0)."""
    if not settings.debias:
        return ()
    return tuple(m for m in settings.id_models if m in BIAS_CORRECTABLE)


class CampaignError(ValueError):
    """Bad campaign input or a table that does not belong to this campaign (exit status 2)."""


# --------------------------------------------------------------------------------------------
# Specification


@dataclass(frozen=True)
class RunSettings:
    """What one virtual experiment and its identification use. None: the project default
    (amplitude: the automatic chirp; motor_bits 17, link_bits 20; wn, Nd: the paper's 176 rad/s
    and 26 at 350.87 Hz)."""

    model: str = "prototype"
    joint: str | None = None
    duration: float = 60.0
    amplitude: float | None = None
    noise: float = 1.0
    motor_bits: int | None = None
    link_bits: int | None = None
    scatter: float = 0.0
    wn: float | None = None
    Nd: int | None = None
    stencil: int = 3
    effect: str | None = None
    id_models: tuple[str, ...] = ("joint-motor", "motor-only")
    debias: int = 0   # bias-correction replicas per two-mass identification (0: none)

    def __post_init__(self):
        if not self.id_models:
            raise CampaignError("at least one identification model is needed")
        for m in self.id_models:
            if m not in ID_MODELS:
                raise CampaignError(f"unknown identification model {m!r} "
                                    f"(choices: {', '.join(ID_MODELS)})")
        if self.stencil not in (3, 5):
            raise CampaignError(f"stencil must be 3 (eq. 22) or 5 points, got {self.stencil}")
        if self.debias != 0 and self.debias < 2:
            raise CampaignError(f"--debias needs 0 (off) or at least 2 replicas, got "
                                f"{self.debias}")
        if len(set(self.id_models)) != len(self.id_models):
            raise CampaignError(f"identification models repeated: {', '.join(self.id_models)}")


@dataclass(frozen=True)
class RunTask:
    """Run `index` of a campaign: repeat `repeat` at one sweep point, its seeds, its settings."""

    index: int
    repeat: int
    seed: int
    scatter_seed: int
    settings: RunSettings


@dataclass(frozen=True)
class CampaignSpec:
    """`runs` repeats of `base` (per sweep value when `sweep` names a setting)."""

    base: RunSettings = field(default_factory=RunSettings)
    runs: int = 200
    seed: int = 0
    sweep: str | None = None
    values: tuple[float, ...] = ()

    def __post_init__(self):
        if self.seed < 0:
            raise CampaignError(f"--seed must be >= 0, got {self.seed}")
        if self.runs < 1:
            raise CampaignError(f"--runs must be >= 1, got {self.runs}")
        if self.sweep is not None:
            if self.sweep not in SWEEPABLE:
                raise CampaignError(f"--sweep: cannot sweep {self.sweep!r} "
                                    f"(sweepable: {', '.join(SWEEPABLE)})")
            if not self.values:
                raise CampaignError(f"--sweep {self.sweep}: no values")

    @property
    def total(self) -> int:
        return self.runs * max(1, len(self.values))

    def to_json(self) -> str:
        """Canonical JSON (sorted keys): what the table's `# spec:` line holds."""
        d = asdict(self)
        d["base"]["id_models"] = list(self.base.id_models)
        d["values"] = list(self.values)
        return json.dumps(d, sort_keys=True, separators=(",", ":"))

    def settings_at(self, point: int) -> RunSettings:
        if self.sweep is None:
            return self.base
        return replace(self.base, **{self.sweep: SWEEPABLE[self.sweep](self.values[point])})

    def task(self, index: int) -> RunTask:
        if not 0 <= index < self.total:
            raise IndexError(index)
        point, repeat = divmod(index, self.runs)
        sim_seed, scatter_seed = (int(s) for s in
                                  np.random.SeedSequence([self.seed, repeat]).generate_state(2))
        return RunTask(index=index, repeat=repeat, seed=sim_seed, scatter_seed=scatter_seed,
                       settings=self.settings_at(point))

    def tasks(self) -> list[RunTask]:
        return [self.task(i) for i in range(self.total)]

    def columns(self) -> list[str]:
        cols = ["run", "repeat", "seed", "status", "reason", "model", "joint", *SWEEPABLE,
                "effect", "saturated"]
        cols += [f"truth.{p}" for p in TRUTH]
        for m in self.base.id_models:
            for p in PARAMS[m]:
                cols += [f"{ID_MODELS[m]}.{p}", f"{ID_MODELS[m]}.{p}.sigma",
                         f"{ID_MODELS[m]}.{p}.sigma_c"]
        for m in debiased_models(self.base):
            for p in PARAMS[m]:
                cols += [f"{ID_MODELS[m]}{DEBIASED}.{p}", f"{ID_MODELS[m]}{DEBIASED}.{p}.sigma_c",
                         f"{ID_MODELS[m]}{DEBIASED}.{p}.sigma_r"]
        return cols


# --------------------------------------------------------------------------------------------
# One run (executes in a worker: a top-level function of plain picklable data)


@dataclass(frozen=True)
class RunOutcome:
    """A finished run: its table row (strings) and the wall times it took in the worker."""

    index: int
    row: dict[str, str]
    sim_s: float = math.nan
    identify_s: float = math.nan


def _fmt(x) -> str:
    """Shortest round-trip text of a float (repr), 'nan' when missing; deterministic."""
    if x is None:
        return ""
    if isinstance(x, (int, np.integer)) and not isinstance(x, bool):
        return str(int(x))
    x = float(x)
    return repr(x) if math.isfinite(x) else "nan"


def scattered_factors(scatter: float, seed: int) -> dict[str, float]:
    """Log-normal factors exp(scatter z), z ~ N(0, 1), for K, Jm, JL, FVm, FSm, FV, FS."""
    if scatter <= 0:
        return {p: 1.0 for p in SCATTERED}
    z = np.random.default_rng(seed).standard_normal(len(SCATTERED))
    return {p: float(np.exp(scatter * zi)) for p, zi in zip(SCATTERED, z)}


def _scale_first(element, attr: str, compiled: float, factor: float) -> None:
    """Set the first number of `attr` (the compiled value when the attribute is absent, e.g.
    from a default class) to compiled x factor, at full precision (repr)."""
    tokens = (element.get(attr) or "").split()
    value = repr(float(compiled) * factor)
    element.set(attr, " ".join([value] + tokens[1:]) if tokens else value)


def scattered_mjcf(model: str, joint: str | None, factors: dict[str, float]) -> tuple[str, str]:
    """The MJCF text of `model` with the axis' parameters scaled by `factors`: tendon
    stiffness (K), rotor armature, damping and frictionloss (Jm, FVm, FSm), link damping and
    frictionloss (FV, FS), and the link body's mass and inertia (JL; its first moments MX, MY
    scale with it: a heavier or lighter payload). Returns (xml, joint).

    The file's own XML is edited (ElementTree) with the compiled values x factor written at
    full precision: MjSpec.to_xml rounds every number to 6 digits (K 20341.0458 -> 20341, the
    timestep too). Relative asset folders and includes are made absolute, so the text compiles
    from any folder."""
    import xml.etree.ElementTree as ET

    from jointbench.models import ModelStructureError, load_model

    full, axes, path = load_model(model)
    names = [a.name for a in axes]
    joint = joint or names[0]
    if joint not in names:
        raise ModelStructureError(f"{path}: no axis '{joint}' (axes: {', '.join(names)})")
    axis = axes[names.index(joint)]
    root = ET.parse(path).getroot()
    base = path.resolve().parent

    def named(tag: str, name: str):
        found = [e for e in root.iter(tag) if e.get("name") == name]
        if len(found) != 1:
            raise ModelStructureError(f"{path}: parameter scatter needs exactly one <{tag} "
                                      f"name=\"{name}\"> in the file itself (found {len(found)})")
        return found[0]

    _scale_first(named("fixed", f"{joint}_spring"), "stiffness",
                 full.tendon_stiffness[axis.tendon], factors["K"])
    rotor, link = named("joint", f"{joint}_motor"), named("joint", joint)
    _scale_first(rotor, "armature", full.dof_armature[axis.motor_dof], factors["Jm"])
    for el, dof, fv, fs in ((rotor, axis.motor_dof, "FVm", "FSm"),
                            (link, axis.link_dof, "FV", "FS")):
        _scale_first(el, "damping", full.dof_damping[dof], factors[fv])
        _scale_first(el, "frictionloss", full.dof_frictionloss[dof], factors[fs])
    body = named("body", full.body(full.jnt_bodyid[axis.link_joint]).name)
    inertial = body.find("inertial")
    if inertial is None:
        raise ModelStructureError(f"{path}: body '{body.get('name')}' has no explicit "
                                  "<inertial>: parameter scatter scales the link's mass and inertia")
    f = factors["JL"]
    inertial.set("mass", repr(float(inertial.get("mass")) * f))
    for attr in ("diaginertia", "fullinertia"):
        if inertial.get(attr):
            inertial.set(attr, " ".join(repr(float(v) * f) for v in inertial.get(attr).split()))
    compiler = root.find("compiler")
    if compiler is None:
        compiler = ET.SubElement(root, "compiler")
    for attr in ("meshdir", "texturedir", "assetdir"):
        folder = compiler.get(attr)
        if folder is not None or attr == "assetdir":
            compiler.set(attr, str(base / (folder or "")))
    for inc in root.iter("include"):
        inc.set("file", str(base / inc.get("file")))
    return ET.tostring(root, encoding="unicode"), joint


def _sensors(settings: RunSettings, model_ref: str, joint: str | None):
    """Sensors.default with the campaign's noise multiple and encoder resolutions."""
    from jointbench.bench.sim.axes import build_experiment_model
    from jointbench.bench.sim.sensors import Sensors

    if settings.noise == 1.0 and settings.motor_bits is None and settings.link_bits is None:
        return None
    exp = build_experiment_model(model_ref, joint)
    base = Sensors.default(exp.truth.gear_ratio, exp.tau_max)
    N = exp.truth.gear_ratio or 100.0
    return Sensors(
        motor_resolution=(2 * math.pi / (2 ** settings.motor_bits * N)
                          if settings.motor_bits is not None else base.motor_resolution),
        link_resolution=(2 * math.pi / 2 ** settings.link_bits
                         if settings.link_bits is not None else base.link_resolution),
        torque_noise_std=settings.noise * base.torque_noise_std)


def _filter(settings: RunSettings, log):
    from jointbench.identification.filtering import FilterSettings
    from jointbench.identification.defaults import default_settings

    if settings.wn is None and settings.Nd is None and settings.stencil == 3:
        return None
    base = default_settings(log.sample_rate_hz, log.truth().get("f1_hz"))
    return FilterSettings(wn=settings.wn if settings.wn is not None else base.wn, m=base.m,
                          Nd=settings.Nd if settings.Nd is not None else base.Nd, ts=log.ts,
                          stencil=settings.stencil)


def corrected_sigmas(ident, log) -> dict[str, float]:
    """Standard deviations of the physical parameters from the corrected covariance that
    identification.uncertainty attaches to the LS result (`cov_corrected`), propagated through
    the motor-only inversion like the paper's; {} when the LS result carries none."""
    ls = ident.ls
    cov = getattr(ls, "cov_corrected", None)
    if callable(cov):
        cov = cov()
    if cov is None:
        return {}
    cov = np.asarray(cov, dtype=float)
    if ident.model.startswith("motor-only"):
        from jointbench.identification.physical import invert_motor_only

        swapped = replace(ls, cov=cov, sigma=np.sqrt(np.abs(np.diag(cov))))
        phys = invert_motor_only(swapped, g=log.gravity, qc=float(np.mean(log.q_m)))
        return {n: phys.std(n) for n in phys.names}
    return {n: float(np.sqrt(cov[i, i])) for i, n in enumerate(ls.names)
            if n not in ls.unidentifiable}


def run_task(task: RunTask) -> RunOutcome:
    """Simulate and identify one run; never raises: a failure is the row's status and reason."""
    s = task.settings
    row: dict[str, str] = {"run": str(task.index), "repeat": str(task.repeat),
                           "seed": str(task.seed), "status": "ok", "reason": "",
                           "model": s.model, "joint": s.joint or "", "effect": s.effect or ""}
    for name in SWEEPABLE:
        row[name] = _fmt(getattr(s, name))
    reasons: list[str] = []
    sim_s = identify_s = math.nan
    try:
        from jointbench.bench.effects import parse_effect
        from jointbench.bench.sim.experiment import run_experiment

        t0 = time.perf_counter()
        effect = parse_effect(s.effect) if s.effect else None
        with tempfile.TemporaryDirectory(prefix="jointbench-run-") as tmp:
            model_ref, joint = s.model, s.joint
            if s.scatter > 0:
                xml, joint = scattered_mjcf(s.model, s.joint,
                                            scattered_factors(s.scatter, task.scatter_seed))
                model_ref = str(Path(tmp) / "scattered.xml")
                Path(model_ref).write_text(xml, encoding="utf-8")
            result = run_experiment(model_ref, joint, duration=s.duration, seed=task.seed,
                                    amplitude=s.amplitude, effect=effect,
                                    sensors=_sensors(s, model_ref, joint))
        sim_s = time.perf_counter() - t0
    except Exception as err:  # noqa: BLE001 - recorded in the row
        reasons.append(f"simulation: {type(err).__name__}: {err}")
        result = None
    if result is not None:
        log = result.log
        row["joint"] = log.meta.get("joint", row["joint"])
        row["saturated"] = str(result.saturated)
        truth = log.truth()
        for p in TRUTH:
            row[f"truth.{p}"] = _fmt(truth.get(p))
        t1 = time.perf_counter()
        for m in s.id_models:
            try:
                from jointbench.identification.identify import identify

                ident = identify(log, m, _filter(s, log))
                corr = corrected_sigmas(ident, log)
            except Exception as err:  # noqa: BLE001 - recorded in the row
                reasons.append(f"{m}: {type(err).__name__}: {err}")
                continue
            pre = ID_MODELS[m]
            for p in PARAMS[m]:
                row[f"{pre}.{p}"] = _fmt(ident.physical.get(p))
                row[f"{pre}.{p}.sigma"] = _fmt(ident.physical_sigma.get(p))
                row[f"{pre}.{p}.sigma_c"] = _fmt(corr.get(p))
            if m in debiased_models(s):
                try:
                    from jointbench.bench.analysis.debias import debias, friction_timeconst_of

                    d = debias(log, ident, replicas=s.debias, seed=task.seed,
                               friction_timeconst=friction_timeconst_of(
                                   result.experiment.model, result.experiment.axis))
                except Exception as err:  # noqa: BLE001 - recorded in the row
                    reasons.append(f"{m} bias correction: {type(err).__name__}: {err}")
                    continue
                for p in PARAMS[m]:
                    row[f"{pre}{DEBIASED}.{p}"] = _fmt(d.estimate.get(p))
                    row[f"{pre}{DEBIASED}.{p}.sigma_c"] = _fmt(d.sigma.get(p))
                    row[f"{pre}{DEBIASED}.{p}.sigma_r"] = _fmt(d.sigma_replicas.get(p))
        identify_s = time.perf_counter() - t1
    if reasons:
        row["status"] = "failed"
        row["reason"] = " ".join("; ".join(reasons).split())  # one line
    return RunOutcome(task.index, row, sim_s, identify_s)


def lost_outcome(task: RunTask, error: str) -> RunOutcome:
    """The row of a run the engine lost (worker died)."""
    row = {"run": str(task.index), "repeat": str(task.repeat), "seed": str(task.seed),
           "status": "failed", "reason": " ".join(error.split()), "model": task.settings.model,
           "joint": task.settings.joint or "", "effect": task.settings.effect or ""}
    for name in SWEEPABLE:
        row[name] = _fmt(getattr(task.settings, name))
    return RunOutcome(task.index, row)


# --------------------------------------------------------------------------------------------
# The table: append-only while running, sorted when complete


def _csv_line(values: Sequence[str]) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(values)
    return buf.getvalue()


class CampaignTable:
    """The CSV table of a campaign, opened for appending; resumes an existing one.

    `rows` maps run index -> row (dict of strings) for every run recorded so far.
    """

    def __init__(self, path: Path, spec: CampaignSpec):
        self.path = Path(path)
        self.spec = spec
        self.columns = spec.columns()
        self.rows: dict[int, dict[str, str]] = {}
        self.dropped_partial = False
        if self.path.exists():
            self._resume()
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            head = TABLE_MAGIC + "\n" + "# spec: " + spec.to_json() + "\n" + _csv_line(self.columns)
            atomic_write_text(self.path, head)
        self._handle = open(self.path, "a", encoding="utf-8", newline="")

    def _preamble(self) -> list[str]:
        return [TABLE_MAGIC, "# spec: " + self.spec.to_json(), _csv_line(self.columns).rstrip("\n")]

    def _resume(self) -> None:
        if self.path.is_dir():
            raise CampaignError(f"{self.path}: is a directory")
        raw = self.path.read_bytes()
        text = raw.decode("utf-8", errors="replace")
        complete = text[: text.rfind("\n") + 1]
        if complete != text:
            # A run killed in the middle of a write: drop the partial line, keep the rest.
            self.dropped_partial = True
            with open(self.path, "r+b") as f:
                f.truncate(len(complete.encode("utf-8")))
                f.flush()
                os.fsync(f.fileno())
        lines = complete.split("\n")[:-1]
        expected = self._preamble()
        for lineno, (have, want) in enumerate(zip(lines, expected), start=1):
            if have != want:
                what = {1: "is not a jointbench campaign table (first line)",
                        2: "was written by a different campaign (its '# spec:' line differs); "
                           "run the same command as before to resume it, or choose another --out",
                        3: "has a different header"}[lineno]
                raise CampaignError(f"{self.path}:{lineno}: {what}")
        if len(lines) < len(expected):
            raise CampaignError(f"{self.path}: incomplete header ({len(lines)} lines); "
                                "delete the file to start afresh")
        for lineno, values in enumerate(csv.reader(lines[len(expected):]),
                                        start=len(expected) + 1):
            if len(values) != len(self.columns):
                raise CampaignError(f"{self.path}:{lineno}: {len(values)} columns, "
                                    f"expected {len(self.columns)}")
            try:
                index = int(values[0])
            except ValueError:
                raise CampaignError(f"{self.path}:{lineno}: column 'run': not an integer: "
                                    f"{values[0]!r}") from None
            if not 0 <= index < self.spec.total:
                raise CampaignError(f"{self.path}:{lineno}: run {index} outside this campaign "
                                    f"(0-{self.spec.total - 1})")
            self.rows.setdefault(index, dict(zip(self.columns, values)))

    def append(self, row: dict[str, str]) -> None:
        """One row, one write, then flush and fsync: a kill leaves at most a partial last line."""
        index = int(row["run"])
        if index in self.rows:
            return
        self._handle.write(_csv_line([row.get(c, "") for c in self.columns]))
        self._handle.flush()
        os.fsync(self._handle.fileno())
        self.rows[index] = {c: row.get(c, "") for c in self.columns}

    def close(self) -> None:
        if not self._handle.closed:
            self._handle.close()

    def finalize(self) -> None:
        """Rewrite the complete table sorted by run (atomically)."""
        self.close()
        body = "".join(_csv_line([self.rows[i][c] for c in self.columns])
                       for i in sorted(self.rows))
        atomic_write_text(self.path, "\n".join(self._preamble()) + "\n" + body)


def read_table(path: str | Path) -> tuple[CampaignSpec, list[dict[str, str]]]:
    """The spec and rows (sorted by run) of a campaign table."""
    path = Path(path)
    lines = path.read_text(encoding="utf-8").split("\n")
    if not lines or lines[0] != TABLE_MAGIC or len(lines) < 3 or not lines[1].startswith("# spec: "):
        raise CampaignError(f"{path}:1: not a jointbench campaign table")
    spec = spec_from_json(lines[1][len("# spec: "):])
    reader = csv.DictReader([ln for ln in lines[2:] if ln])
    rows = sorted(reader, key=lambda r: int(r["run"]))
    return spec, rows


def spec_from_json(text: str) -> CampaignSpec:
    d = json.loads(text)
    base = d.pop("base")
    base["id_models"] = tuple(base["id_models"])
    return CampaignSpec(base=RunSettings(**base), runs=d["runs"], seed=d["seed"],
                        sweep=d["sweep"], values=tuple(d["values"]))


# --------------------------------------------------------------------------------------------
# Summary


def _num(row: dict[str, str], key: str) -> float:
    v = row.get(key, "")
    try:
        return float(v) if v else math.nan
    except ValueError:
        return math.nan


def _model_stats(sel: list[dict[str, str]], pre: str, params: tuple[str, ...],
                 sigma_kinds: dict[str, str], k: float) -> list[dict]:
    """Per parameter the statistics of the columns `pre.p` against `truth.p`, each sigma column
    `pre.p.col` as the coverage of kind `sigma_kinds[col]`."""
    stats = []
    for p in params:
        est = np.array([_num(r, f"{pre}.{p}") for r in sel])
        truth = np.array([_num(r, f"truth.{p}") for r in sel])
        sig = {kind: np.array([_num(r, f"{pre}.{p}.{col}") for r in sel])
               for col, kind in sigma_kinds.items()}
        stats.append(parameter_stats(p, est, truth, sig, k).as_dict())
    return stats


def summarize(spec: CampaignSpec, rows: list[dict[str, str]], k: float = 2.0) -> dict:
    """The campaign's Monte Carlo statistics (JSON-able): per sweep point, per identification
    model, per parameter: bias, empirical std, mean sigma (paper and corrected) and coverage."""
    failures: dict[str, int] = {}
    for r in rows:
        if r["status"] != "ok":
            key = r["reason"][:160]
            failures[key] = failures.get(key, 0) + 1
    groups = []
    points = range(max(1, len(spec.values)))
    for point in points:
        sel = [r for r in rows if int(r["run"]) // spec.runs == point]
        group = {"n_runs": len(sel), "ok": sum(r["status"] == "ok" for r in sel)}
        if spec.sweep is not None:
            group["sweep"] = {spec.sweep: spec.values[point]}
        models = {}
        for m in spec.base.id_models:
            models[m] = _model_stats(sel, ID_MODELS[m], PARAMS[m], SIGMA_KINDS, k)
        for m in debiased_models(spec.base):
            models[f"{m} (bias-corrected)"] = _model_stats(sel, ID_MODELS[m] + DEBIASED,
                                                           PARAMS[m], DEBIASED_SIGMA_KINDS, k)
        group["models"] = models
        groups.append(group)
    return {"spec": json.loads(spec.to_json()), "runs": len(rows),
            "ok": sum(r["status"] == "ok" for r in rows),
            "failed": sum(r["status"] != "ok" for r in rows),
            "failures": dict(sorted(failures.items(), key=lambda kv: -kv[1])[:10]),
            "k_sigma": k, "nominal_coverage": NOMINAL_2SIGMA if k == 2.0 else None,
            "groups": groups}


def _stats_of(group_model: list[dict]) -> list[ParameterStats]:
    from jointbench.identification.summary import Coverage

    out = []
    for d in group_model:
        cov = {kind: Coverage(n=c["n"], sigma_mean=c["sigma_mean"],
                              sigma_mean_pct=c["sigma_mean_pct"], coverage=c["coverage"],
                              interval=tuple(c["coverage_ci95"]),
                              std_over_sigma=c["std_over_sigma"])
               for kind, c in d["coverage"].items()}
        out.append(ParameterStats(d["name"], d["n"], d["truth_mean"], d["bias"], d["bias_pct"],
                                  d["std"], d["std_pct"], d["rmse_pct"], d["k"], cov))
    return out


def summary_text(summary: dict) -> str:
    """The summary as fixed-width tables (printed, and the body of the Markdown file)."""
    lines = [f"runs: {summary['runs']}, ok: {summary['ok']}, failed: {summary['failed']}"]
    for reason, count in summary["failures"].items():
        lines.append(f"  failed x{count}: {reason}")
    lines.append("Columns: bias and empirical std of (estimate - truth) in % of truth; per kind "
                 "of reported sigma: its mean in % of truth, empirical std / RMS sigma "
                 f"(1 = calibrated), and the +-{summary['k_sigma']:g} sigma coverage with its "
                 "95 % interval (nominal 95.4 %).")
    for group in summary["groups"]:
        title = ", ".join(f"{k} = {v:g}" for k, v in group.get("sweep", {}).items())
        for m, stats in group["models"].items():
            kinds = tuple(kind for kind in ("paper", "corrected", "replicas")
                          if any(s["coverage"].get(kind, {}).get("n", 0) > 0 for s in stats))
            lines.append("")
            lines.append(f"## {m}" + (f" ({title})" if title else "")
                         + f": {group['ok']} of {group['n_runs']} runs ok")
            lines.append(stats_table(_stats_of(stats), kinds or ("paper",)))
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------
# Driver


class Progress:
    """A one-line progress bar on a stream (stderr), redrawn at most 10 times a second."""

    def __init__(self, total: int, done: int = 0, stream=None, enabled: bool = True,
                 label: str = "campaign"):
        self.total, self.done, self.failed = total, done, 0
        self.start_done = done
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.label = label
        self.t0 = time.perf_counter()
        self._last = 0.0

    def update(self, ok: bool) -> None:
        self.done += 1
        self.failed += 0 if ok else 1
        now = time.perf_counter()
        if self.enabled and (now - self._last > 0.1 or self.done == self.total):
            self._last = now
            rate = (self.done - self.start_done) / max(now - self.t0, 1e-9)
            eta = (self.total - self.done) / rate if rate > 0 else math.inf
            width = 30
            fill = int(width * self.done / max(self.total, 1))
            self.stream.write(f"\r{self.label}: [{'#' * fill}{'.' * (width - fill)}] "
                              f"{self.done}/{self.total} runs, {self.failed} failed, "
                              f"{rate:.2f} runs/s, eta {eta:.0f} s ")
            if self.done == self.total:
                self.stream.write("\n")
            self.stream.flush()


@dataclass(frozen=True)
class CampaignResult:
    spec: CampaignSpec
    rows: list[dict[str, str]]
    summary: dict
    resumed: int          # rows found in the table before this invocation
    new: int              # runs done by this invocation
    wall_s: float
    sim_s: list[float]
    identify_s: list[float]


def run_campaign(spec: CampaignSpec, table: str | Path, executor,
                 progress: Callable[[bool], None] | None = None) -> CampaignResult:
    """Run the campaign's missing runs on `executor` (bench.executors), appending to `table`;
    when all are in, sort the table and return the rows and summary."""
    tab = CampaignTable(Path(table), spec)
    resumed = len(tab.rows)
    pending = [spec.task(i) for i in range(spec.total) if i not in tab.rows]
    sim_s: list[float] = []
    identify_s: list[float] = []
    t0 = time.perf_counter()
    try:
        for done in executor.map_unordered(run_task, pending):
            outcome = done.value if done.error is None else lost_outcome(done.item, done.error)
            tab.append(outcome.row)
            if math.isfinite(outcome.sim_s):
                sim_s.append(outcome.sim_s)
            if math.isfinite(outcome.identify_s):
                identify_s.append(outcome.identify_s)
            if progress is not None:
                progress(outcome.row["status"] == "ok")
    finally:
        tab.close()
    wall = time.perf_counter() - t0
    tab.finalize()
    rows = [tab.rows[i] for i in sorted(tab.rows)]
    return CampaignResult(spec=spec, rows=rows, summary=summarize(spec, rows), resumed=resumed,
                          new=len(pending), wall_s=wall, sim_s=sim_s, identify_s=identify_s)


# --------------------------------------------------------------------------------------------
# Command line (`jointbench campaign`; bench/cli.py registers it)


def _parse_sweep(text: str) -> tuple[str, tuple[float, ...]]:
    if "=" not in text:
        raise CampaignError(f"--sweep '{text}': expected NAME=V1,V2,... "
                            f"(NAME one of {', '.join(SWEEPABLE)})")
    name, values = text.split("=", 1)
    name = name.strip()
    if name not in SWEEPABLE:
        raise CampaignError(f"--sweep: cannot sweep {name!r} (sweepable: {', '.join(SWEEPABLE)})")
    out = []
    for v in values.split(","):
        try:
            x = SWEEPABLE[name](v.strip())
        except ValueError:
            raise CampaignError(f"--sweep {name}: value {v!r} is not "
                                f"{'an integer' if SWEEPABLE[name] is int else 'a number'}") from None
        if not math.isfinite(x):
            raise CampaignError(f"--sweep {name}: value {v!r} is not finite")
        out.append(x)
    return name, tuple(out)


def add_arguments(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    p.add_argument("--model", default="prototype",
                   help="prototype, arm6 or an MJCF file following the axis convention")
    p.add_argument("--joint", help="axis to move (default: the first)")
    p.add_argument("--runs", type=int, default=200,
                   help="runs (per sweep value with --sweep; default 200)")
    p.add_argument("--seed", type=int, default=0, help="campaign seed (default 0)")
    p.add_argument("--duration", type=float, default=60.0, help="experiment length in s (default 60)")
    p.add_argument("--amplitude", type=float, help="chirp amplitude in rad (default: automatic)")
    p.add_argument("--noise", type=float, default=1.0,
                   help="torque noise as a multiple of the default 1.25 %% of tau_max (default 1)")
    p.add_argument("--motor-bits", type=int, help="motor encoder bits per turn (default 17)")
    p.add_argument("--link-bits", type=int, help="link encoder bits per turn (default 20)")
    p.add_argument("--scatter", type=float, default=0.0,
                   help="relative (log-normal) scatter of K, Jm, JL, FVm, FSm, FV, FS around "
                        "the model, e.g. 0.1 (default 0)")
    p.add_argument("--wn", type=float, help="Butterworth frequency in rad/s (default 176)")
    p.add_argument("--decimate", type=int, help="decimation factor Nd (default 26)")
    p.add_argument("--stencil", type=int, default=3, choices=(3, 5),
                   help="central-difference points: 3, the paper's eq. (22) (default), or 5")
    p.add_argument("--effect", help="hidden effect NAME=STRENGTH[:OPTION=VALUE] in every run")
    p.add_argument("--id-models", default="joint-motor,motor-only",
                   help="identification models, comma separated (default joint-motor,motor-only)")
    p.add_argument("--debias", type=int, default=0, metavar="B",
                   help="also bias-correct every two-mass estimate by B closed-loop replicas "
                        "(bench/debias.py; each run then costs about 1 + B experiments; "
                        "default 0: off)")
    p.add_argument("--sweep", help="sweep one setting: NAME=V1,V2,... with NAME one of "
                                   + ", ".join(SWEEPABLE))
    p.add_argument("--workers", type=int,
                   help="local worker processes (default: all cores; 1 runs in this process)")
    p.add_argument("--scheduler", help="run on an existing Dask cluster: tcp://HOST:PORT")
    p.add_argument("--out", default="campaign.csv",
                   help="table file; an existing one of the same campaign is resumed "
                        "(default campaign.csv)")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def spec_from_args(args: argparse.Namespace) -> CampaignSpec:
    for name in ("duration", "noise", "scatter", "amplitude", "wn"):
        v = getattr(args, name)
        if v is not None and not math.isfinite(v):
            raise CampaignError(f"--{name}: {v} is not finite")
    if args.duration <= 0:
        raise CampaignError(f"--duration must be positive, got {args.duration:g}")
    if args.noise < 0:
        raise CampaignError(f"--noise must be >= 0, got {args.noise:g}")
    if args.scatter < 0:
        raise CampaignError(f"--scatter must be >= 0, got {args.scatter:g}")
    if args.effect:
        from jointbench.bench.effects import parse_effect

        parse_effect(args.effect)  # ValueError names what is wrong
    base = RunSettings(model=str(args.model), joint=args.joint, duration=args.duration,
                       amplitude=args.amplitude, noise=args.noise, motor_bits=args.motor_bits,
                       link_bits=args.link_bits, scatter=args.scatter, wn=args.wn,
                       Nd=args.decimate, stencil=args.stencil, effect=args.effect,
                       debias=args.debias,
                       id_models=tuple(m.strip() for m in args.id_models.split(",") if m.strip()))
    sweep, values = _parse_sweep(args.sweep) if args.sweep else (None, ())
    if not str(args.model) in ("prototype", "prototype_axis", "arm6") and not Path(args.model).is_file():
        raise CampaignError(f"--model {args.model}: no such model file")
    return CampaignSpec(base=base, runs=args.runs, seed=args.seed, sweep=sweep, values=values)


def jsonable(x):
    """x with every non-finite float replaced by None (strict JSON)."""
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def summary_paths(table: Path) -> tuple[Path, Path]:
    stem = table.with_suffix("") if table.suffix.lower() == ".csv" else table
    return Path(f"{stem}.summary.json"), Path(f"{stem}.summary.md")


def main(args: argparse.Namespace) -> int:
    """`jointbench campaign`."""
    from jointbench.bench.campaign.executors import make_executor

    spec = spec_from_args(args)
    out = Path(args.out)
    if out.suffix.lower() == ".xml" or (Path(str(args.model)).exists()
                                        and out.resolve() == Path(str(args.model)).resolve()):
        raise CampaignError(f"--out {out}: refusing to overwrite the model file")
    executor = make_executor(args.workers, args.scheduler)
    try:
        tab_rows = 0
        if out.exists():
            tab = CampaignTable(out, spec)  # validates before any work
            tab_rows = len(tab.rows)
            tab.close()
        bar = Progress(spec.total, tab_rows, enabled=not args.quiet and sys.stderr.isatty())
        if not args.quiet:
            print(f"campaign: {spec.total} runs ({tab_rows} already in {out}) on "
                  f"{executor.description}", file=sys.stderr)
        result = run_campaign(spec, out, executor, progress=bar.update)
    finally:
        executor.close()
    summary = dict(result.summary)
    summary["table"] = str(out)
    summary["timing"] = {
        "engine": executor.description, "workers": executor.workers,
        "runs_this_invocation": result.new, "resumed_rows": result.resumed,
        "wall_s": result.wall_s,
        "runs_per_s": result.new / result.wall_s if result.wall_s > 0 and result.new else None,
        "mean_simulation_s": float(np.mean(result.sim_s)) if result.sim_s else None,
        "mean_identification_s": float(np.mean(result.identify_s)) if result.identify_s else None,
    }
    text = summary_text(summary)
    json_path, md_path = summary_paths(out)
    atomic_write_text(json_path, json.dumps(jsonable(summary), indent=1, allow_nan=False) + "\n")
    t = summary["timing"]
    timing = (f"{result.new} runs in {result.wall_s:.1f} s on {executor.description}"
              + (f" ({t['runs_per_s']:.2f} runs/s; per run: simulation "
                 f"{t['mean_simulation_s']:.3f} s, identification "
                 f"{1e3 * t['mean_identification_s']:.1f} ms, all models)"
                 if t["runs_per_s"] and t["mean_simulation_s"] and t["mean_identification_s"]
                 else "")
              + (f"; {result.resumed} rows resumed from the table" if result.resumed else ""))
    atomic_write_text(md_path, f"# Campaign {out.name}\n\n{timing}\n\n```\n{text}\n```\n")
    if args.json:
        print(json.dumps(jsonable(summary), allow_nan=False))
    else:
        print(f"table: {out}; summary: {json_path}, {md_path}")
        print(timing)
        print(text)
    return 0 if summary["ok"] > 0 else 1
