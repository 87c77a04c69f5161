"""`diagnose` time against another checkout of jointbench on the same logs: the logs of
benchmarks/diagnose_speed.py's cases are made once by this checkout and written to files, then
each file is diagnosed in a fresh process by this checkout's `diagnose` and by the other's
(its own venv), alternately, and the CPU seconds of the call alone are compared.

    .venv/bin/python benchmarks/diagnose_speed_against.py OTHER_CHECKOUT [--duration 60]
        [--seed 2026] [--repeat 1] [--out DIR] [CASE ...]

OTHER_CHECKOUT is a checkout with its own `.venv` (git worktree add --detach DIR COMMIT;
make .venv/.installed there). Each line: the case, both CPU times and their ratio; last, the
largest ratio.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from diagnose_speed import add_case_args, case_specs, make_log

from jointbench.identification.log.write import write_log

ROOT = Path(__file__).resolve().parent.parent

# run in the checkout's own interpreter: read the log, time the diagnose call alone
TIMER = """
import json, sys, time
from jointbench.identification.log.read import read_log
from jointbench.bench.analysis.diagnose import diagnose
log = read_log(sys.argv[1])
c0 = time.process_time()
d = diagnose(log)
print(json.dumps({"cpu": time.process_time() - c0,
                  "named": [c.effect for c in d.causes] if d.named else []}))
"""


def _time(checkout: Path, path: Path) -> dict:
    out = subprocess.run([str(checkout / ".venv" / "bin" / "python"), "-c", TIMER, str(path)],
                         cwd=checkout, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("other", type=Path, help="another checkout with its own .venv")
    add_case_args(ap)
    ap.add_argument("--repeat", type=int, default=1, help="timings per log and checkout")
    ap.add_argument("--out", type=Path, default=None, help="folder for the logs (default: temp)")
    args = ap.parse_args(argv)
    if not (args.other / ".venv" / "bin" / "python").exists():
        print(f"{args.other}: no .venv/bin/python there (make .venv/.installed)",
              file=sys.stderr)
        return 2
    specs = case_specs(args)
    if specs is None:
        return 2
    folder = args.out or Path(tempfile.mkdtemp(prefix="diagnose_speed_"))
    folder.mkdir(parents=True, exist_ok=True)
    print(f"diagnose CPU time on {args.duration:g} s logs (battery seed {args.seed}): "
          f"this checkout ({ROOT}) against {args.other}")
    worst = 0.0
    for i, s in zip(args.cases, specs):
        path = folder / f"case{i:03d}.csv"
        write_log(make_log(s), path)
        ours, theirs = [], []
        for _ in range(args.repeat):
            theirs.append(_time(args.other, path))
            ours.append(_time(ROOT, path))
        a, b = min(t["cpu"] for t in ours), min(t["cpu"] for t in theirs)
        worst = max(worst, a / b)
        what = "+".join(s.effects) or "clean"
        print(f"#{i:3d} {s.place.family:16s} {what:30s} ours {a:5.2f} s "
              f"({','.join(ours[0]['named']) or 'none'}), other {b:5.2f} s "
              f"({','.join(theirs[0]['named']) or 'none'}): {a / b:.2f}x")
    print(f"largest ratio: {worst:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
