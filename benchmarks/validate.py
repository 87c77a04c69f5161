"""Regenerate docs/validation.md, section by section (`make validate`).

    .venv/bin/python benchmarks/validate.py                       # every section (hours)
    .venv/bin/python benchmarks/validate.py --sections accuracy,speed
    .venv/bin/python benchmarks/validate.py --list

docs/validation.md holds every measured figure of the project. Each section's generated
block sits between the markers

    <!-- validate:NAME -->
    ...
    <!-- /validate:NAME -->

and starts with a stamp line: the commit, the date (UTC), the machine (CPU model, cores,
numpy's BLAS, load average at the start) and the wall time. A section's generator runs the
existing benchmark scripts of benchmarks/ or the `jointbench` commands a user runs, in a
fresh temporary folder, and the block gets their real output. Sections not asked for keep
their block and their own stamp. The file is rewritten atomically after each section (a
temporary file in the same folder, then a rename), so an interrupted run keeps the sections
already done. A section whose command fails keeps its old block; the run then exits 1.

Nothing here asserts a figure: the tests and bars do (tests/, docs/validation.md's text).
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import platform
import re
import shlex
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "validation.md"


@dataclass(frozen=True)
class Command:
    """One command of a generator. `argv` may hold the placeholders {py} (this Python),
    {jb} (the jointbench script beside it), {root} (the checkout) and {tmp} (the section's
    temporary folder). `tail`: keep only the last lines of the output (0: all). `ok`: the
    exit statuses that count as success (a failed accuracy gate exits 3 on purpose)."""

    argv: str
    tail: int = 0
    ok: tuple[int, ...] = (0,)
    shown: str = ""   # how the command is printed in the block (default: argv, shortened)


@dataclass(frozen=True)
class Section:
    name: str
    commands: tuple[Command, ...] = ()
    summary: Callable[[Path], str] | None = None   # a table computed from the commands' files
    minutes: float = 1.0                           # rough wall time on 2 cores, for --list
    note: str = ""


def _cmd(argv: str, **kw) -> Command:
    return Command(argv, **kw)


def _accuracy_table(tmp: Path) -> str:
    """K, Jm, JL errors against the truth on the demo's log (seed 1, 60 s), one row per
    model and option, from `identify --json` (error_pct, and `debiased.error_pct`)."""
    rows = [("joint-motor (eq. 13)", ["--model", "joint-motor"]),
            ("motor-only as printed (eq. 18), NLS inversion", ["--model", "motor-only-printed"]),
            ("motor-only corrected", ["--model", "motor-only"]),
            ("joint-motor, 5-point differences", ["--model", "joint-motor", "--stencil", "5"]),
            ("motor-only corrected, 5-point differences", ["--model", "motor-only", "--stencil", "5"]),
            ("joint-motor, bias-corrected (`--debias 8`)", ["--model", "joint-motor", "--debias", "8"]),
            ("motor-only corrected, bias-corrected (`--debias 8`)",
             ["--model", "motor-only", "--debias", "8"])]
    lines = ["| model | K | Jm | JL | command |", "| --- | --- | --- | --- | --- |"]
    for label, opts in rows:
        argv = [_jointbench(), "identify", str(tmp / "demo.csv"), "--json", *opts]
        r = subprocess.run(argv, capture_output=True, text=True, cwd=tmp)
        if r.returncode != 0:
            raise RuntimeError(f"{' '.join(argv)}: exit {r.returncode}: {r.stderr.strip()}")
        answer = json.loads(r.stdout)
        err = answer.get("error_pct") or {}
        if "--debias" in opts:
            err = ((answer.get("debiased") or {}).get("error_pct") or {}).get("debiased") or {}
        cells = [f"{err[p]:+.3f} %" if isinstance(err.get(p), (int, float)) else "-"
                 for p in ("K", "Jm", "JL")]
        lines.append(f"| {label} | {' | '.join(cells)} | `identify demo.csv {' '.join(opts)}` |")
    return "\n".join(lines)


DRIVE_MAP = ("--map t=time_ms,q_m=motor_counts,q=link_deg,tau_m=current_A,q_ref=ref_counts "
             "--units t=ms,q_m=counts,q=deg,tau_m=A,q_ref=counts --gear-ratio 100 "
             "--counts-per-turn 131072 --torque-constant 0.5 --kp 5.83678819 --kv 5188.797305 "
             "--ki 30285.91083 --tau-max 3000 --joint axis1")
EMPS = "{root}/tests/data/emps"

SECTIONS: tuple[Section, ...] = (
    Section("tests", (_cmd("{py} -m pytest -q -p no:cacheprovider {root}/tests", tail=3),),
            minutes=15, note="the whole suite, as `make test` runs it"),
    Section("demo", (_cmd("{jb} demo --out demo_out"),), minutes=0.5),
    Section("cli", (_cmd("{jb} simulate --model arm6 --joint axis3 --duration 10 --seed 2 --out a3.csv"),
                    _cmd("{jb} design-filter --f1 3.9 --nd 2 --m 4")), minutes=0.1),
    Section("survey", (_cmd("{jb} survey --model arm6 --seed 1 --workers 2 --out survey_out"),),
            minutes=0.5),
    Section("import", (_cmd("{jb} import {root}/docs/examples/drive_raw.csv --out log.csv " + DRIVE_MAP,
                            shown="jointbench import drive_raw.csv --out log.csv " + DRIVE_MAP),
                       _cmd("{jb} identify log.csv"),
                       _cmd("{jb} diagnose log.csv --quiet --out diag")), minutes=0.5),
    Section("cross-validation", (_cmd("{jb} simulate --seed 1 --out s1.csv --quiet"),
                                 _cmd("{jb} simulate --seed 2 --out s2.csv --quiet"),
                                 _cmd("{jb} identify s1.csv --validate s2.csv", tail=2)),
            minutes=0.2),
    Section("modelling", note="no generator: the figures come from probes described in the record"),
    Section("speed", (_cmd("{py} {root}/benchmarks/run.py"),), minutes=1),
    Section("speed-ratios", (_cmd("{py} {root}/benchmarks/speed_ratios.py"),), minutes=3,
            note="identify, diagnose and --debias against the plain chain (`make bench`)"),
    Section("diagnose-speed", (_cmd("{py} {root}/benchmarks/diagnose_speed.py"),), minutes=3),
    Section("accuracy", (_cmd("{jb} simulate --seed 1 --out demo.csv --quiet"),),
            summary=_accuracy_table, minutes=1),
    Section("lean", (_cmd("{py} {root}/benchmarks/lean_corrections.py --out lean.md", tail=1),),
            summary=lambda tmp: (tmp / "lean.md").read_text(), minutes=4,
            note="each correction's effect (docs/method.md, section 4)"),
    Section("arm", (_cmd("{py} -m pytest -q -p no:cacheprovider {test:test_arm.py}", tail=3),),
            minutes=3, note="the test's bars; the figures are in the record"),
    Section("any-axis", (_cmd("{py} {root}/benchmarks/indep_accuracy.py"),), minutes=10),
    Section("diagnose", (_cmd("{jb} simulate --seed 1 --effect backlash=0.002 --out backlash.csv --quiet"),
                         _cmd("{jb} diagnose backlash.csv --out diag")), minutes=0.3),
    Section("diagnose-model", (_cmd("{py} {root}/benchmarks/diagnose_model.py"),), minutes=5),
    Section("diagnose-battery", (_cmd("{py} {root}/benchmarks/diagnose_battery.py --per-effect 5"),),
            minutes=5),
    Section("battery", (_cmd("{py} {root}/benchmarks/battery.py --jobs 2 --seed 3658 --out battery_out "
                             "--record {root}/docs/battery_cases "
                             "--figure {root}/docs/figures/detection.png", tail=40),), minutes=20),
    Section("emps", (_cmd("{jb} identify " + EMPS + "/emps_estimation.csv --model rigid --fc 100 "
                          "--decimate 10 --skip 49 --no-zoh --no-torque-filter"),
                     _cmd("{jb} simulate --replay " + EMPS + "/emps_estimation.csv"),
                     _cmd("{jb} diagnose " + EMPS + "/emps_estimation.csv --validate " + EMPS +
                          "/emps_validation_pulses.csv --disturbance-column pulses_N "
                          "--disturbance-gain 35.15065188 --disturbance-at motor --out emps_diag")),
            minutes=1),
    Section("faults", (_cmd("{py} -m pytest -q -p no:cacheprovider {test:test_faults_output.py} "
                            "{test:test_faults_input.py} {test:test_faults_messages.py}",
                            tail=3),), minutes=3, note="the attack classes' tests"),
    Section("campaign", (_cmd("{py} {root}/benchmarks/campaign.py --out campaign_out"),), minutes=25),
    Section("refine", (_cmd("{jb} simulate --duration 60 --seed 1 --out proto.csv --quiet"),
                       _cmd("{jb} identify proto.csv --model motor-only --refine")), minutes=1),
    Section("debias", (_cmd("{jb} simulate --seed 1 --out demo1.csv --quiet"),
                       _cmd("{jb} identify demo1.csv --debias 8")), minutes=0.5),
    Section("tune-filter", (_cmd("{jb} tune-filter --seeds 6"),), minutes=1.5),
    Section("methods", (_cmd("{jb} campaign --runs 50 --method frf={root}/examples/frf_fit.py:estimate "
                             "--out frf50.csv",
                             shown="jointbench campaign --runs 50 --method "
                                   "frf=examples/frf_fit.py:estimate --out frf50.csv"),),
            minutes=1),
    Section("ci-gates", (_cmd("{jb} campaign --runs 50 --method frf={root}/examples/frf_fit.py:estimate "
                              "--require 'joint-motor:K.abs_bias_pct<0.5, frf:K.abs_bias_pct<5, "
                              "frf:JL.abs_bias_pct<5, failed==0' --junit accuracy.xml "
                              "--out campaign.csv --quiet", ok=(0, 3),
                              shown="jointbench campaign --runs 50 --method "
                                    "frf=examples/frf_fit.py:estimate --require 'joint-motor:"
                                    "K.abs_bias_pct<0.5, frf:K.abs_bias_pct<5, frf:JL.abs_bias_pct<5, "
                                    "failed==0' --junit accuracy.xml --out campaign.csv --quiet"),),
            minutes=1),
    Section("peers", (_cmd("{py} {root}/benchmarks/peers.py"),), minutes=1.5,
            note="needs MuJoCo's `sysid` extra (`make bench-peers` installs it)"),
)
BY_NAME = {s.name: s for s in SECTIONS}


def _jointbench() -> str:
    script = Path(sys.executable).with_name("jointbench")
    return str(script) if script.exists() else "jointbench"


def machine() -> str:
    """CPU model, cores, numpy's BLAS and the load average: what a figure's speed depends on."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    blas = "unknown"
    try:
        import numpy as np
        cfg = np.show_config(mode="dicts")
        b = cfg.get("Build Dependencies", {}).get("blas", {})
        blas = f"{b.get('name', '?')} {b.get('version', '')}".strip()
        np_version = np.__version__
    except Exception:   # older numpy: no dict mode
        np_version = "?"
    try:
        load = "%.1f" % os.getloadavg()[0]
    except OSError:
        load = "?"
    return (f"{cpu}, {os.cpu_count()} cores, numpy {np_version} with {blas}, Python "
            f"{platform.python_version()}, load average {load} at the start (shared machine)")


