"""What each correction beyond the paper changes (docs/method.md, section 4), measured.

    .venv/bin/python benchmarks/lean_corrections.py [--duration 60] [--out TABLE.md]

`benchmarks/validate.py --sections lean` runs it and puts the table (`--out`, markdown) into
the `lean` section of docs/validation.md, which docs/method.md links to. On the bench's logs at its defaults (8 physics steps a control
period, bench/sim/defaults.py):
- the prototype (`run_experiment("prototype")`, seed 3);
- arm6 axis6 at twice eq. (29)'s rate with the chirp of tests/validation/test_arm.py
  (seed 1);
- the independent simulator's five axis families (jointbench.testing, seed 1, linear sweep,
  velocity feed-forward), of which the row gives the largest |error|;
each log is identified with every correction (`identify`'s default), with the paper's chain
alone (`corrections=()`, `identify --plain`) and with every correction but one, for the
joint-motor model (eq. 13) and the motor-only model (eqs. 18-20). The cells are the errors of
K, Jm and JL against the truth in %; a fit that fails prints its reason's first word.
Nothing is asserted: the bars are the tests' (tests/validation/).
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from pathlib import Path

from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.sim.experiment import default_chirp, run_experiment
from jointbench.identification.corrections import CORRECTIONS
from jointbench.identification.estimate import NotIdentifiable
from jointbench.identification.filter_choice import default_settings, design_rate_hz
from jointbench.identification.identify import identify
from jointbench.identification.log import Log
from jointbench.identification.physical import InversionError
from jointbench.testing import FAMILIES, simulate

PARAMS = ("K", "Jm", "JL")
ARM_SHARE = 0.55   # the arm chirp's acceleration cap (tests/validation/test_arm.py)
# the corrections that act on each model's path (identification/corrections.py)
ACTS_ON = {"joint-motor": ("zoh", "stencil5", "instruments", "reversals", "stick_phases",
                           "wide_band"),
           "motor-only": ("zoh", "stencil5", "instruments", "stick_phases",
                          "motor_only_columns", "link_reconstruction")}


def arm_log(duration: float, joint: str = "axis6") -> tuple[Log, object]:
    """An arm6 log at twice eq. (29)'s rate, with its filter settings from the true f1."""
    rate = design_rate_hz(build_experiment_model("arm6", joint).truth.f1_hz)
    exp = build_experiment_model("arm6", joint, sample_rate_hz=rate)
    chirp = default_chirp(exp, duration)
    chirp = replace(chirp, max_acceleration=ARM_SHARE * exp.tau_max
                    / (exp.truth.Jm + exp.truth.JL))
    log = run_experiment("arm6", joint, duration=duration, seed=1, chirp=chirp,
                         sample_rate_hz=rate).log
    return log, default_settings(rate, log.truth()["f1_hz"])


def errors(log: Log, model: str, settings, corrections) -> dict[str, float] | str:
    """K, Jm, JL errors [%] against the truth, or the failure's reason."""
    try:
        r = identify(log, model, settings, corrections=corrections)
    except (NotIdentifiable, InversionError, ValueError) as err:
        return str(err).split()[0] if str(err) else type(err).__name__
    truth = log.truth()
    out = {}
    for n in PARAMS:
        v = r.physical.get(n, math.nan)
        out[n] = 100 * (v - truth[n]) / abs(truth[n])
    return out


def cell(e: dict[str, float] | str) -> str:
    if isinstance(e, str):
        return e
    return " / ".join(f"{e[n]:+.2f}" for n in PARAMS)


def worst(rows: list[dict[str, float] | str]) -> str:
    """The largest |error| of each parameter over the families (a failure named)."""
    failed = [r for r in rows if isinstance(r, str)]
    if failed:
        return f"{len(failed)} failed ({failed[0]})"
    return " / ".join(f"{max(abs(r[n]) for r in rows):.2f}" for n in PARAMS)


def variants(model: str) -> list[tuple[str, tuple[str, ...]]]:
    out = [("every correction (default)", CORRECTIONS), ("paper alone (`--plain`)", ())]
    out += [(f"without `{c}`", tuple(x for x in CORRECTIONS if x != c)) for c in ACTS_ON[model]]
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=60.0)
    p.add_argument("--out", type=Path, help="also write the tables (markdown) to this file")
    a = p.parse_args()
    proto = run_experiment("prototype", duration=a.duration, seed=3).log
    arm, arm_settings = arm_log(a.duration)
    families = [simulate(FAMILIES[f], seed=1, duration=a.duration) for f in FAMILIES]
    lines = [f"K / Jm / JL error in % against the truth ({a.duration:g} s logs; families: the "
             f"largest |error| of {', '.join(FAMILIES)})"]
    print(lines[0], flush=True)
    for model in ("joint-motor", "motor-only"):
        lines += ["", f"{model}:", "",
                  "| corrections | prototype (seed 3) | arm6 axis6 | families, max abs |",
                  "| --- | --- | --- | --- |"]
        print("\n".join(lines[-5:]), flush=True)
        for label, corr in variants(model):
            row = [cell(errors(proto, model, None, corr)),
                   cell(errors(arm, model, arm_settings, corr)),
                   worst([errors(f, model, None, corr) for f in families])]
            lines.append(f"| {label} | {' | '.join(row)} |")
            print(lines[-1], flush=True)
    if a.out is not None:
        a.out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
