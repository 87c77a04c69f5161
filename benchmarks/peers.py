"""Peer methods on the same logs, side by side (README "Benchmarks against peer methods").

    .venv/bin/python benchmarks/peers.py [--logs 3] [--duration 10] [--max-iters 20]

On `--logs` virtual experiments of the paper's prototype (`run_experiment("prototype",
duration, seed)`, default sensors, seeds 101, 102, ...), each method identifies K, Jm and JL:

1. this project's least squares (`identify`), joint-motor model (eq. 13) with every default
   correction, as the paper's chain alone (`--plain`: eqs. 26-29, 22, 13, least squares) and
   as the paper's chain with the held torque's correction only (`--corrections zoh`, the one
   that moves K, Jm and JL on these logs: docs/method.md), and motor-only model (eqs. 18-20,
   corrected, NLS inversion);
2. output-error identification with MuJoCo's own `mujoco.sysid` on the same MJCF axis
   (models/prototype_axis.xml plus three sensors: both encoders and the actuator force).
   Open-loop replay of the logged torque drifts away (the rigid-body mode is free and the
   link is gravity-unstable about q0), so the replay is closed-loop: `custom_rollout`
   re-runs the log's own discrete controller (bench.controller.PIController, the gains and
   reference of the log, docs/controller.md) on every candidate model. sysid's own rollout
   is not used, which also steps around its current pitfalls: it maps `range(model.nu)` to
   actuators (wrong for multi-input actuators) and labels its rollout sensor rows one step
   late (row k is computed at t_k but stamped t_k+1); here row k is the state at t_k, the
   sample time of the log. Free parameters: K, Jm, JL, FVm, FV, FSm, FS (the joint-motor
   model's physical set without the first moments, which stay at the model's), started at
   a deliberately wrong nominal model (START factors below, -20 % to +30 %), bounds
   [0.2, 5] x start, sysid.optimize(optimizer="mujoco");
3. a frequency-domain fit of the two-mass model (eqs. 5-6 linearised, python-control
   `two_mass_tf`) to the measured frequency responses q_m / tau_m and q / tau_m (closed-loop
   indirect estimate from q_ref, scipy.signal.csd over the whole log, Hann window), least
   squares on the complex log ratio (log magnitude and phase) over 0.3-10 Hz, with a free
   gravity stiffness G, same start (the spectral alternative the paper cites, its ref. [3]).

Printed: per method the wall time per log (the identification itself, the logs being
simulated once beforehand; best of 5 calls for the methods that take milliseconds, one call
for the output-error peer) and the mean absolute K, Jm, JL errors against truth; the ratio
of our least squares to the output-error peer (target: >= 500x faster, with a K error no larger
than the peer's); then identification time per 60 s log (best of 5) and virtual experiments per
second on all local cores (a campaign of 60 s experiments, both identification models).
Nothing is asserted: timings depend on the machine and its load.
"""

from __future__ import annotations

import argparse
import io
import math
import os
import platform
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.identify import identify
from jointbench.identification.log import Log

PARAMS = ("K", "Jm", "JL")
# the wrong nominal model both iterative peers start from (factor x truth)
START = {"K": 1.3, "Jm": 0.8, "JL": 1.2, "FVm": 1.25, "FV": 0.8, "FSm": 1.2, "FS": 0.8}


@dataclass(frozen=True)
class PeerResult:
    method: str
    wall_s: float
    estimates: dict[str, float]
    errors_pct: dict[str, float]
    note: str = ""
    settled_s: float = math.nan  # iterative peers: time until the objective settled


def errors_pct(est: dict[str, float], truth: dict[str, float]) -> dict[str, float]:
    return {p: 100.0 * (est[p] - truth[p]) / abs(truth[p]) for p in PARAMS}


# ---------------------------------------------------------------------------------------------
# 1. this project's least squares


def best_of(fn, repeats: int):
    """(best wall time over `repeats` calls, last result)."""
    best, out = math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def ours(log: Log, model: str, repeats: int = 5,
         corrections: tuple[str, ...] | None = None) -> PeerResult:
    """`identify` with every default correction (None), or the paper's chain with only the
    named `corrections` (`()`: the chain alone, `identify --plain`)."""
    kwargs = {} if corrections is None else {"corrections": corrections}
    wall, ident = best_of(lambda: identify(log, model, **kwargs), repeats)
    est = {p: ident.physical[p] for p in PARAMS}
    name = f"least squares, {model}"
    if corrections is not None:
        name += (f", paper chain + {'+'.join(corrections)}" if corrections
                 else ", paper chain (--plain)")
    return PeerResult(name, wall, est, errors_pct(est, log.truth()))


