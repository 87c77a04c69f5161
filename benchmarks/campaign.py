"""Campaign benchmark: calibration of the reported sigma and the filter search.

    .venv/bin/python benchmarks/campaign.py [--runs 200] [--seeds 6] [--out campaign_out]

1. Coverage. `jointbench campaign --runs 200` on the paper's prototype (60 s chirps, default
   sensors, campaign seed 0, both identification models), on all local cores. Printed per
   model for K, Jm, JL (and the others): bias and empirical std of the error against truth,
   the mean paper-style sigma and the mean corrected sigma (identification/uncertainty.py,
   when present), std / sigma, and the +-2 sigma coverage with its 95 % interval. The table
   `OUT/coverage.csv` resumes if the run is interrupted (run the same command again).
   Then the same 200 runs with `--debias 8` (bench/analysis/debias.py): every two-mass estimate also
   bias-corrected by 8 closed-loop replicas, whose coverage the summary gives as the models
   "joint-motor (bias-corrected)" and "motor-only (bias-corrected)" (`OUT/coverage_debias.csv`;
   about 9x the runtime of the first).
2. Filter tuning. `jointbench tune-filter`: wn x Nd grid, `--seeds` search experiments and as
   many validation experiments, optimum beside the paper's wn = 176 rad/s, Nd = 26 and the
   eq. (28)-(29) values.

Wall times are printed; nothing is asserted.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from jointbench.bench.cli import main as jointbench


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=200, help="coverage runs (default 200)")
    ap.add_argument("--seeds", type=int, default=6, help="tuning search seeds (default 6)")
    ap.add_argument("--out", default="campaign_out", help="folder for tables and summaries")
    ap.add_argument("--workers", help="local worker processes (default: all cores)")
    ap.add_argument("--skip-tuning", action="store_true")
    ap.add_argument("--skip-debias", action="store_true",
                    help="no bias-corrected coverage campaign")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    workers = ["--workers", args.workers] if args.workers else []

    print(f"$ jointbench campaign --runs {args.runs} --out {out / 'coverage.csv'}")
    t0 = time.perf_counter()
    rc = jointbench(["campaign", "--runs", str(args.runs), "--seed", "0",
                     "--out", str(out / "coverage.csv"), *workers])
    print(f"(exit {rc}, {time.perf_counter() - t0:.1f} s)")
    if not args.skip_debias:
        print()
        print(f"$ jointbench campaign --runs {args.runs} --debias 8 "
              f"--out {out / 'coverage_debias.csv'}")
        t0 = time.perf_counter()
        rc = jointbench(["campaign", "--runs", str(args.runs), "--seed", "0", "--debias", "8",
                         "--out", str(out / "coverage_debias.csv"), *workers])
        print(f"(exit {rc}, {time.perf_counter() - t0:.1f} s)")
    if args.skip_tuning:
        return
    print()
    print(f"$ jointbench tune-filter --seeds {args.seeds}")
    t0 = time.perf_counter()
    rc = jointbench(["tune-filter", "--seeds", str(args.seeds), *workers])
    print(f"(exit {rc}, {time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
