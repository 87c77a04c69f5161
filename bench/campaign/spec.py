"""A campaign's specification: `runs` repeats of one `RunSettings`, optionally per value of one
swept setting (`--sweep amplitude=0.05,0.1,0.2`), and the campaign seed.

Run i is repeat j = i mod runs of sweep point i // runs; its noise and scatter seeds derive
from (campaign seed, j) through numpy's SeedSequence, so every sweep point sees the same noise
(paired comparison) and a run's result does not depend on N, on the order runs finish in, or
on the number of workers. The spec also names the table's columns (bench.campaign.table).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from jointbench.bench.campaign.settings import (ID_MODELS, SWEEPABLE, CampaignError, RunSettings,
                                                debiased_models)
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


def spec_from_json(text: str) -> CampaignSpec:
    """The spec of a table's `# spec:` line (CampaignSpec.to_json)."""
    d = json.loads(text)
    base = d.pop("base")
    base["id_models"] = tuple(base["id_models"])
    return CampaignSpec(base=RunSettings(**base), runs=d["runs"], seed=d["seed"],
                        sweep=d["sweep"], values=tuple(d["values"]))
