"""Simulation-based bias correction of a least-squares identification (parametric bootstrap).

`jointbench identify --debias N`. The paper's least squares is biased by what its regressor
approximates, not by noise alone (README "Accuracy", "Where the remaining bias comes from"):
the central differences of eq. (22) at the mode, the motor Coulomb friction as
FSm sign(qm') while the rotor sticks at velocity reversals, and the correlation the closed
loop creates between the torque noise and the regressor. Each is a few tenths of a per cent,
several times the paper's sigma on long clean logs, so that sigma's interval misses the truth.

All three are properties of the experiment, not of the particular noise draw, and the bench
can reproduce them: the estimate theta^ = theta_LS is built into the nominal two-mass axis
(`bench.nominal.two_mass_axis`), the logged experiment is replayed on it `replicas` times in
closed loop (`bench.replay.replay`: the log's q_ref, controller gains, sample period) with the
log's sensors (`bench.sensors.Sensors.from_log`: encoder quantisation and current-loop torque
noise, a fresh seed per replica), and each replica is identified exactly as the log was
(same model, same filter). With theta*_b the replica estimates,

    bias^      = mean_b(theta*_b) - theta^
    theta_bc   = theta^ - bias^                       (the bootstrap bias correction)
    sigma_bc^2 = sigma_c^2 + s*^2 / B                 (s* the replicas' standard deviation)
    sigma_r    = s* sqrt(1 + 1 / B)

where sigma_c is the log's autocorrelation-consistent sigma (`LSResult.cov_corrected`) and
s*^2 / B the variance of the bias estimate (B = replicas). This is the parametric bootstrap bias
correction (B. Efron, R. Tibshirani, "An Introduction to the Bootstrap", 1993, section 10.6).
sigma_bc is the reported sigma; sigma_r, the parametric bootstrap's own standard error (the
spread the experiment shows in simulation), is given beside it: it does not lean on the HAC
covariance, which is conservative for the motor-only model (4x the spread on the prototype),
but with few replicas it is itself uncertain (B = 8: +-25 %).

It assumes that the nominal axis behaves as the robot does at the estimate: the same model
structure (two masses, a torsional spring, MuJoCo's Coulomb friction constraint with its
stick band, `friction_timeconst`: the log's own when it is a jointbench log, else a stated
default) and the same sensors. On the virtual bench that holds by
construction; on a real robot the bias of the structural error the nominal axis does not
have stays (jointbench diagnose looks for it). The log must be replayable (q_ref and the
controller gains, docs/log-format.md and docs/controller.md) and carry its sensor noise in the metadata, or be
given `sensors`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from jointbench.bench.sim.friction import log_substeps, motor_timeconst, timeconst_for_log
from jointbench.bench.sim.nominal import SOLREF_FRICTION
from jointbench.bench.analysis.refine import RefineError, axis_for_log, require_replayable, start_parameters
from jointbench.bench.sim.replay import ReplayError, replay
from jointbench.bench.sim.sensors import Sensors
from jointbench.identification.identify import Identification, NotIdentifiable, identify
from jointbench.identification.log import Log, LogError
from jointbench.identification.parameters import TWO_MASS

DEFAULT_REPLICAS = 8
PARAMETERS = TWO_MASS


class DebiasError(ValueError):
    """The identification cannot be bias-corrected (a rigid model, no sensors, ...)."""


@dataclass(frozen=True)
class DebiasResult:
    """The bias-corrected physical parameters (module docstring). Every dict is keyed by the
    parameters both the log's identification and all successful replicas give."""

    model: str
    estimate: dict[str, float]        # theta_bc = theta_LS - bias
    sigma: dict[str, float]           # sqrt(sigma_c^2 + s*^2 / B)
    bias: dict[str, float]            # mean of the replicas - theta_LS
    spread: dict[str, float]          # s*: the replicas' standard deviation (ddof 1)
    ls: dict[str, float]              # theta_LS
    ls_sigma: dict[str, float]        # sigma_c of the log's identification
    replicas: int                     # successful replicas (B)
    failed: tuple[str, ...] = ()      # reasons of the replicas that failed
    seconds: float = 0.0
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def sigma_replicas(self) -> dict[str, float]:
        """sigma_r = s* sqrt(1 + 1/B): the parametric bootstrap's standard error."""
        return {n: s * math.sqrt(1 + 1 / self.replicas) for n, s in self.spread.items()}

    def to_json(self) -> dict:
        def clean(d: dict[str, float]) -> dict[str, float | None]:
            return {k: (float(v) if math.isfinite(v) else None) for k, v in d.items()}
        return {"replicas": self.replicas, "failed": list(self.failed),
                "seconds": round(self.seconds, 3), "parameters": clean(self.estimate),
                "sigma": clean(self.sigma), "sigma_replicas": clean(self.sigma_replicas),
                "bias": clean(self.bias),
                "replica_std": clean(self.spread), "notes": list(self.notes)}