# ---------------------------------------------------------------------------------------------
# 2. mujoco.sysid, output error, closed loop


def sysid_spec():
    """models/prototype_axis.xml with sensors for both encoders and the motor torque."""
    import mujoco

    from jointbench.models import model_path

    spec = mujoco.MjSpec.from_file(str(model_path("prototype")))
    spec.add_sensor(name="q_m", type=mujoco.mjtSensor.mjSENS_JOINTPOS, objname="axis1_motor",
                    objtype=mujoco.mjtObj.mjOBJ_JOINT)
    spec.add_sensor(name="q", type=mujoco.mjtSensor.mjSENS_JOINTPOS, objname="axis1",
                    objtype=mujoco.mjtObj.mjOBJ_JOINT)
    spec.add_sensor(name="tau_m", type=mujoco.mjtSensor.mjSENS_ACTUATORFRC,
                    objname="axis1_motor", objtype=mujoco.mjtObj.mjOBJ_ACTUATOR)
    return spec


def sysid_parameters(truth: dict[str, float], spec):
    """sysid Parameters for K, Jm, JL, FVm, FV, FSm, FS with MjSpec modifiers."""
    from mujoco import sysid

    link = spec.body("axis1_link")
    m, c = float(link.mass), np.array(link.ipos, dtype=float)
    steiner = m * (c[0] ** 2 + c[2] ** 2)  # JL = Iyy(com) + m |c|^2 about the hinge (y)

    def set_k(s, p):
        s.tendon("axis1_spring").stiffness = [float(p.value[0]), 0.0, 0.0]

    def set_jl(s, p):
        # only Iyy acts about the hinge; Ixx, Izz follow so that the triangle inequality
        # (A + B >= C) MuJoCo checks still holds
        iyy = float(p.value[0]) - steiner
        inertia = np.array(s.body("axis1_link").inertia, dtype=float)
        s.body("axis1_link").inertia = [max(inertia[0], iyy), iyy, max(inertia[2], iyy)]

    def set_joint(joint, attr):
        def modifier(s, p):
            if attr == "damping":
                s.joint(joint).damping = [float(p.value[0]), 0.0, 0.0]
            else:
                setattr(s.joint(joint), attr, float(p.value[0]))
        return modifier

    modifiers = {"K": set_k, "Jm": set_joint("axis1_motor", "armature"), "JL": set_jl,
                 "FVm": set_joint("axis1_motor", "damping"), "FV": set_joint("axis1", "damping"),
                 "FSm": set_joint("axis1_motor", "frictionloss"),
                 "FS": set_joint("axis1", "frictionloss")}
    params = sysid.ParameterDict()
    for name, f in START.items():
        start = f * truth[name]
        lo = 0.2 * start if name != "JL" else max(0.2 * start, 1.01 * steiner)
        params.add(sysid.Parameter(name, nominal=start, min_value=lo, max_value=5.0 * start,
                                   modifier=modifiers[name]))
    return params


