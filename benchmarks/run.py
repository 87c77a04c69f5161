"""jointbench speed benchmark (`make bench`).

What is measured (wall time with time.perf_counter, best of N repeats, in this process):

1. One 60 s closed-loop chirp experiment on the prototype (single axis, `axis1`), as
   `run_experiment("prototype", duration=60.0)`: real-time factor = simulated seconds per
   wall second (best of 3). README target: >= 150x.
2. Each of the six arm6 joints, 60 s each: real-time factor (best of 2). Target >= 40x.
3. Baselines on the same reduced prototype model (`build_experiment_model("prototype")`):
   (a) a bare Python loop of 21053 `mujoco.mj_step` calls with a trivial P-law
       ctrl = -1000 (q_m - q_m0) and no logging, sensors or noise: its real-time factor and
       the ratio full experiment / bare loop (the cost of everything the experiment adds);
   (b) `mujoco.rollout`, open loop, the same number of steps with zero control, when the
       module works in the installed MuJoCo (otherwise the reason it is skipped).
4. Identification time per 60 s log (`identify(log, "joint-motor")` and
   `identify(log, "motor-only")`), in ms (best of 5), and logs identified per second.
5. Start-up of the command line, in fresh processes (best of 5, resp. 3): `jointbench --help`
   against a bare `python -c pass` (target: under 0.5 s), and `jointbench simulate
   --duration 60` against the simulation's own time, the in-process experiment of [1]
   (target: under 1.5x), and the floor under it: a fresh `python -c "import numpy, mujoco"`
   (MuJoCo's OpenGL probe off, as the CLI sets it) added to the experiment's time.
6. `jointbench survey --model arm6 --seed 1 --workers 2` (six 60 s experiments, each
   identified), in a fresh process, once: its wall time (issue 18's target: under 30 s on 2
   cores).

The script only prints figures and ratios to the targets. No wall-clock bound is asserted
anywhere (here or in the tests): timings depend on the machine and its load.
"""

from __future__ import annotations

import datetime
import os
import platform
import subprocess
import sys
import tempfile
import time

import mujoco
import numpy as np

from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.sim.experiment import SAMPLE_RATE_HZ, run_experiment
from jointbench.identification.identify import identify

DURATION = 60.0
N_TICKS = int(round(DURATION * SAMPLE_RATE_HZ)) + 1  # 21053, as in run_experiment
PROTO_TARGET = 150.0
ARM6_TARGET = 40.0
ARM6_JOINTS = [f"axis{i}" for i in range(1, 7)]