def replica_seed(seed: int, b: int) -> int:
    """The torque-noise seed of replica b: independent streams of one SeedSequence, so that
    no replica repeats the noise of a bench log whose own seed is a small integer."""
    return int(np.random.SeedSequence([seed, b]).generate_state(1)[0])


def _sensors(log: Log, sensors: Sensors | None) -> Sensors:
    if sensors is not None:
        return sensors
    found = Sensors.from_log(log)
    if found is None:
        raise DebiasError(
            "--debias replays the experiment with the log's sensors, and the log does not give "
            "them: the metadata needs motor_encoder_resolution_rad, link_encoder_resolution_rad "
            "and torque_noise_std (as a jointbench log carries; 0 for an ideal sensor)")
    return found


def debias(log: Log, ident: Identification, *, replicas: int = DEFAULT_REPLICAS, seed: int = 0,
           substeps: int | None = None, sensors: Sensors | None = None,
           friction_timeconst: float | None = None,
           corrections: frozenset[str] | tuple[str, ...] | None = None,
           progress: Callable[[int, int], None] | None = None) -> DebiasResult:
    """Bias-correct `ident`, the identification of `log`, by `replicas` closed-loop replays of
    the experiment on the nominal axis at its estimate (module docstring). `substeps`: MuJoCo
    steps per log sample in the replays (default: the log's own, else 1,
    `bench.sim.friction.log_substeps`); `corrections`: those the replicas' identification
    applies, as `ident`'s did (default all, identification.identify.CORRECTIONS);
    `progress(done, total)` after each replica.

    Raises LogError when the log cannot be replayed, DebiasError when the identification has
    no two-mass estimate or the log no sensor description, ValueError for bad arguments."""
    if replicas < 2:
        raise ValueError(f"--debias needs at least 2 replicas (their spread enters sigma), "
                         f"got {replicas}")
    require_replayable(log)
    try:
        theta, notes = start_parameters(ident)
    except RefineError as err:
        raise DebiasError(str(err).replace("--refine", "--debias")) from None
    sens = _sensors(log, sensors)
    tc, source = timeconst_for_log(log, SOLREF_FRICTION[0], friction_timeconst)
    model, axis = axis_for_log(log, theta, "bias-correction axis", tc)
    notes = [*notes, f"nominal axis: Coulomb friction time constant {1e3 * tc:g} ms "
             f"(solreffriction), {source}"]
    if substeps is None:
        substeps = log_substeps(log, 1)
    start = time.perf_counter()
    rows: list[dict[str, float]] = []
    failed: list[str] = []
    for b in range(replicas):
        try:
            r = replay(model, axis, log, substeps=substeps, sensors=sens,
                       seed=replica_seed(seed, b))
            sim = Log(t=r.t, q_m=r.q_m, tau_m=r.tau_m, q=r.q, q_ref=log.q_ref, meta=log.meta,
                      path=f"replica {b} of {log.path or 'the log'}")
            rows.append(identify(sim, ident.model, ident.settings,
                                 first_mode=ident.first_mode,
                                 **({} if corrections is None else
                                    {"corrections": corrections})).physical)
        except (ReplayError, LogError, NotIdentifiable, np.linalg.LinAlgError) as err:
            failed.append(f"replica {b}: {err}")
        if progress is not None:
            progress(b + 1, replicas)
    if len(rows) < 2:
        raise DebiasError(f"--debias: only {len(rows)} of {replicas} replicas identified "
                          f"({'; '.join(failed[:3])})")
    names = [n for n in PARAMETERS if n in ident.physical
             and math.isfinite(ident.physical[n]) and all(n in row for row in rows)]
    est, sig, bias, spread, ls, ls_sig = {}, {}, {}, {}, {}, {}
    B = len(rows)
    for n in names:
        values = np.array([row[n] for row in rows])
        ls[n] = float(ident.physical[n])
        bias[n] = float(values.mean() - ls[n])
        spread[n] = float(values.std(ddof=1))
        est[n] = ls[n] - bias[n]
        sc = ident.physical_sigma_corrected.get(n, math.nan)
        ls_sig[n] = float(sc)
        sig[n] = float(math.sqrt(sc ** 2 + spread[n] ** 2 / B))
    return DebiasResult(ident.model, est, sig, bias, spread, ls, ls_sig, B, tuple(failed),
                        time.perf_counter() - start, tuple(notes))


def friction_timeconst_of(model, axis) -> float:
    """The solreffriction time constant of an axis's rotor in a compiled MuJoCo model (what
    the bench's logs carry, bench.sim.friction.META_KEY)."""
    return motor_timeconst(model, axis.motor_dof)