def commit() -> str:
    def git(*args: str) -> str:
        r = subprocess.run(["git", *args], capture_output=True, text=True, cwd=ROOT)
        return r.stdout.strip() if r.returncode == 0 else ""
    head = git("rev-parse", "--short", "HEAD") or "unknown"
    return head + ("-dirty" if git("status", "--porcelain", "--untracked-files=no") else "")


def stamp(name: str, seconds: float) -> str:
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return (f"_Generated by `python benchmarks/validate.py --sections {name}`: commit {commit()}, "
            f"{now}, {machine()}; {seconds:.0f} s wall._")


def _test_file(name: str) -> str:
    """A test file by its basename, wherever tests/ keeps it (basenames are unique there)."""
    found = sorted((ROOT / "tests").rglob(name))
    if len(found) != 1:
        raise RuntimeError(f"tests/**/{name}: {len(found)} files found, 1 expected")
    return str(found[0])


def _expand(text: str, tmp: Path) -> str:
    text = re.sub(r"\{test:([\w.]+)\}", lambda m: shlex.quote(_test_file(m.group(1))), text)
    return text.format(py=shlex.quote(sys.executable), jb=shlex.quote(_jointbench()),
                       root=shlex.quote(str(ROOT)), tmp=shlex.quote(str(tmp)))


