"""Closed-loop output-error refinement of a least-squares identification (DIDIM-style).

`jointbench identify --refine`. The least-squares estimate (`identification.identify`) is the
start of a closed-loop output-error fit in the spirit of DIDIM (M. Gautier, A. Janot,
P.-O. Vandanjon, IEEE Trans. Control Systems Technology 21(2), 2013): each candidate theta is
built into the nominal two-mass MuJoCo axis (`bench.sim.nominal.two_mass_axis`), the logged
experiment is replayed on it in closed loop (`bench.sim.replay.replay`, docs/controller.md),
and

    min_theta  sum_k ((tau_sim[k](theta) - tau_m[k]) / s_tau)^2
             [ + sum_k ((q_sim[k](theta) - q[k]) / s_q)^2   when q is fitted ]

by `scipy.optimize.least_squares` (trust-region reflective, bounds); s_tau, s_q are the RMS
output errors at the start (`cost` is the mean squared weighted residual, 1 per output at
the start). theta_i = start_i + |start_i| x_i (x relative to the LS estimate). Bounds: Jm, K,
JL within [1/5, 5] x start; frictions >= 0; MX, MY free. A friction LS does not give (or gives
negative) starts at 0.1 x its counterpart (FS from FSm, FV from FVm, and back), off its bound.
All nine parameters of eq. (13) are free for both models; the q residual is fitted for a
joint-motor identification only.

`sigma`: sigma^2 (J^T J)^-1 at the optimum (white residuals: optimistic, the output error is
coloured); `sigma_corrected`: the HAC sandwich of `identification.uncertainty.hac_covariance`
on the linearised problem. Only two-mass identifications of revolute axes are refined; a log
without q_ref or the controller gains raises LogError. Measured accuracy, uncertainty and
times: docs/validation.md.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import mujoco
import numpy as np
from scipy import optimize

from jointbench.bench.sim.controller import Gains
from jointbench.bench.analysis.refine_sigma import (  # noqa: F401 - public here too
    widen_on_disagreement, withdraw_when_unmoved)
from jointbench.bench.sim.friction import integrator_for_log, log_substeps, timeconst_for_log
from jointbench.bench.sim.nominal import SOLREF_FRICTION, compile_axis, two_mass_axis
from jointbench.bench.sim.replay import ReplayError, ReplayResult, forward_errors, replay
from jointbench.identification.identify import Identification
from jointbench.identification.log import Log, LogError
from jointbench.identification.output_values import rms
from jointbench.identification.parameters import FRICTIONS, STIFFNESS_AND_INERTIAS, TWO_MASS
from jointbench.identification.uncertainty import hac_covariance
from jointbench.models import Axis

ALL_PARAMETERS = TWO_MASS
FREE = {"joint-motor": ALL_PARAMETERS, "motor-only": ALL_PARAMETERS}
POSITIVE = STIFFNESS_AND_INERTIAS
COUNTERPART = {"FS": "FSm", "FV": "FVm", "FSm": "FS", "FVm": "FV"}
ZERO_START_SHARE = 0.1   # a friction LS does not give starts at 0.1 x its counterpart
BOUND_FACTOR = 5.0       # Jm, K, JL within [start / 5, 5 x start]
DIFF_STEP = 1e-6         # finite-difference step in x (relative to the start values)
XTOL, FTOL, GTOL = 1e-5, 1e-6, 1e-8  # least_squares stops: steps 1e-5 relative, cost 1e-6
DEFAULT_MAX_NFEV = 40    # residual evaluations (each one replay), Jacobian columns not counted


class RefineError(ValueError):
    """The refinement cannot run (no two-mass identification, a start that does not replay)."""


@dataclass(frozen=True)
class RefineResult:
    """What `refine` found. `start` and `parameters` hold every parameter of the nominal axis
    (the fixed ones unchanged); `free` the ones fitted, `sigma` their standard deviations
    (white-residual assumption, module docstring); `cost_before` / `cost_after` the mean
    squared weighted residual (1 per output at the start); `forward_before` / `forward_after`
    `bench.replay.forward_errors`; `replays` every closed-loop replay run (Jacobian columns
    included)."""

    model: str
    free: tuple[str, ...]
    start: dict[str, float]
    parameters: dict[str, float]
    sigma: dict[str, float]
    sigma_corrected: dict[str, float]
    outputs: tuple[str, ...]
    scales: dict[str, float]
    cost_before: float
    cost_after: float
    forward_before: dict
    forward_after: dict
    replays: int
    iterations: int
    wall_s: float
    message: str
    skip: int = 0
    notes: tuple[str, ...] = field(default_factory=tuple)

    def to_json(self) -> dict:
        """The "refined" object of `identify --refine --json`."""
        return {"model": self.model,
                "parameters": {n: {"value": self.parameters[n], "sigma": self.sigma.get(n),
                                   "sigma_corrected": self.sigma_corrected.get(n),
                                   "start": self.start[n]} for n in self.free},
                "fixed": {n: self.parameters[n] for n in self.parameters if n not in self.free},
                "outputs": list(self.outputs), "scales": dict(self.scales),
                "cost": {"before": self.cost_before, "after": self.cost_after},
                "forward": {"before": self.forward_before, "after": self.forward_after},
                "replays": self.replays, "iterations": self.iterations,
                "wall_s": self.wall_s, "skip": self.skip, "message": self.message,
                "uncertainty": {
                    "sigma": "sigma^2 (J^T J)^-1 at the optimum, white residuals assumed",
                    "sigma_corrected": "HAC sandwich on the linearised problem "
                                       "(identification.uncertainty.hac_covariance)"},
                "notes": list(self.notes)}


def require_replayable(log: Log) -> None:
    """LogError unless `log` can be replayed in closed loop: the column q_ref and the
    controller gains kp, kv, ki, tau_max in the metadata (docs/log-format.md and docs/controller.md)."""
    if log.q_ref is None:
        raise LogError("--refine replays the experiment in closed loop: the log has no column "
                       "'q_ref' (the reference the controller tracked)", log.path, column="q_ref")
    Gains.from_log(log)


def start_parameters(ident: Identification, free: tuple[str, ...] = ALL_PARAMETERS
                     ) -> tuple[dict[str, float], list[str]]:
    """The start of the refinement: the physical parameters of `ident`; a friction it does
    not give or gives negative at 0, or when it is in `free` at ZERO_START_SHARE x its
    counterpart (module docstring); MX, MY at 0 when absent; and notes on what was changed.
    RefineError for a rigid identification or a non-positive Jm, K, JL."""
    if ident.model not in FREE:
        raise RefineError(f"--refine applies to the two-mass models (joint-motor, motor-only), "
                          f"not to the {ident.model} model (give --model joint-motor or "
                          "motor-only)")
    if ident.prismatic:
        raise RefineError("--refine: two-mass nominal axes are hinges only (bench/sim/nominal.py)")
    p, notes = ident.physical, []
    start: dict[str, float] = {}
    missing: list[str] = []
    for n in ALL_PARAMETERS:
        v = p.get(n)
        if n in POSITIVE:
            if v is None or not v > 0 or not math.isfinite(v):
                raise RefineError(f"the {ident.model} identification gives {n} = {v}: no "
                                  "two-mass axis to start the refinement from")
            start[n] = float(v)
        elif v is None or not math.isfinite(v):
            start[n] = 0.0
            if n in FRICTIONS:
                missing.append(n)
            else:
                notes.append(f"{n} not identified by least squares: 0")
        elif n in FRICTIONS and v < 0:
            start[n] = 0.0
            missing.append(n)
            notes.append(f"{n} = {v:.4g} < 0 by least squares")
        else:
            start[n] = float(v)
    for n in missing:
        if n in free:
            start[n] = ZERO_START_SHARE * start[COUNTERPART[n]]
            notes.append(f"{n} starts at {ZERO_START_SHARE:g} x {COUNTERPART[n]} = "
                         f"{start[n]:.4g}")
        else:
            notes.append(f"{n} held at 0")
    return start, notes


def _scales(start: dict[str, float], free: tuple[str, ...]) -> np.ndarray:
    out = []
    for n in free:
        s = abs(start[n])
        if s == 0 and n in COUNTERPART:
            s = ZERO_START_SHARE * abs(start[COUNTERPART[n]])
        out.append(s if s > 0 else 1.0)
    return np.array(out)


def _bounds(start: dict[str, float], free: tuple[str, ...],
            scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = np.full(len(free), -np.inf), np.full(len(free), np.inf)
    for i, n in enumerate(free):
        if n in POSITIVE:
            lo[i] = (start[n] / BOUND_FACTOR - start[n]) / scale[i]
            hi[i] = (start[n] * BOUND_FACTOR - start[n]) / scale[i]
        elif n in FRICTIONS:
            lo[i] = -start[n] / scale[i]
    return lo, hi


def axis_for_log(log: Log, theta: dict[str, float], source: str,
                 friction_timeconst: float | None = None) -> tuple[mujoco.MjModel, Axis]:
    """The compiled two-mass axis with parameters `theta` (all of ALL_PARAMETERS) and the
    log's sample period, torque limit, gravity and joint name; its friction time constant
    `friction_timeconst`, else the log's (bench.sim.friction.timeconst_for_log), and the
    log's plant's integrator (bench.sim.friction.integrator_for_log)."""
    if friction_timeconst is None:
        friction_timeconst = timeconst_for_log(log, SOLREF_FRICTION[0])[0]
    spec = two_mass_axis(*(theta[n] for n in ("Jm", "FVm", "FSm", "K", "JL", "FV", "FS",
                                               "MX", "MY")),
                         timestep=log.ts, tau_max=log.meta_float("tau_max"),
                         gravity=log.gravity, name=log.meta.get("joint") or "axis1",
                         friction_timeconst=friction_timeconst,
                         integrator=integrator_for_log(log))
    return compile_axis(spec, source)


def simulate(log: Log, theta: dict[str, float], *, substeps: int | None = None
             ) -> ReplayResult:
    """One closed-loop replay of `log` on the two-mass axis with parameters `theta` (all of
    ALL_PARAMETERS), the log's sample period, torque limit and gravity; `substeps` MuJoCo
    steps a sample (default: the log's own, else 1, `bench.sim.friction.log_substeps`)."""
    model, axis = axis_for_log(log, theta, "refinement candidate")
    return replay(model, axis, log,
                  substeps=log_substeps(log, 1) if substeps is None else substeps)


def _standard_deviations(J: np.ndarray, r: np.ndarray, scale: np.ndarray,
                         free: tuple[str, ...], lengths: list[int]
                         ) -> tuple[dict[str, float], dict[str, float]]:
    """(sigma, sigma_corrected) of the free parameters from the Jacobian J of the weighted
    residual r at the optimum (in x, times `scale` for the parameters' units): the white-noise
    sigma^2 (J^T J)^-1 with sigma^2 = ||r||^2 / (n - p), and the autocorrelation-consistent
    sandwich of `identification.uncertainty.hac_covariance` on the linearised problem (the
    rows of the outputs stacked in `lengths` share their sampling instants); {} for the
    latter when it cannot be computed (a zero Jacobian column)."""
    n, p = J.shape
    s2 = float(r @ r) / max(n - p, 1)
    cov = s2 * np.linalg.pinv(J.T @ J)
    sigma = {name: float(scale[i] * math.sqrt(max(cov[i, i], 0.0)))
             for i, name in enumerate(free)}
    instants = np.concatenate([np.arange(m) for m in lengths]) if len(lengths) > 1 else None
    try:
        hac = hac_covariance(J, r, time=instants)
    except (ValueError, np.linalg.LinAlgError):
        return sigma, {}
    return sigma, {name: float(scale[i] * math.sqrt(max(hac.cov[i, i], 0.0)))
                   for i, name in enumerate(free)}


def refine(log: Log, ident: Identification, *, params: tuple[str, ...] | None = None,
           outputs: tuple[str, ...] | None = None, max_nfev: int | None = None,
           substeps: int | None = None, skip: int = 0, diff_step: float = DIFF_STEP,
           progress: Callable[[str], None] | None = None) -> RefineResult:
    """Refine the two-mass identification `ident` of `log` by closed-loop output error (module
    docstring). `params`: the free parameters (default `FREE[ident.model]`); `outputs`: the
    fitted signals, "tau_m" and, when q is logged, "q" (default: both for a joint-motor
    identification, tau_m alone for motor-only, even when the log has q); `max_nfev`:
    residual evaluations allowed (default DEFAULT_MAX_NFEV; the Jacobian's replays come on
    top, one per free parameter and iteration); `skip`: samples left out at the start;
    `progress`: called with a line after each iteration.

    Raises LogError (no q_ref, no gains), RefineError (rigid identification, unknown
    parameter, the start does not replay), ValueError for bad arguments. Deterministic: the
    same log and identification give the same numbers, bit for bit.
    """
    t_start = time.perf_counter()
    require_replayable(log)
    max_nfev = DEFAULT_MAX_NFEV if max_nfev is None else max_nfev
    if max_nfev < 1:
        raise ValueError(f"--refine-max-nfev must be >= 1, got {max_nfev}")
    if not 0 <= skip < len(log) // 2:
        raise ValueError(f"skip must lie in [0, {len(log) // 2}), got {skip}")
    if ident.model not in FREE:
        start_parameters(ident)  # RefineError naming the model
    free = tuple(params) if params is not None else FREE[ident.model]
    unknown = [n for n in free if n not in ALL_PARAMETERS]
    if unknown or len(set(free)) != len(free) or not free:
        raise RefineError(f"--refine parameters {', '.join(free) or '(none)'}: each must be one "
                          f"of {', '.join(ALL_PARAMETERS)}, once")
    start, notes = start_parameters(ident, free)
    available = ("tau_m", "q") if log.q is not None else ("tau_m",)
    if outputs is None:  # a motor-only identification uses the motor side only
        outputs = available if ident.model == "joint-motor" else ("tau_m",)
    outputs = tuple(outputs)
    if not outputs or any(o not in available for o in outputs):
        raise ValueError(f"outputs {outputs}: choose among {', '.join(available)}")

    scale = _scales(start, free)
    lo, hi = _bounds(start, free, scale)
    k = slice(skip, None)
    measured = {"tau_m": log.tau_m[k], "q": None if log.q is None else log.q[k]}
    count = {"replays": 0}

    def theta_of(x: np.ndarray) -> dict[str, float]:
        theta = dict(start)
        for n, v in zip(free, start_values + scale * x):
            theta[n] = max(float(v), 0.0) if n in FRICTIONS else float(v)  # 0: -1e-17 at a bound
        return theta

    start_values = np.array([start[n] for n in free])

    def run(x: np.ndarray) -> ReplayResult:
        count["replays"] += 1
        return simulate(log, theta_of(x), substeps=substeps)

    def signals(r: ReplayResult) -> dict[str, np.ndarray]:
        return {"tau_m": r.tau_m[k], "q": None if r.q is None else r.q[k]}

    try:
        first = run(np.zeros(len(free)))
    except (ReplayError, ValueError) as err:
        raise RefineError(f"{log.path or 'the log'}: the least-squares start does not replay: "
                          f"{err}") from None
    sim0 = signals(first)
    scales = {o: rms(sim0[o] - measured[o]) for o in outputs}
    for o, e in scales.items():
        if not (e > 0 and math.isfinite(e)):
            raise RefineError(f"the replay's {o} equals the measurement (RMS error {e}): nothing "
                              "to refine")

    def residual_of(r: ReplayResult) -> np.ndarray:
        sim = signals(r)
        return np.concatenate([(sim[o] - measured[o]) / scales[o] for o in outputs])

    n_rows = sum(len(measured[o]) for o in outputs)
    penalty = np.full(n_rows, 1e3)
    cache: dict[bytes, tuple[np.ndarray, ReplayResult | None]] = {}

    def fun(x: np.ndarray) -> np.ndarray:
        """The weighted residual at x; the last one is kept (the Jacobian at an accepted step
        and the final forward errors reuse it)."""
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            try:
                r = run(x)
                cache[key] = (residual_of(r), r)
            except ReplayError:
                cache[key] = (penalty, None)  # a diverging candidate: the trust region shrinks
        return cache[key][0]

    iters = {"n": 0}

    def jac(x: np.ndarray) -> np.ndarray:
        """Forward differences of step `diff_step` in x (a relative change of the parameter),
        away from a bound it would cross; the residual at x comes from the cache."""
        f0 = fun(x)
        J = np.empty((n_rows, len(x)))
        for i in range(len(x)):
            h = diff_step * max(1.0, abs(x[i]))
            if x[i] + h > hi[i]:
                h = -h
            xi = x.copy()
            xi[i] += h
            try:
                fi = residual_of(run(xi))
            except ReplayError as err:
                raise RefineError(f"the replay diverged next to the current estimate ({free[i]} "
                                  f"moved by {h:.1e} relative): {err}") from None
            J[:, i] = (fi - f0) / h
        iters["n"] += 1
        if progress is not None:
            theta = theta_of(x)
            progress(f"refine: iteration {iters['n']}, cost {float(f0 @ f0) / n_rows:.6g}, "
                     f"{count['replays']} replays, "
                     + ", ".join(f"{n} {theta[n]:.6g}" for n in free))
        return J

    r0 = residual_of(first)
    cache[np.zeros(len(free)).tobytes()] = (r0, first)
    sol = optimize.least_squares(fun, np.zeros(len(free)), jac=jac, bounds=(lo, hi),
                                 method="trf", x_scale=1.0, max_nfev=max_nfev,
                                 xtol=XTOL, ftol=FTOL, gtol=GTOL)
    final = cache.get(sol.x.tobytes(), (None, None))[1]
    if final is None:
        final = run(sol.x)
    theta = theta_of(sol.x)
    sigma, sigma_c = _standard_deviations(sol.jac, sol.fun, scale, free,
                                          [len(measured[o]) for o in outputs])
    sigma, sigma_c, widened = widen_on_disagreement(theta, start, sigma, sigma_c,
                                                    ident.physical_sigma_corrected)
    notes += widened
    sigma, sigma_c, withdrawn = withdraw_when_unmoved(theta, start, sigma, sigma_c,
                                                      ident.physical_sigma_corrected)
    notes += withdrawn
    tc, source = timeconst_for_log(log, SOLREF_FRICTION[0])
    notes.append(f"nominal axis: Coulomb friction time constant {1e3 * tc:g} ms "
                 f"(solreffriction), {source}")
    return RefineResult(
        model=ident.model, free=free, start=start, parameters=theta, sigma=sigma,
        sigma_corrected=sigma_c, outputs=outputs, scales=scales,
        cost_before=float(r0 @ r0) / n_rows, cost_after=float(sol.fun @ sol.fun) / n_rows,
        forward_before=forward_errors(log, first, skip),
        forward_after=forward_errors(log, final, skip),
        replays=count["replays"], iterations=iters["n"],
        wall_s=time.perf_counter() - t_start, message=str(sol.message), skip=skip,
        notes=tuple(notes))

