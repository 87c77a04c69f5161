"""`jointbench flexify ROBOT.xml --out FLEX.xml [--from RESULT.json] [--set JOINT.K=V,...]`:
a rigid MJCF arm (hinges driven by gear motors) rewritten in the axis convention of
models/__init__.py, a rotor, a spring and a motor per joint (bench/sim/flexify.py). The
result runs with `simulate`, `survey` and `diagnose --model`."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from jointbench.bench.cli.common import UsageError, check_output_file

LIBRARY = ("jointbench.bench.sim.flexify",)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of `flexify`."""
    p.add_argument("model", help="the rigid MJCF: hinge joints, each driven by an actuator")
    p.add_argument("--out", required=True, help="the flexified MJCF to write (never the input)")
    p.add_argument("--from", dest="source", metavar="RESULT.json",
                   help="parameters from a `survey --json` answer (per joint) or an `identify "
                        "--json` answer (with --joints JOINT, one joint)")
    p.add_argument("--set", action="append", default=[], metavar="JOINT.P=V,...",
                   help="a joint's parameter, joint side, SI: K, Jm, FVm, FSm, FV, FS, N (gear "
                        "ratio), tau_max, e.g. shoulder.K=2e4,shoulder.Jm=3.5 (repeatable; "
                        "over --from)")
    p.add_argument("--joints", help="the joints to flexify (default: every joint)")
    p.add_argument("--json", action="store_true", help="print a JSON summary")


def parse_set(items: list[str]) -> dict[str, dict[str, float]]:
    """--set JOINT.P=V,... as joint -> parameter -> value; UsageError naming the item."""
    from jointbench.bench.sim.flexify import PARAMETERS

    out: dict[str, dict[str, float]] = {}
    for item in (x for text in items for x in text.split(",") if x.strip()):
        key, sep, value = item.partition("=")
        joint, dot, param = key.strip().rpartition(".")
        if not sep or not dot or not joint:
            raise UsageError(f"--set: '{item}' must read JOINT.P=V (e.g. shoulder.K=2e4)")
        if param not in PARAMETERS:
            raise UsageError(f"--set {item}: '{param}' is not a parameter "
                             f"({', '.join(PARAMETERS)})")
        try:
            x = float(value)
        except ValueError:
            raise UsageError(f"--set {item}: '{value.strip()}' is not a number") from None
        if not math.isfinite(x) or "_" in value:
            raise UsageError(f"--set {item}: '{value.strip()}' is not a finite number")
        out.setdefault(joint, {})[param] = x
    return out


def read_result(path: Path, joints: list[str] | None) -> dict[str, dict[str, float]]:
    """The K, Jm, FVm, FSm, FV, FS of a survey or identify JSON, per joint."""
    try:
        doc = json.loads(path.read_text())
    except OSError as err:
        raise UsageError(f"--from {path}: {err.strerror}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise UsageError(f"--from {path}: not JSON ({err})") from None

    def values(params: dict, where: str) -> dict[str, float]:
        if not isinstance(params, dict):
            raise UsageError(f"--from {path}: {where} has no \"parameters\" object")
        out = {}
        for name in ("K", "Jm", "FVm", "FSm", "FV", "FS"):
            entry = params.get(name)
            value = entry.get("value") if isinstance(entry, dict) else None
            if isinstance(value, (int, float)) and math.isfinite(value):
                out[name] = float(value)
        return out

    if isinstance(doc, dict) and isinstance(doc.get("joints"), list):   # survey --json
        return {j["joint"]: values(j.get("parameters"), f"joint {j.get('joint')}")
                for j in doc["joints"] if isinstance(j, dict) and j.get("status") == "ok"}
    if isinstance(doc, dict) and "parameters" in doc:                      # identify --json
        if not joints or len(joints) != 1:
            raise UsageError(f"--from {path}: an identify answer is one joint's: give "
                             "--joints JOINT")
        return {joints[0]: values(doc["parameters"], "the answer")}
    raise UsageError(f"--from {path}: neither a `survey --json` nor an `identify --json` "
                     "answer")


def run(args: argparse.Namespace) -> int:
    """Flexify, check the convention, write atomically; print the drives and their sources."""
    from jointbench.bench.sim.axes import build_experiment_model
    from jointbench.bench.sim.flexify import flexify, to_xml
    from jointbench.bench.output_files import write_text

    src, out = Path(args.model), Path(args.out)
    if not src.is_file():
        raise UsageError(f"{src}: no such MJCF file")
    if out.exists() and out.resolve() == src.resolve():
        raise UsageError(f"--out {out}: is the input file; choose another name")
    check_output_file(out)
    joints = [j.strip() for j in args.joints.split(",")] if args.joints else None
    given = parse_set(args.set)
    from_file = read_result(Path(args.source), joints) if args.source else None
    result = flexify(src, given, from_file, joints,
                     from_name=f"--from {Path(args.source).name}" if args.source else "--from")
    text, moved = to_xml(result.spec, src, out)
    changes = list(result.changes) + moved
    write_text(out, text)   # atomically, recorded in the folder's manifest as ours
    try:   # the convention check of `simulate --model`, on the file as written
        for d in result.drives:
            build_experiment_model(out, d.joint)
    except BaseException:
        out.unlink(missing_ok=True)
        raise
    if args.json:
        print(json.dumps({"out": str(out), "changes": changes, "joints": [
            {"joint": d.joint, "values": d.values, "sources": d.sources, "JL": d.JL,
             "f1_hz": d.f1_hz} for d in result.drives]}))
        return 0
    lines = [f"{src} -> {out}: {len(result.drives)} joints made flexible (axis convention: "
             "rotor X_motor, spring X_spring, motor X_motor)"]
    for d in result.drives:
        lines.append(f"  {d.joint}: JL {d.JL:.6g} kg m^2 at qpos0, f1 {d.f1_hz:.4g} Hz")
        for k in ("K", "Jm", "FVm", "FSm", "FV", "FS", "N", "tau_max"):
            if k in d.values:
                lines.append(f"    {k:<8}{d.values[k]:<14.6g}{d.sources[k]}")
    lines.append("model options: " + "; ".join(changes))
    print("\n".join(lines))
    return 0
