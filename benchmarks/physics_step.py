"""The bench's physics step against the suite's accuracy bars and its cost.

For each count of MuJoCo steps a control period (`--steps`, at the paper's 350.87 Hz; the
arm's design-rate runs take `--design-steps`), the figures the accuracy tests check, on
several seeds:
  - prototype, 60 s, defaults: joint-motor K, Jm, JL (0.5 %, 3 sigma), frictions (5 %), MY (2 %);
    motor-only (3 %); the paper's chain alone (3 %)
    (tests/validation/test_identification.py, tests/sim/test_plain_corrections.py);
  - the frictionless prototype, ideal sensors, the paper's filter with 3 and 5 points
    (test_identification.py::test_five_point_stencil_removes_the_differentiation_bias);
  - arm6 axes 1-6 at 350.87 Hz, 60 s, defaults: joint-motor and motor-only K, Jm, JL error
    and corrected z, the frictions' z (tests/sim/test_first_mode.py, test_survey.py);
  - arm6 axes 1, 4, 6 at their design rate with test_arm.py's chirp (tests/validation/test_arm.py);
  - the substep convergence: the prototype at N against 2 N steps, ideal sensors, 20 s
    (tests/sim/test_bench.py::test_substep_convergence);
and the cost: the process CPU time of a 20 s run, as a real-time factor.

Prints one JSON object a case (`--out` also writes them, one a line) and asserts nothing.
Usage: python benchmarks/physics_step.py --steps 4,8,29 --seeds 1,2,3 --jobs 2 --out f.jsonl
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np

RATE = 350.87
ARM = tuple(f"axis{j}" for j in range(1, 7))
DESIGN_JOINTS = ("axis1", "axis4", "axis6")
NAMES = ("K", "Jm", "JL", "FVm", "FSm", "FV", "FS", "MX", "MY")


def _figures(result, truth: dict) -> dict:
    out = {}
    for name in NAMES:
        value = result.physical.get(name)
        if value is None or not np.isfinite(value) or name not in truth:
            continue
        sc = (result.physical_sigma_corrected or result.physical_sigma).get(name, np.nan)
        s = result.physical_sigma.get(name, np.nan)
        true = truth[name]
        out[name] = {"err_pct": 100 * (value - true) / abs(true) if true else None,
                     "z": (value - true) / sc if sc else None,
                     "z_white": (value - true) / s if s else None, "value": value}
    return out


def _nofriction_model(tmp: Path) -> Path:
    import mujoco

    from jointbench.models import model_path

    spec = mujoco.MjSpec.from_file(str(model_path("prototype")))
    for j in spec.joints:
        j.frictionloss = 0.0
    path = tmp / "prototype_no_friction.xml"
    if not path.exists():
        path.write_text(spec.to_xml())
    return path


def _arm_no_motor_coulomb(tmp: Path) -> Path:
    import mujoco

    from jointbench.models import model_path

    spec = mujoco.MjSpec.from_file(str(model_path("arm6")))
    spec.joint("axis4_motor").frictionloss = 0.0
    path = tmp / "arm6_no_motor_coulomb.xml"
    if not path.exists():
        path.write_text(spec.to_xml())
    return path


def run_case(case: tuple) -> dict:
    """One case: (kind, steps, seed, joint, tmp folder)."""
    from jointbench.bench.sim.axes import build_experiment_model
    from jointbench.bench.sim.experiment import default_chirp, run_experiment
    from jointbench.bench.sim.sensors import Sensors
    from jointbench.identification import filter_choice, filtering
    from jointbench.identification.first_mode import measure_first_mode
    from jointbench.identification.identify import identify

    kind, n, seed, joint, tmp = case
    tmp = Path(tmp)
    out = {"kind": kind, "steps": n, "seed": seed, "joint": joint}
    t0 = time.process_time()
    if kind == "prototype":
        log = run_experiment("prototype", duration=60.0, seed=seed, substeps=n).log
        truth = log.truth()
        for model, kw in (("joint-motor", {}), ("motor-only", {}),
                          ("motor-only-printed", {}), ("plain", {"corrections": ()})):
            r = identify(log, "joint-motor" if model == "plain" else model, **kw)
            out[model] = _figures(r, truth)
    elif kind == "nofriction":
        res = run_experiment(_nofriction_model(tmp), seed=seed, sensors=Sensors.ideal(),
                             substeps=n)
        truth = res.log.truth()
        base = filter_choice.default_settings(filter_choice.PAPER_RATE)
        for stencil in (3, 5):
            s = filtering.FilterSettings(wn=base.wn, m=base.m, Nd=base.Nd, ts=res.log.ts,
                                         stencil=stencil)
            out[f"stencil{stencil}"] = _figures(identify(res.log, "joint-motor", settings=s),
                                                truth)
    elif kind == "arm350":
        log = run_experiment("arm6", joint, duration=60.0, seed=seed, substeps=n).log
        truth = log.truth()
        out["f1_err_pct"] = 100 * (measure_first_mode(log).f1_hz / truth["f1_hz"] - 1)
        for model in ("joint-motor", "motor-only"):
            out[model] = _figures(identify(log, model), truth)
    elif kind in ("design", "design_nomotorcoulomb"):
        model = "arm6" if kind == "design" else str(_arm_no_motor_coulomb(tmp))
        rate = filter_choice.design_rate_hz(build_experiment_model("arm6", joint).truth.f1_hz)
        exp = build_experiment_model(model, joint, sample_rate_hz=rate)
        chirp = default_chirp(exp, 60.0)
        chirp = replace(chirp, max_acceleration=0.55 * exp.tau_max
                        / (exp.truth.Jm + exp.truth.JL))
        log = run_experiment(model, joint, duration=60.0, seed=seed, chirp=chirp,
                             sample_rate_hz=rate, substeps=n).log
        truth = log.truth()
        r = identify(log, "joint-motor", filter_choice.default_settings(rate, truth["f1_hz"]))
        out["rate_hz"] = rate
        out["joint-motor"] = _figures(r, truth)
    elif kind == "convergence":
        a = run_experiment("prototype", duration=20.0, seed=0, sensors=Sensors.ideal(),
                           substeps=n).log
        b = run_experiment("prototype", duration=20.0, seed=0, sensors=Sensors.ideal(),
                           substeps=2 * n).log
        c = a.q_m[0]

        def rel(x, y):
            return float(np.sqrt(np.mean((x - y) ** 2)) / np.sqrt(np.mean(y ** 2)))
        out.update(q_m=rel(a.q_m - c, b.q_m - c), q=rel(a.q - c, b.q - c),
                   tau_m=rel(a.tau_m, b.tau_m))
    elif kind == "cost":
        model, joint_, rate = {"prototype": ("prototype", None, RATE),
                               "arm6_axis4": ("arm6", "axis4", RATE),
                               "arm6_axis6_design": ("arm6", "axis6", None)}[joint]
        if rate is None:
            rate = filter_choice.design_rate_hz(
                build_experiment_model("arm6", "axis6").truth.f1_hz)
        best = np.inf
        for _ in range(2):
            c0 = time.process_time()
            run_experiment(model, joint_, duration=20.0, seed=1, substeps=n,
                           sample_rate_hz=rate)
            best = min(best, time.process_time() - c0)
        out.update(rate_hz=rate, cpu_s=best, real_time_factor=20.0 / best)
    else:
        raise ValueError(kind)
    out["cpu_s_case"] = time.process_time() - t0
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", default="4,6,8,12,16,29")
    p.add_argument("--design-steps", default="4,5,6,7")
    p.add_argument("--seeds", default="1,2,3")
    p.add_argument("--kinds", default="prototype,nofriction,arm350,design,"
                                      "design_nomotorcoulomb,convergence,cost")
    p.add_argument("--joints", default=",".join(ARM))
    p.add_argument("--jobs", type=int, default=1)
    p.add_argument("--out", type=Path)
    p.add_argument("--tmp", type=Path, default=Path("/tmp"))
    a = p.parse_args(argv)
    steps = [int(x) for x in a.steps.split(",")]
    design_steps = [int(x) for x in a.design_steps.split(",")]
    seeds = [int(x) for x in a.seeds.split(",")]
    kinds = a.kinds.split(",")
    joints = a.joints.split(",")
    tmp = str(a.tmp)
    cases = []
    for n in steps:
        if "cost" in kinds:
            cases += [("cost", n, 1, j, tmp) for j in ("prototype", "arm6_axis4")]
        if "convergence" in kinds:
            cases.append(("convergence", n, 0, None, tmp))
        if "prototype" in kinds:
            cases += [("prototype", n, s, None, tmp) for s in seeds]
        if "nofriction" in kinds:
            cases += [("nofriction", n, s, None, tmp) for s in seeds[:2]]
        if "arm350" in kinds:
            cases += [("arm350", n, s, j, tmp) for s in seeds for j in joints]
    for n in design_steps:
        if "cost" in kinds:
            cases.append(("cost", n, 1, "arm6_axis6_design", tmp))
        if "design" in kinds:
            cases += [("design", n, s, j, tmp) for s in seeds for j in DESIGN_JOINTS
                      if j in joints]
        if "design_nomotorcoulomb" in kinds:
            cases.append(("design_nomotorcoulomb", n, 1, "axis4", tmp))
    sink = a.out.open("a") if a.out else None
    with ProcessPoolExecutor(a.jobs) as pool:
        for result in pool.map(run_case, cases):
            line = json.dumps(result)
            print(line, flush=True)
            if sink:
                sink.write(line + "\n")
                sink.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
