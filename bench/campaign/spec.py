"""A campaign's specification: `runs` repeats of one `RunSettings`, optionally per value of one
swept setting (`--sweep amplitude=0.05,0.1,0.2`), and the campaign seed.

Run i is repeat j = i mod runs of sweep point i // runs; its noise and scatter seeds derive
from (campaign seed, j) through numpy's SeedSequence, so every sweep point sees the same noise
(paired comparison) and a run's result does not depend on N, on the order runs finish in, or
on the number of workers. The spec also names the table's columns (bench.campaign.table).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from jointbench.bench.campaign.settings import (ID_MODELS, SWEEPABLE, CampaignError, RunSettings,
                                                debiased_models)
from jointbench.bench.sim.reference import Chirp
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.parameters import (MOTOR_ONLY_PHYSICAL, PARAMETERS,
                                                  STIFFNESS_AND_INERTIAS, TWO_MASS)


def _stiffness_first(names: tuple[str, ...]) -> tuple[str, ...]:
    """`names` with K, Jm, JL first (the table's order), the others in their given order."""
    return STIFFNESS_AND_INERTIAS + tuple(n for n in names if n not in STIFFNESS_AND_INERTIAS)


_GRAVITY = tuple(n for n, p in PARAMETERS.items() if p.group == "gravity")   # MX, MY
# The physical parameters recorded per identification model, in column order.
PARAMS = {"joint-motor": _stiffness_first(TWO_MASS),
          "motor-only": _stiffness_first(MOTOR_ONLY_PHYSICAL) + _GRAVITY,
          "motor-only-printed": _stiffness_first(MOTOR_ONLY_PHYSICAL)}
TRUTH = PARAMS["joint-motor"] + ("f1_hz",)
DEBIASED = "+bc"   # column prefix suffix of the bias-corrected estimates (bench.analysis.debias)


# The command-line option of each RunSettings field (for the messages).
OPTION = {"duration": "--duration", "amplitude": "--amplitude", "noise": "--noise",
          "motor_bits": "--motor-bits", "link_bits": "--link-bits", "scatter": "--scatter",
          "wn": "--wn", "Nd": "--decimate", "stencil": "--stencil"}
# The default chirp fades in and out over `taper` s each: a run must hold both.
MIN_DURATION_S = 2 * next(f.default for f in fields(Chirp) if f.name == "taper")
MAX_BITS = 52          # an encoder finer than 2 pi / 2**52 rad is below double precision
MAX_RUNS = 10**6       # runs of one campaign (sweep points included)
MIN_ROWS = 16          # decimated rows the identification needs at least (6 edge + 10)


def check_settings(s: RunSettings, where: str = "") -> None:
    """CampaignError naming the option (and `where`: the sweep value) of a setting no run can
    use: checked for every sweep point before any run starts."""
    def fail(name: str, value, want: str) -> None:
        lead = f"{where}: {OPTION[name]}" if where else f"{OPTION[name]} {value:g}:"
        raise CampaignError(f"{lead} must be {want}")

    for name in ("duration", "amplitude", "noise", "scatter", "wn"):
        v = getattr(s, name)
        if v is not None and not math.isfinite(v):
            fail(name, v, "a finite number")
    if not s.duration >= MIN_DURATION_S:
        fail("duration", s.duration, f"at least {MIN_DURATION_S:g} s (the chirp fades in and "
                                     "out over 2 s each)")
    if s.amplitude is not None and not s.amplitude > 0:
        fail("amplitude", s.amplitude, "positive (rad)")
    for name in ("noise", "scatter"):
        if not getattr(s, name) >= 0:
            fail(name, getattr(s, name), ">= 0")
    for name in ("motor_bits", "link_bits"):
        v = getattr(s, name)
        if v is not None and not 1 <= v <= MAX_BITS:
            fail(name, v, f"between 1 and {MAX_BITS} bits per turn")
    rate = s.rate or PAPER_RATE
    nyquist, lowest = math.pi * rate, 2 * math.pi / s.duration
    if s.wn is not None and not lowest <= s.wn < nyquist:
        fail("wn", s.wn, f"in [{lowest:.3g}, {nyquist:.0f}) rad/s: at least one cycle over "
                         f"the run, below the Nyquist frequency at {rate:g} Hz")
    samples = s.duration * rate
    if s.Nd is not None and not 1 <= s.Nd <= samples / MIN_ROWS:
        fail("Nd", s.Nd, f"between 1 and {int(samples / MIN_ROWS)} (a {s.duration:g} s run "
                         f"has {samples:.0f} samples, the fit needs {MIN_ROWS} decimated rows)")


def model_digest(model: str) -> str:
    """SHA-256 of the model file's content (a shipped model's too); "" when unreadable."""
    from jointbench.models import model_path

    try:
        return hashlib.sha256(Path(model_path(model)).read_bytes()).hexdigest()
    except (OSError, ValueError):
        return ""


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
    """`runs` repeats of `base` (per sweep value when `sweep` names a setting).

    Raises CampaignError for a negative seed, no runs, or a sweep of an unknown setting or
    without values."""

    base: RunSettings = field(default_factory=RunSettings)
    runs: int = 200
    seed: int = 0
    sweep: str | None = None
    values: tuple[float, ...] = ()
    # SHA-256 of the model file when the campaign started: a resume refuses to mix runs of a
    # model edited since (default: computed now).
    model_sha256: str | None = None

    def __post_init__(self):
        if self.model_sha256 is None:
            object.__setattr__(self, "model_sha256", model_digest(self.base.model))
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
        if self.total > MAX_RUNS:
            raise CampaignError(f"--runs {self.runs}: {self.total:,} runs, over the "
                                f"{MAX_RUNS:,} a campaign holds (its tasks are listed up front)")
        check_settings(self.base)
        for point, value in enumerate(self.values):
            check_settings(self.settings_at(point), f"--sweep {self.sweep}={value:g}")

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


def spec_from_json(text: str) -> CampaignSpec:
    """The spec of a table's `# spec:` line (CampaignSpec.to_json)."""
    d = json.loads(text)
    base = d.pop("base")
    base["id_models"] = tuple(base["id_models"])
    return CampaignSpec(base=RunSettings(**base), runs=d["runs"], seed=d["seed"],
                        sweep=d["sweep"], values=tuple(d["values"]),
                        model_sha256=d.get("model_sha256", ""))


def spec_difference(stored: str, spec: CampaignSpec) -> str:
    """Why a table's `# spec:` line `stored` is not `spec`'s: the model file edited since the
    table was started, or another campaign."""
    try:
        old = json.loads(stored[len("# spec: "):]) if stored.startswith("# spec: ") else None
    except ValueError:
        old = None
    if isinstance(old, dict):
        new = json.loads(spec.to_json())
        if "model_sha256" not in old:
            return ("was written by an older jointbench, without the model file's content hash "
                    "a resume checks: choose another --out to start the campaign afresh")
        if old.get("model_sha256") != new["model_sha256"] and \
                {k: v for k, v in old.items() if k != "model_sha256"} == \
                {k: v for k, v in new.items() if k != "model_sha256"}:
            return (f"the model file {spec.base.model} changed since this table was started "
                    f"(SHA-256 {str(old.get('model_sha256'))[:12] or 'none'}... then, "
                    f"{new['model_sha256'][:12]}... now): refusing to mix runs of two models; "
                    "restore the file or choose another --out")
    return ("was written by a different campaign (its '# spec:' line differs); run the same "
            "command as before to resume it, or choose another --out")