def closed_loop_rollout(log: Log):
    """A sysid custom_rollout: every candidate model tracks the log's q_ref under the log's
    own controller (docs/controller.md); returns trajectories whose row k is the sample at
    t_k (q_m, q, tau_m). The controller reads the simulated q_m unquantised: encoder rounding
    would make the residual piecewise constant in the parameters, and the finite-difference
    Jacobian zero (the optimiser then stops at its start)."""
    import mujoco
    from mujoco import sysid
    from mujoco.sysid._src.trajectory import SystemTrajectory

    from jointbench.bench.sim.controller import Gains, PIController

    gains = Gains.from_log(log)
    T = log.ts
    q_ref = log.q_ref.tolist()
    n = len(log)
    times = log.t

    def rollout(models, datas, control_signal, initial_states, param_dicts,
                rollout_signal_mapping, rollout_state_mapping, ctrl_mapping):
        out = []
        spec_state = mujoco.mjtState.mjSTATE_FULLPHYSICS
        for model, x0 in zip(models, initial_states):
            d = mujoco.MjData(model)
            mujoco.mj_setState(model, d, x0, spec_state)
            mujoco.mj_forward(model, d)
            im = model.jnt_qposadr[model.joint("axis1_motor").id]
            il = model.jnt_qposadr[model.joint("axis1").id]
            ctrl = PIController(gains, T, float(log.tau_m[0]))
            sens = np.empty((n, 3))
            qs = np.empty((n, model.nq))
            vs = np.empty((n, model.nv))
            qpos, qvel, act, step = d.qpos, d.qvel, d.ctrl, mujoco.mj_step
            for k in range(n):
                qm = qpos[im]
                u = ctrl.step(qm, q_ref[k])
                sens[k, 0], sens[k, 1], sens[k, 2] = qm, qpos[il], u
                qs[k], vs[k] = qpos, qvel
                act[0] = u
                step(model, d)
            # rows of mjSTATE_FULLPHYSICS at t_k: time, qpos, qvel (the rest, unused, zero)
            state = np.zeros((n, mujoco.mj_stateSize(model, spec_state)))
            state[:, 0] = times
            state[:, 1:1 + model.nq] = qs
            state[:, 1 + model.nq:1 + model.nq + model.nv] = vs
            out.append(SystemTrajectory(
                model=model,
                control=sysid.TimeSeries(times, sens[:, 2:3], signal_mapping=ctrl_mapping),
                sensordata=sysid.TimeSeries(times, sens, signal_mapping=rollout_signal_mapping),
                initial_state=x0,
                state=sysid.TimeSeries(times, state, signal_mapping=rollout_state_mapping)))
        return out

    return rollout


def sysid_peer(log: Log, max_iters: int) -> PeerResult:
    import mujoco
    from mujoco import sysid

    if not hasattr(sysid, "optimize"):  # mujoco/sysid/__init__.py swallows the ImportError
        raise RuntimeError("mujoco.sysid's optional dependencies are missing: pip install "
                           f"'mujoco[sysid]=={mujoco.__version__}' (or make bench-peers)")

    t0 = time.perf_counter()
    truth = log.truth()
    spec = sysid_spec()
    model = spec.compile()
    im = model.jnt_qposadr[model.joint("axis1_motor").id]
    il = model.jnt_qposadr[model.joint("axis1").id]
    qpos = np.zeros(model.nq)
    qpos[im], qpos[il] = log.q_m[0], log.q[0]
    x0 = sysid.create_initial_state(model, qpos)
    measured = sysid.TimeSeries.from_names(log.t, np.column_stack([log.q_m, log.q, log.tau_m]),
                                           model)
    control = sysid.TimeSeries(log.t, log.tau_m[:, None])
    seq = sysid.ModelSequences("prototype", spec, "chirp", x0, control, measured)
    params = sysid_parameters(truth, spec)
    residual_fn = sysid.build_residual_fn(models_sequences=[seq],
                                          custom_rollout=closed_loop_rollout(log))
    trace = io.StringIO()  # mujoco.minimize's per-iteration printout
    stamps: list[tuple[float, float]] = []  # (time, objective) at every iteration

    def stamp(iterations) -> None:
        stamps.append((time.perf_counter(), float(iterations[-1].objective)))

    opt, res = sysid.optimize(params, residual_fn, optimizer="mujoco", verbose=False,
                              max_iters=max_iters, x_scale="jac", output=trace,
                              iter_callback=stamp)
    wall = time.perf_counter() - t0
    est = {p: float(opt[p].value[0]) for p in START}
    objective = np.array([o for _, o in stamps])
    settled = int(np.argmax(objective <= 1.001 * objective.min())) if stamps else -1
    settled_s = stamps[settled][0] - t0 if stamps else math.nan
    ended = [ln for ln in trace.getvalue().splitlines() if ln.startswith("Terminated")]
    return PeerResult("mujoco.sysid output error (closed loop)", wall, est,
                      errors_pct(est, truth), settled_s=settled_s,
                      note=(ended[0].split(". y:")[0] if ended else "")
                      + f"; objective within 0.1 % of its final value from iteration "
                        f"{settled}, after {settled_s:.2f} s")