def best_of(fn, repeats: int):
    """Run fn() `repeats` times; return (best wall time [s], last result)."""
    best, result = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def _cpu_model() -> str:
    """The CPU's model name (Linux /proc/cpuinfo), '' when unknown."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return ""


def header() -> None:
    print("jointbench benchmark")
    print(f"  date        {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}")
    print(f"  processor   {_cpu_model() or platform.processor() or '?'} / {platform.machine()}")
    print(f"  cpu_count   {os.cpu_count()}")
    print(f"  python      {platform.python_version()} ({sys.executable})")
    print(f"  mujoco      {mujoco.__version__}")
    print(f"  60 s log    {N_TICKS} ticks at {SAMPLE_RATE_HZ} Hz")
    print()


def bench_prototype() -> tuple[float, object]:
    wall, res = best_of(lambda: run_experiment("prototype", duration=DURATION, seed=0), 3)
    rtf = DURATION / wall
    print(f"[1] prototype axis1, 60 s experiment: {wall:.3f} s wall (best of 3) -> "
          f"{rtf:.1f}x real time ({rtf / PROTO_TARGET:.2f} of the {PROTO_TARGET:.0f}x target)")
    return rtf, res


def bench_arm6() -> dict[str, float]:
    out = {}
    for joint in ARM6_JOINTS:
        wall, _ = best_of(lambda: run_experiment("arm6", joint, duration=DURATION, seed=0), 2)
        rtf = DURATION / wall
        out[joint] = rtf
        print(f"[2] arm6 {joint}, 60 s experiment: {wall:.3f} s wall (best of 2) -> "
              f"{rtf:.1f}x real time ({rtf / ARM6_TARGET:.2f} of the {ARM6_TARGET:.0f}x target)")
    return out


def bench_bare_loop(exp) -> float:
    m = exp.model
    ax = exp.axis
    im, act = ax.motor_qpos, ax.actuator
    q0 = float(exp.qpos_init[im])

    def loop() -> None:
        d = mujoco.MjData(m)
        d.qpos[:] = exp.qpos_init
        mujoco.mj_forward(m, d)
        qpos, ctrl, step = d.qpos, d.ctrl, mujoco.mj_step
        for _ in range(N_TICKS):
            ctrl[act] = -1000.0 * (qpos[im] - q0)
            step(m, d)

    wall, _ = best_of(loop, 3)
    sim = N_TICKS * m.opt.timestep
    rtf = sim / wall
    print(f"[3a] bare mj_step loop, prototype reduced model, {N_TICKS} steps: {wall:.3f} s wall "
          f"(best of 3) -> {rtf:.1f}x real time")
    return rtf


def bench_rollout(exp) -> tuple[float | None, str]:
    try:
        import mujoco.rollout as mj_rollout
    except Exception as err:  # noqa: BLE001 - report any import failure
        reason = f"import mujoco.rollout failed: {type(err).__name__}: {err}"
        print(f"[3b] mujoco.rollout: skipped ({reason})")
        return None, reason
    m = exp.model
    try:
        d = mujoco.MjData(m)
        d.qpos[:] = exp.qpos_init
        mujoco.mj_forward(m, d)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state0 = np.empty(mujoco.mj_stateSize(m, spec))
        mujoco.mj_getState(m, d, state0, spec)
        control = np.zeros((1, N_TICKS, m.nu))

        def roll():
            return mj_rollout.rollout(m, mujoco.MjData(m), state0[None, :], control)

        wall, (states, _) = best_of(roll, 3)
        if states.shape[:2] != (1, N_TICKS):
            raise RuntimeError(f"unexpected state shape {states.shape}")
    except Exception as err:  # noqa: BLE001 - report any runtime failure
        reason = f"mujoco.rollout.rollout failed: {type(err).__name__}: {err}"
        print(f"[3b] mujoco.rollout: skipped ({reason})")
        return None, reason
    rtf = N_TICKS * m.opt.timestep / wall
    print(f"[3b] mujoco.rollout, open loop, zero control, {N_TICKS} steps: {wall:.3f} s wall "
          f"(best of 3) -> {rtf:.1f}x real time")
    return rtf, ""


def bench_identify(log) -> dict[str, float]:
    out = {}
    for name in ("joint-motor", "motor-only"):
        wall, _ = best_of(lambda: identify(log, name), 5)
        out[name] = wall
        print(f"[4] identify(log, {name!r}) on a 60 s log: {1e3 * wall:.1f} ms (best of 5) -> "
              f"{1.0 / wall:.1f} logs/s")
    return out


HELP_TARGET_S = 0.5
SIMULATE_TARGET = 1.5


def _command_wall(argv: list[str], repeats: int, extra_env: dict[str, str] | None = None) -> float:
    """Best wall time [s] of `python argv` in a fresh process (output discarded), as a user
    runs it: with Python's bytecode cache (PYTHONDONTWRITEBYTECODE, set on some CI machines,
    would charge every start with compiling the package's sources again, about 0.08 s)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env.update(extra_env or {})

    def run() -> None:
        subprocess.run([sys.executable, *argv], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, env=env)
    run()   # writes the bytecode cache
    return best_of(run, repeats)[0]


def bench_startup(sim_wall: float) -> dict[str, float]:
    bare = _command_wall(["-c", "pass"], 5)
    helps = _command_wall(["-m", "jointbench.bench.cli", "--help"], 5)
    print(f"[5] `jointbench --help`: {helps:.3f} s wall (best of 5) against {bare:.3f} s for "
          f"`python -c pass` ({helps / bare:.1f}x; {helps - bare:.3f} s of jointbench; "
          f"target under {HELP_TARGET_S} s)")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "s.csv")
        sim = _command_wall(["-m", "jointbench.bench.cli", "simulate", "--duration", "60",
                             "--quiet", "--out", out], 3)
    print(f"[5] `jointbench simulate --duration 60`: {sim:.3f} s wall (best of 3) against "
          f"{sim_wall:.3f} s for the experiment in-process [1] ({sim / sim_wall:.2f}x; target "
          f"under {SIMULATE_TARGET}x)")
    # The least any command that simulates with these libraries can take: the interpreter and
    # the imports of numpy and MuJoCo (with MuJoCo's OpenGL probe off, as the CLI sets it).
    floor = _command_wall(["-c", "import numpy, mujoco"], 5, {"MUJOCO_GL": "disable"})
    print(f"[5] `python -c 'import numpy, mujoco'`: {floor:.3f} s wall (best of 5): a simulating "
          f"command cannot go under ({floor:.3f} + {sim_wall:.3f}) / {sim_wall:.3f} = "
          f"{(floor + sim_wall) / sim_wall:.2f}x; jointbench's own share of the command: "
          f"{sim - floor - sim_wall:.3f} s")
    return {"bare": bare, "help": helps, "simulate": sim, "simulate_ratio": sim / sim_wall,
            "floor": floor, "floor_ratio": (floor + sim_wall) / sim_wall}


