"""The discrepancy battery by visibility (issue 14, item 3; issue 15, item 2): `diagnose` on
logs of the bench and of the independent simulator, every strength set by its in-band
visibility, not by the detector's thresholds.

    .venv/bin/python benchmarks/battery.py [--out battery_out] [--jobs 2] [--per-effect 8]
        [--clean 24] [--pairs 28] [--seed 2026] [--duration 40] [--figure docs/figures/detection.png]
        [--cases 39,55,71]   # only these plan indices, drawn as in the whole plan
    .venv/bin/python benchmarks/battery.py --from battery_out/cases.json   # summary, figure again

Every case runs at the paper's rate (350.87 Hz), the lab rig at its own, cycling over the places (bench prototype,
arm6 axis2 and axis4; independent families balanced, soft, wrist, pendulum; and the
independent simulator's lab rig, a voltage drive under a P loop at its own 500 Hz) and over
velocity feedforward on/off x torque noise on/off. Writes OUT/cases.json and OUT/cases.csv (model,
joint, seed, effects, strengths, visibilities, named; the distinguishing visibility of every
effect that reduces to another: bench.campaign.detection.distinguishing_visibility; the share
of torque samples at the limit, identification.saturation.clipped_samples),
OUT/summary.txt (confusion table, detection curve, 95 % visibility per effect) and the
detection-curve figure.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from jointbench.bench.campaign.battery import (BENCH_PLACES, BenchRunner, Spec, clean_key,
                                               draw_strength, plan, run_spec)
from jointbench.bench.campaign.detection import (BINS, curve,
                                                 distinguishing_visibility, found_above, right,
                                                 summary_lines)
from jointbench.identification.effects import EFFECTS, NONE
from jointbench.identification.log.write import atomic_write_text
from jointbench.identification.output_values import finite_json
from jointbench.identification.saturation import clipped_samples
from jointbench.testing import INDEP_PLACES, LAB_PLACES, IndepRunner, LabRigRunner

PLACES = (*BENCH_PLACES, *INDEP_PLACES, *LAB_PLACES)
_RUNNERS: dict = {}
_CACHE: dict = {}


def _init(duration: float) -> None:
    _RUNNERS.update(bench=BenchRunner(duration), indep=IndepRunner(duration),
                    lab=LabRigRunner(duration))


# the part of each case's `diagnose --json` answer that its claims are checked on
# (claims.failing_claims), kept in cases.json so the check can be redone on the record
ANSWER_KEYS = ("named_cause", "named_causes", "verdict", "causes", "alternatives", "ambiguity",
               "not_named", "stopped", "floor_pct")


def named_causes(d) -> list[str]:
    """The causes a Diagnosis names, in order: its `causes` (Candidates, issue 15 item 2)
    when the detector names several, else its one `named_cause`."""
    several = getattr(d, "causes", None)
    if several is not None:
        return [c.effect for c in several]
    return [] if d.named_cause == NONE else [d.named_cause]


def distinguishing(spec: Spec, outcome) -> list[float | None]:
    """Each hidden effect's distinguishing visibility (bench.campaign.detection.
    distinguishing_visibility: the part of its change the effect it reduces to cannot take),
    alone, from noise-free runs; None for an effect that reduces to no other. Reporting only:
    two more simulations per such effect, nothing the case's draw or diagnosis sees."""
    p = spec.place
    runner = _RUNNERS[p.source]
    tau_max, f1, K = runner.scales(p)
    clean = _CACHE[clean_key(spec, runner)]   # run_spec's noise-free clean command

    def tau(effect: tuple) -> np.ndarray:
        return runner.log(p, (effect,), spec.seed, spec.feedforward, False).tau_m

    found: list[float | None] = []
    for k, (name, strength, options) in enumerate(zip(spec.effects, outcome.strengths,
                                                      outcome.options)):
        reduced = EFFECTS[name].reduces_to
        if not reduced:
            found.append(None)
            continue
        s, o = draw_strength(reduced, np.random.default_rng([spec.seed, k]), tau_max, f1, K)
        found.append(distinguishing_visibility(clean, tau((name, strength, options)),
                                              tau((reduced, s, o)), f1, runner.rate_hz))
    return found