def _shown(c: Command) -> str:
    if c.shown:
        return c.shown
    text = re.sub(r"\{test:([\w.]+)\}", r"\1", c.argv)
    text = text.replace("{py} {root}/", "python ")
    text = text.replace("{py} -m pytest -q -p no:cacheprovider", "pytest -q")
    return text.replace("{jb}", "jointbench").replace("{root}/", "").replace("{py}", "python")


def run_section(section: Section) -> str:
    """Run the section's commands in a fresh temporary folder; return its block (stamp line,
    then the output). Raises RuntimeError when a command fails."""
    start = time.perf_counter()
    parts: list[str] = []
    with tempfile.TemporaryDirectory(prefix=f"validate-{section.name}-") as d:
        tmp = Path(d)
        env = dict(os.environ, MPLBACKEND="Agg")
        for c in section.commands:
            argv = shlex.split(_expand(c.argv, tmp))
            print(f"[{section.name}] $ {_shown(c)}", file=sys.stderr, flush=True)
            r = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                               cwd=tmp, env=env)   # one stream: progress where it happened
            out = r.stdout.rstrip("\n").replace(str(tmp) + os.sep, "")
            out = out.replace(str(ROOT) + os.sep, "")
            if r.returncode not in c.ok:
                raise RuntimeError(f"{_shown(c)}: exit {r.returncode}\n{out[-2000:]}")
            lines = out.splitlines()
            if c.tail and len(lines) > c.tail:
                lines = ["...", *lines[-c.tail:]]
            shown = "$ " + _shown(c) + (f"   # exit {r.returncode}" if r.returncode else "")
            parts.append("\n".join([shown, *lines]))
        table = section.summary(tmp) if section.summary else ""
    body = "```\n" + "\n".join(parts) + "\n```" if parts else ""
    if table:
        body = (body + "\n\n" if body else "") + table
    return stamp(section.name, time.perf_counter() - start) + "\n\n" + body