# ---------------------------------------------------------------------------------------------
# 3. frequency-domain fit of the two-mass model


def frf_peer(log: Log, fmin: float = 0.3, fmax: float = 10.0, repeats: int = 5) -> PeerResult:
    wall, result = best_of(lambda: _frf_fit(log, fmin, fmax), repeats)
    return PeerResult(result.method, wall, result.estimates, result.errors_pct, result.note)


def _frf_fit(log: Log, fmin: float, fmax: float) -> PeerResult:
    from scipy import optimize

    import control

    from jointbench.identification.frequency import measured_frf, two_mass_tf

    t0 = time.perf_counter()
    truth = log.truth()
    # One chirp, one window: the empirical transfer function estimate over the whole log
    # (Hann window, no averaging). Welch averaging over shorter segments cuts the sweep into
    # pieces that each see part of the band: on 10 s logs it moved K by 1 to 17 %.
    nperseg = len(log)
    hm = measured_frf(log, nperseg=nperseg, output="q_m")
    hl = measured_frf(log, nperseg=nperseg, output="q")
    band = (hm.f_hz >= fmin) & (hm.f_hz <= fmax)
    f = hm.f_hz[band]
    meas = np.concatenate([hm.H[band], hl.H[band]])
    names = ("Jm", "K", "JL", "FVm", "FV")
    start = np.array([START[n] * truth[n] for n in names] + [0.0])
    s = 2j * np.pi * f

    def model(p):
        Jm, K, JL, FVm, FV, G = p
        link = JL * s ** 2 + FV * s + K + G
        den = (Jm * s ** 2 + FVm * s + K) * link - K ** 2
        return np.concatenate([link / den, K / den])

    def residual(z):
        p = np.concatenate([start[:5] * np.exp(z[:5]), [z[5] * 1e3]])
        r = np.log(model(p) / meas)
        return np.concatenate([r.real, r.imag])

    sol = optimize.least_squares(residual, np.zeros(6), method="trf", x_scale="jac")
    p = np.concatenate([start[:5] * np.exp(sol.x[:5]), [sol.x[5] * 1e3]])
    wall = time.perf_counter() - t0
    est = dict(zip(names, p[:5]))
    # the fitted model's first mode: its complex pole pair (python-control)
    poles = control.poles(two_mass_tf(*p[:5], G=p[5]))
    f1 = float(np.max(np.abs(poles[np.abs(poles.imag) > 0]), initial=0.0)) / (2 * np.pi)
    return PeerResult("two-mass FRF fit (scipy.signal + control)", wall, est,
                      errors_pct(est, truth),
                      note=f"f1 {f1:.3f} Hz (truth {truth['f1_hz']:.3f}), gravity stiffness "
                           f"G = {p[5]:.0f} N m/rad, {len(f)} frequencies, {sol.nfev} evaluations")


# ---------------------------------------------------------------------------------------------
# Speed figures


def identification_time(log: Log) -> dict[str, float]:
    out = {}
    for model in ("joint-motor", "motor-only"):
        best = math.inf
        for _ in range(5):
            t0 = time.perf_counter()
            identify(log, model)
            best = min(best, time.perf_counter() - t0)
        out[model] = best
    return out