def run_one(spec: Spec) -> dict:
    """One case: strengths by visibility, the log, its diagnosis; a JSON-ready record."""
    from jointbench.bench.analysis.diagnose import diagnose
    from jointbench.bench.analysis.diagnose.claims import failing_claims

    p = spec.place
    rec = {"index": spec.index, "kind": spec.kind, "source": p.source, "model": p.model,
           "joint": p.joint or "", "family": p.family, "seed": spec.seed,
           "feedforward": spec.feedforward, "noise": spec.noise, "effects": list(spec.effects),
           "targets": list(spec.targets), "strengths": [], "options": [], "visibilities": [],
           "combined": 0.0, "clipped_pct": 0.0, "simulations": 0, "distinguishing": [],
           "saturated": [], "named": [], "ambiguity": [], "alternatives": [], "verdict": "",
           "failing_claims": [], "answer": {}, "error": ""}
    t0 = time.perf_counter()
    try:
        out = run_spec(spec, _RUNNERS[p.source], _CACHE)
        rec.update(strengths=list(out.strengths), options=[dict(o) for o in out.options],
                   visibilities=list(out.visibilities), combined=out.combined,
                   simulations=sum(len(s.tried) for s in out.searches) + 1,
                   saturated=[s.saturated for s in out.searches],
                   distinguishing=distinguishing(spec, out))
        # reporting only: a hidden effect may drive the loop into its torque limit
        rec["clipped_pct"] = 100 * clipped_samples(out.log).share
        t1 = time.perf_counter()
        d = diagnose(out.log)
        doc = finite_json(d.to_json())
        rec.update(named=named_causes(d), ambiguity=list(d.ambiguities), verdict=d.verdict,
                   alternatives=[[a.named, a.other] for c in d.causes
                                 for a in d.alternatives_of(c.effect)],
                   diagnose_s=time.perf_counter() - t1, failing_claims=failing_claims(doc),
                   answer={k: doc[k] for k in ANSWER_KEYS if k in doc})
    except Exception as err:  # a failed case is reported, never hidden
        rec["error"] = f"{type(err).__name__}: {err}"
    rec["seconds"] = time.perf_counter() - t0
    return rec


def _line(rec: dict) -> str:
    what = ",".join(f"{e}={s:.4g}" for e, s in zip(rec["effects"], rec["strengths"])) or NONE
    vis = ",".join(f"{100 * v:.1f}" for v in rec["visibilities"]) or "-"
    apart = [f"{100 * v:.1f}" for v in rec.get("distinguishing", ()) if v is not None]
    vis += f" (apart {','.join(apart)})" if apart else ""
    vis += " (out of reach)" if any(rec.get("saturated", ())) else ""
    named = ",".join(rec["named"]) or NONE
    mark = "error: " + rec["error"] if rec["error"] else ("" if right(rec) else "<-- miss")
    cond = ("ff" if rec["feedforward"] else "no-ff") + (" noise" if rec["noise"] else " quiet")
    where = f"{rec['model']}:{rec['joint']}" if rec["joint"] else rec["model"]
    return (f"#{rec['index']:3d} {rec['source']:5s} {where:12s} {cond:14s} {what:42s} "
            f"vis {vis:>11s} % -> {named:30s} {rec['seconds']:5.1f} s {mark}")


def _csv(records: list[dict]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["index", "kind", "source", "model", "joint", "seed", "feedforward", "noise",
                "effects", "strengths", "targets_pct", "visibilities_pct", "combined_pct",
                "named", "right", "ambiguity", "error", "distinguishing_pct", "clipped_pct",
                "saturated"])
    for r in records:
        w.writerow([r["index"], r["kind"], r["source"], r["model"], r["joint"], r["seed"],
                    r["feedforward"], r["noise"], ";".join(r["effects"]),
                    ";".join(f"{s:.6g}" for s in r["strengths"]),
                    ";".join(f"{100 * t:.2f}" for t in r["targets"]),
                    ";".join(f"{100 * v:.2f}" for v in r["visibilities"]),
                    f"{100 * r['combined']:.2f}", ";".join(r["named"]), right(r),
                    " | ".join(r.get("ambiguity", [])), r["error"],
                    ";".join("" if v is None else f"{100 * v:.2f}"
                             for v in r.get("distinguishing", [])),
                    f"{r.get('clipped_pct', 0.0):.3g}",
                    ";".join(str(bool(x)) for x in r.get("saturated", []))])
    return buf.getvalue()