def markers(name: str) -> tuple[str, str]:
    return f"<!-- validate:{name} -->", f"<!-- /validate:{name} -->"


def replace_block(text: str, name: str, block: str) -> str:
    """`text` with the content between section `name`'s markers replaced by `block`; every
    other byte unchanged. Raises KeyError when the markers are missing or out of order."""
    begin, end = markers(name)
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < i or text.find(begin, i + 1) >= 0:
        raise KeyError(f"{name}: markers {begin} ... {end} missing, repeated or out of order")
    return text[:i + len(begin)] + "\n" + block.strip("\n") + "\n" + text[j:]


def write_atomic(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def parse_sections(value: str | None) -> list[Section]:
    if not value:
        return [s for s in SECTIONS if s.commands]
    names = [v.strip() for v in value.split(",") if v.strip()]
    unknown = [n for n in names if n not in BY_NAME]
    if unknown:
        raise argparse.ArgumentTypeError(
            f"--sections: unknown section(s) {', '.join(unknown)}; known: {', '.join(BY_NAME)}")
    return [BY_NAME[n] for n in names]


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sections", help="comma-separated section names (default: all with a generator)")
    ap.add_argument("--file", type=Path, default=DOC, help="the document (default docs/validation.md)")
    ap.add_argument("--list", action="store_true", help="list the sections and exit")
    ap.add_argument("--show", action="store_true", help="also print each block written")
    args = ap.parse_args(argv)
    if args.list:
        for s in SECTIONS:
            what = f"~{s.minutes:g} min" if s.commands else "no generator"
            print(f"{s.name:18s} {what:14s} {s.note}")
        return 0
    try:
        chosen = parse_sections(args.sections)
    except argparse.ArgumentTypeError as e:
        print(f"validate.py: error: {e}", file=sys.stderr)
        return 2
    if not args.file.is_file():
        print(f"validate.py: error: {args.file}: no such file", file=sys.stderr)
        return 2
    for s in chosen:   # every marker present before anything runs
        try:
            replace_block(args.file.read_text(), s.name, "")
        except KeyError as e:
            print(f"validate.py: error: {args.file}: {e.args[0]}", file=sys.stderr)
            return 2
    failed = []
    for s in chosen:
        if not s.commands:
            print(f"[{s.name}] no generator: block kept", file=sys.stderr)
            continue
        try:
            block = run_section(s)
        except RuntimeError as e:
            print(f"[{s.name}] failed, block kept: {e}", file=sys.stderr)
            failed.append(s.name)
            continue
        write_atomic(args.file, replace_block(args.file.read_text(), s.name, block))
        print(f"[{s.name}] written", file=sys.stderr)
        if args.show:
            print(block, flush=True)
    if failed:
        print(f"validate.py: {len(failed)} section(s) failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