SURVEY_TARGET_S = 30.0


def bench_survey() -> float:
    with tempfile.TemporaryDirectory() as tmp:
        wall = _command_wall(["-m", "jointbench.bench.cli", "survey", "--model", "arm6",
                              "--seed", "1", "--workers", "2", "--quiet", "--out",
                              os.path.join(tmp, "survey")], 1)
    print(f"[6] `jointbench survey --model arm6 --seed 1 --workers 2`: {wall:.1f} s wall "
          f"(six 60 s experiments and identifications; target under {SURVEY_TARGET_S:g} s)")
    return wall


def main() -> None:
    header()
    t_start = time.perf_counter()
    proto_rtf, proto_res = bench_prototype()
    startup = bench_startup(DURATION / proto_rtf)
    arm6 = bench_arm6()
    exp = build_experiment_model("prototype")
    bare_rtf = bench_bare_loop(exp)
    ratio = proto_rtf / bare_rtf
    print(f"[3a] full experiment / bare loop (real-time factors): {ratio:.2f} "
          f"(experiment wall time = {1 / ratio:.2f}x the bare loop's)")
    roll_rtf, roll_reason = bench_rollout(exp)
    if roll_rtf is not None:
        print(f"[3b] full experiment / rollout (real-time factors): {proto_rtf / roll_rtf:.3f}; "
              f"bare loop / rollout: {bare_rtf / roll_rtf:.3f}")
    ident = bench_identify(proto_res.log)
    survey = bench_survey()

    print()
    print("Summary (real-time factor = simulated s / wall s; no bound is asserted)")
    rows = [("prototype axis1 experiment", f"{proto_rtf:.1f}x", f">= {PROTO_TARGET:.0f}x",
             f"{proto_rtf / PROTO_TARGET:.2f}")]
    for joint, rtf in arm6.items():
        rows.append((f"arm6 {joint} experiment", f"{rtf:.1f}x", f">= {ARM6_TARGET:.0f}x",
                     f"{rtf / ARM6_TARGET:.2f}"))
    rows.append(("arm6 slowest joint", f"{min(arm6.values()):.1f}x", f">= {ARM6_TARGET:.0f}x",
                 f"{min(arm6.values()) / ARM6_TARGET:.2f}"))
    rows.append(("bare mj_step loop (prototype)", f"{bare_rtf:.1f}x", "-", "-"))
    rows.append(("experiment / bare loop", f"{ratio:.2f}", "-", "-"))
    if roll_rtf is not None:
        rows.append(("mujoco.rollout (prototype)", f"{roll_rtf:.1f}x", "-", "-"))
        rows.append(("experiment / rollout", f"{proto_rtf / roll_rtf:.3f}", "-", "-"))
    else:
        rows.append(("mujoco.rollout (prototype)", "skipped", "-", "-"))
    for name, wall in ident.items():
        rows.append((f"identify {name}", f"{1e3 * wall:.1f} ms ({1 / wall:.1f}/s)", "-", "-"))
    rows.append(("`jointbench --help` wall", f"{startup['help']:.3f} s",
                 f"< {HELP_TARGET_S} s", f"{startup['help'] / HELP_TARGET_S:.2f}"))
    rows.append(("`python -c pass` wall", f"{startup['bare']:.3f} s", "-", "-"))
    rows.append(("`simulate --duration 60` / experiment", f"{startup['simulate_ratio']:.2f}x",
                 f"< {SIMULATE_TARGET}x", f"{startup['simulate_ratio'] / SIMULATE_TARGET:.2f}"))
    rows.append(("floor: (numpy + MuJoCo imports + experiment) / experiment",
                 f"{startup['floor_ratio']:.2f}x", "-", "-"))
    rows.append(("`survey --model arm6` (2 workers) wall", f"{survey:.1f} s",
                 f"< {SURVEY_TARGET_S:g} s", f"{survey / SURVEY_TARGET_S:.2f}"))
    w0 = max(len(r[0]) for r in rows + [("figure",)])
    w1 = max(len(r[1]) for r in rows + [("", "value")])
    w2 = max(len(r[2]) for r in rows + [("", "", "target")])
    print(f"  {'figure':<{w0}}  {'value':>{w1}}  {'target':>{w2}}  ratio to target")
    for a, b, c, r in rows:
        print(f"  {a:<{w0}}  {b:>{w1}}  {c:>{w2}}  {r}")
    if roll_rtf is None:
        print(f"  (rollout skipped: {roll_reason})")
    print(f"\ntotal benchmark wall time: {time.perf_counter() - t_start:.1f} s")


if __name__ == "__main__":
    main()