def figure(records: list[dict], path: Path) -> None:
    """Share named right against visibility bin, one line per effect."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    from jointbench.identification.log.write import save_figure_atomic

    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    effects = sorted({r["effects"][0] for r in records if r["kind"] == "single"})
    for e in effects:
        pts = [(lo, hi, k / n) for lo, hi, k, n in curve(records, e) if n]
        x = [100 * (lo * hi) ** 0.5 if hi != float("inf") else 100 * lo * 1.4
             for lo, hi, _ in pts]
        ax.plot(x, [100 * s for *_, s in pts], "o-", label=e)
    ax.set_xscale("log")
    ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
    ax.set_xticks([100 * b for b in BINS])
    ax.set_xticklabels([f"{100 * b:g}" for b in BINS])
    ax.axhline(95, color="0.5", ls="--", lw=0.8)
    ax.set_xlabel("in-band visibility of the hidden effect [%] (bin centres)")
    ax.set_ylabel("named right [%]")
    ax.set_ylim(-5, 105)
    ax.set_title("diagnose: detection curve per effect (single-effect cases)")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure_atomic(fig, path)
    plt.close(fig)


def case_indices(text: str) -> list[int]:
    """--cases' value: comma-separated plan indices (>= 0), in ascending order without
    repeats; argparse.ArgumentTypeError (exit 2) naming the bad item."""
    out = set()
    for item in text.split(","):
        item = item.strip()
        if not item.isdigit():
            raise argparse.ArgumentTypeError(f"{item!r} is not a case index (an integer >= 0)")
        out.add(int(item))
    return sorted(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="battery_out", help="output folder (default battery_out)")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    ap.add_argument("--per-effect", type=int, default=8)
    ap.add_argument("--clean", type=int, default=24)
    # issue 15 asks >= 20 pairs with both visibilities >= 10 %; a drawn target of 10-40 % can
    # land under 10 % (1 of 20 did at seed 2026), so 28 leave room
    ap.add_argument("--pairs", type=int, default=28)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--duration", type=float, default=40.0, help="log length [s] (default 40)")
    ap.add_argument("--figure", default=None,
                    help="detection-curve figure (default docs/figures/detection.png; with "
                         "--cases none unless given)")
    ap.add_argument("--cases", type=case_indices, metavar="I,J,...",
                    help="run only these indices of the plan (each case drawn as in the whole "
                         "plan of these sizes and seed), e.g. to run its misses again")
    ap.add_argument("--record", metavar="PREFIX",
                    help="also write the cases as PREFIX.json (compact) and PREFIX.csv, e.g. "
                         "docs/battery_cases for the record the docs and tests read")
    ap.add_argument("--from", dest="source", metavar="CASES.json",
                    help="run nothing: the summary and figure of an earlier cases.json")
    args = ap.parse_args(argv)
    figure_path = args.figure or (None if args.cases else "docs/figures/detection.png")
    if args.source:
        records = json.loads(Path(args.source).read_text())["cases"]
        print("\n".join(summary_lines(records)))
        if figure_path:
            figure(records, Path(figure_path))
        return 0
    specs = plan(PLACES, args.per_effect, args.clean, args.pairs, args.seed)
    if args.cases:
        beyond = [i for i in args.cases if i >= len(specs)]
        if beyond:
            ap.error(f"--cases: no case {', '.join(map(str, beyond))} in a plan of "
                     f"{len(specs)} cases (0-{len(specs) - 1})")
        specs = [specs[i] for i in args.cases]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"{len(specs)} cases, {args.jobs} job(s), {args.duration:g} s logs", flush=True)
    t0 = time.perf_counter()
    records: list[dict] = []
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs, initializer=_init,
                                 initargs=(args.duration,)) as pool:
            for rec in pool.map(run_one, specs):
                records.append(rec)
                print(f"[{len(records):3d}/{len(specs)}] " + _line(rec), flush=True)
    else:
        _init(args.duration)
        for spec in specs:
            records.append(run_one(spec))
            print(f"[{len(records):3d}/{len(specs)}] " + _line(records[-1]), flush=True)
    wall = time.perf_counter() - t0
    lines = summary_lines(records)
    errors = [r for r in records if r["error"]]
    lines += [f"failed cases: {len(errors)}", f"run time: {wall:.0f} s with {args.jobs} job(s), "
              f"{os.cpu_count()} cores"]
    text = "\n".join(lines) + "\n"
    print("\n" + text)
    meta = {"seed": args.seed, "duration_s": args.duration, "jobs": args.jobs,
            "cases": args.cases or "all",
            "run_time_s": wall, "found_95_above": {
                e: found_above(records, e) for e in sorted({r["effects"][0] for r in records
                                                            if r["kind"] == "single"})}}
    atomic_write_text(out / "cases.json", json.dumps(finite_json(
        {"battery": meta, "cases": records}), indent=1, allow_nan=False) + "\n")
    atomic_write_text(out / "cases.csv", _csv(records))
    atomic_write_text(out / "summary.txt", text)
    if args.record:
        atomic_write_text(Path(args.record + ".json"), json.dumps(finite_json(
            {"battery": meta, "cases": records}), separators=(",", ":"), allow_nan=False) + "\n")
        atomic_write_text(Path(args.record + ".csv"), _csv(records))
    if figure_path:
        figure(records, Path(figure_path))
    print(f"wrote {out / 'cases.json'}, {out / 'cases.csv'}, {out / 'summary.txt'}"
          + (f", {figure_path}" if figure_path else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