def experiments_per_second(runs: int, workers: int | None) -> tuple[float, float, str]:
    """A campaign of `runs` 60 s prototype experiments (both identification models) on
    LocalExecutor(workers): (runs per second, mean simulation s per run, engine)."""
    from jointbench.bench.campaign.run import run_campaign
    from jointbench.bench.campaign.settings import RunSettings
    from jointbench.bench.campaign.spec import CampaignSpec
    from jointbench.bench.campaign.executors import LocalExecutor

    spec = CampaignSpec(base=RunSettings(duration=60.0), runs=runs, seed=99)
    with tempfile.TemporaryDirectory() as tmp, LocalExecutor(workers) as ex:
        warm = list(ex.map_unordered(abs, range(ex.workers)))  # start the processes
        assert len(warm) == ex.workers
        result = run_campaign(spec, Path(tmp) / "speed.csv", ex)
        return result.new / result.wall_s, float(np.mean(result.sim_s)), ex.description


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--logs", type=int, default=3, help="logs (seeds 101, 102, ...)")
    ap.add_argument("--duration", type=float, default=10.0, help="log length in s (default 10)")
    ap.add_argument("--max-iters", type=int, default=20, help="sysid iterations (default 20)")
    ap.add_argument("--speed-runs", type=int, default=0,
                    help="runs of the all-cores throughput campaign (default 4 x cores)")
    args = ap.parse_args()

    import mujoco

    print("jointbench peers benchmark")
    print(f"  machine   {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, MuJoCo {mujoco.__version__}")
    print(f"  logs      {args.logs} x {args.duration:g} s, prototype, default sensors, "
          f"seeds 101..{100 + args.logs}")
    print(f"  start     iterative peers start at {', '.join(f'{k} x{v}' for k, v in START.items())}")
    print()
    logs = [run_experiment("prototype", duration=args.duration, seed=100 + i).log
            for i in range(1, args.logs + 1)]
    methods = {"ls-jm": [], "ls-jm-plain": [], "ls-jm-zoh": [], "ls-mo": [], "sysid": [],
               "frf": []}
    for i, log in enumerate(logs):
        runs = [("ls-jm", ours(log, "joint-motor")),
                ("ls-jm-plain", ours(log, "joint-motor", corrections=())),
                ("ls-jm-zoh", ours(log, "joint-motor", corrections=("zoh",))),
                ("ls-mo", ours(log, "motor-only")),
                ("frf", frf_peer(log))]
        try:
            runs.append(("sysid", sysid_peer(log, args.max_iters)))
        except Exception as err:  # noqa: BLE001 - report why the peer did not run
            print(f"  log {i + 1}: mujoco.sysid failed: {type(err).__name__}: {err}")
        for key, r in runs:
            methods[key].append(r)
            print(f"  log {i + 1} seed {101 + i}: {r.method:<52} {r.wall_s:9.4f} s  "
                  + "  ".join(f"{p} {r.errors_pct[p]:+7.3f} %" for p in PARAMS)
                  + (f"  ({r.note})" if r.note else ""))
    print()
    print(f"Mean over {args.logs} logs of {args.duration:g} s: wall time per log and mean "
          "absolute error against truth")
    head = (f"| {'method':<52} | {'wall time / log':>15} | "
            + " | ".join(f"{p + ' error':>9}" for p in PARAMS) + " |")
    print(head)
    print("|" + "|".join("-" * len(c) for c in head.split("|")[1:-1]) + "|")
    summary = {}
    for key, rs in methods.items():
        if not rs:
            continue
        wall = float(np.mean([r.wall_s for r in rs]))
        err = {p: float(np.mean([abs(r.errors_pct[p]) for r in rs])) for p in PARAMS}
        summary[key] = (wall, err)
        wall_txt = f"{1e3 * wall:.1f} ms" if wall < 1 else f"{wall:.2f} s"
        print(f"| {rs[0].method:<52} | {wall_txt:>15} | "
              + " | ".join(f"{err[p]:>7.3f} %" for p in PARAMS) + " |")
    if "sysid" in summary:
        print()
        for key in ("ls-jm", "ls-jm-plain", "ls-jm-zoh", "ls-mo"):
            speed = summary["sysid"][0] / summary[key][0]
            kratio = summary[key][1]["K"] / summary["sysid"][1]["K"]
            settled = float(np.mean([r.settled_s for r in methods["sysid"]]))
            print(f"{methods[key][0].method}: {speed:.0f}x faster than the output-error peer "
                  f"({settled / summary[key][0]:.0f}x counting only until the peer's "
                  f"objective settled), K error {kratio:.2f}x the peer's "
                  "(targets: >= 500x, <= 1x)")
    print()
    log60 = run_experiment("prototype", duration=60.0, seed=1).log
    for model, wall in identification_time(log60).items():
        print(f"identification time per 60 s log, {model}: {1e3 * wall:.1f} ms (best of 5) "
              f"-> {1 / wall:.0f} logs/s on one core")
    runs = args.speed_runs or 4 * (os.cpu_count() or 1)
    rate, sim, engine = experiments_per_second(runs, None)
    print(f"virtual experiments per second on all cores: {rate:.2f} (60 s prototype "
          f"experiments identified with both models, {runs} runs on {engine}; "
          f"{sim:.3f} s simulation per run)")


if __name__ == "__main__":
    main()
