"""`jointbench tune-filter`: the optimisation of wn and Nd that the paper leaves open.

End of section 3.2: starting from eqs. (28)-(29), "wn and Ts can be improved by optimization
in order to bound the estimation error relative to a priori values". Here the a priori values
are the virtual axis' truth: a campaign of experiments (seeds) is simulated once each, every
log is identified with every (wn, Nd) of a grid (Ts is the log's, fixed by the acquisition;
Nd sets the rate of the decimated system), and the objective is the RMS over seeds and over
the chosen parameters (default K, Jm, JL) of the relative error against truth [%].

The optimum is picked on the search seeds and checked on as many fresh validation seeds,
beside the paper's choice (wn = 176 rad/s, Nd = 26) and eq. (28) with f1 = 3.9 Hz (the paper's)
and with the model's true f1; so a grid point that only fits the search noise shows up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from tabulate import tabulate

from jointbench.bench.sim.axes import build_experiment_model
from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification import output_values as output
from jointbench.identification.filter_choice import PAPER_F1, PAPER_ND, PAPER_RATE, PAPER_WN, nd_from_f1
from jointbench.identification.design import design_bandpass
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.first_mode import measure_first_mode
from jointbench.identification.identify import identify
from jointbench.identification.parameters import STIFFNESS_AND_INERTIAS

PAPER = (PAPER_WN, PAPER_ND)
PAPER_F1_HZ = PAPER_F1


@dataclass(frozen=True)
class TuneTask:
    """Simulate one experiment (sim seed `seed`) and identify it with every (wn, Nd) pair."""

    model: str
    joint: str | None
    duration: float
    seed: int
    pairs: tuple[tuple[float, int], ...]
    id_model: str = "joint-motor"
    params: tuple[str, ...] = STIFFNESS_AND_INERTIAS


def evaluate(task: TuneTask) -> np.ndarray:
    """Relative errors [%] against truth, shape (pairs, params); NaN where the pair fails.
    Runs in a worker (top-level, plain data)."""
    out = np.full((len(task.pairs), len(task.params)), np.nan)
    try:
        log = run_experiment(task.model, task.joint, duration=task.duration, seed=task.seed).log
    except Exception:  # noqa: BLE001 - a failed experiment contributes NaN
        return out
    truth = log.truth()
    mode = measure_first_mode(log)   # once per log, not once per pair (identify would)
    for i, (wn, Nd) in enumerate(task.pairs):
        try:
            ident = identify(log, task.id_model,
                             FilterSettings(wn=float(wn), m=4, Nd=int(Nd), ts=log.ts),
                             first_mode=mode)
        except Exception:  # noqa: BLE001 - e.g. wn beyond Nyquist, too few samples
            continue
        for j, p in enumerate(task.params):
            x = ident.physical.get(p, math.nan)
            out[i, j] = 100.0 * (x - truth[p]) / abs(truth[p])
    return out


def rms(errors: np.ndarray) -> np.ndarray:
    """RMS over seeds (axis 0) and parameters (last axis) of errors (seeds, pairs, params);
    NaN for a pair that failed on any seed."""
    return np.sqrt(np.mean(errors ** 2, axis=(0, 2)))


@dataclass(frozen=True)
class Candidate:
    label: str
    wn: float
    Nd: int
    search_rms_pct: float
    validation_rms_pct: float
    validation_per_param: dict[str, float]
    note: str = ""


@dataclass(frozen=True)
class TuneResult:
    model: str
    joint: str
    f1_hz: float
    id_model: str
    params: tuple[str, ...]
    seeds: int
    duration: float
    wn_grid: tuple[float, ...]
    Nd_grid: tuple[int, ...]
    objective: np.ndarray           # (wn, Nd) RMS relative error on the search seeds [%]
    candidates: tuple[Candidate, ...] = field(default_factory=tuple)

    def as_dict(self) -> dict:
        return {"model": self.model, "joint": self.joint, "f1_hz": self.f1_hz,
                "id_model": self.id_model, "params": list(self.params), "seeds": self.seeds,
                "duration_s": self.duration, "wn_grid": list(self.wn_grid),
                "Nd_grid": list(self.Nd_grid),
                "objective_rms_pct": [[None if not math.isfinite(v) else float(v) for v in r]
                                      for r in self.objective],
                "candidates": [{"label": c.label, "wn_rad_s": c.wn, "Nd": c.Nd,
                                "search_rms_pct": c.search_rms_pct,
                                "validation_rms_pct": c.validation_rms_pct,
                                "validation_rms_pct_per_param": c.validation_per_param,
                                "note": c.note} for c in self.candidates]}


def _seeds(campaign_seed: int, first: int, n: int) -> list[int]:
    return [int(np.random.SeedSequence([campaign_seed, j]).generate_state(1)[0])
            for j in range(first, first + n)]


def _run(executor, tasks: list[TuneTask], progress) -> np.ndarray:
    """Errors (seeds, pairs, params), in the order of `tasks` whatever order they finish in."""
    results: dict[int, np.ndarray] = {}
    for done in executor.map_unordered(evaluate, tasks):
        idx = tasks.index(done.item)
        results[idx] = done.value if done.error is None else np.full(
            (len(done.item.pairs), len(done.item.params)), np.nan)
        if progress is not None:
            progress(done.error is None)
    return np.stack([results[i] for i in range(len(tasks))])


def tune_filter(model: str, joint: str | None, wn_grid: tuple[float, ...],
                Nd_grid: tuple[int, ...], seeds: int, executor, duration: float = 60.0,
                seed: int = 0, id_model: str = "joint-motor",
                params: tuple[str, ...] = STIFFNESS_AND_INERTIAS, progress=None) -> TuneResult:
    """Grid search of (wn, Nd) on `seeds` experiments, then the optimum and the reference
    settings on `seeds` fresh ones."""
    exp = build_experiment_model(model, joint)
    rate = PAPER_RATE
    f1 = exp.truth.f1_hz

    def nd_rule(f1_hz: float) -> int:
        return nd_from_f1(rate, f1_hz)

    d_paper = design_bandpass(PAPER_F1_HZ, nd=2, m=4)
    d_true = design_bandpass(f1, nd=2, m=4)
    refs = [("paper section 4", PAPER[0], PAPER[1], "decimated cutoff 5.40 Hz"),
            (f"eq. (28), paper's f1 = {PAPER_F1_HZ:g} Hz", round(d_paper.wn_rad_s, 2), PAPER[1],
             f"eq. (29): Fs >= {d_paper.fs_hz:.1f} Hz (Ts = {1e3 * d_paper.ts_s:.3f} ms)"),
            (f"eq. (28), true f1 = {f1:.3f} Hz", round(d_true.wn_rad_s, 2), nd_rule(f1),
             f"eq. (29): Fs >= {d_true.fs_hz:.1f} Hz; Nd by the 5.4 / 3.9 cutoff rule")]
    grid = tuple((float(w), int(n)) for w in wn_grid for n in Nd_grid)
    pairs = grid + tuple((w, n) for _, w, n, _ in refs)
    search = [TuneTask(model, joint, duration, s, pairs, id_model, params)
              for s in _seeds(seed, 0, seeds)]
    err = _run(executor, search, progress)
    s_rms = rms(err)
    obj = s_rms[:len(grid)].reshape(len(wn_grid), len(Nd_grid))
    if not np.isfinite(obj).any():
        raise ValueError("no (wn, Nd) pair of the grid identified every search experiment")
    i, j = np.unravel_index(np.nanargmin(obj), obj.shape)
    refs = [("optimum (search seeds)", float(wn_grid[i]), int(Nd_grid[j]), "")] + refs
    ref_search = [float(obj[i, j])] + [float(v) for v in s_rms[len(grid):]]
    val_pairs = tuple((w, n) for _, w, n, _ in refs)
    val = _run(executor, [TuneTask(model, joint, duration, s, val_pairs, id_model, params)
                          for s in _seeds(seed, seeds, seeds)], progress)
    v_rms = rms(val)
    cands = []
    for k, (label, w, n, note) in enumerate(refs):
        per = {p: output.rms(val[:, k, q]) for q, p in enumerate(params)}
        cands.append(Candidate(label, w, n, ref_search[k], float(v_rms[k]), per, note))
    return TuneResult(model=model, joint=exp.axis.name, f1_hz=f1, id_model=id_model,
                      params=params, seeds=seeds, duration=duration, wn_grid=tuple(wn_grid),
                      Nd_grid=tuple(Nd_grid), objective=obj, candidates=tuple(cands))


def result_text(r: TuneResult) -> str:
    lines = [f"model {r.model} {r.joint} (true f1 = {r.f1_hz:.3f} Hz), {r.id_model} model, "
             f"{r.seeds} search + {r.seeds} validation experiments of {r.duration:g} s",
             f"objective: RMS over experiments and {', '.join(r.params)} of the relative error "
             "against truth [%]",
             "", "search grid (rows wn [rad/s], columns Nd):"]
    best = np.nanmin(r.objective)
    grid = [[f"{w:.1f}", *(("-" if not math.isfinite(v) else f"{v:.3f}") + ("*" if v == best
                                                                            else "")
                            for v in row)] for w, row in zip(r.wn_grid, r.objective)]
    lines += tabulate(grid, ["wn", *(str(n) for n in r.Nd_grid)], tablefmt="plain",
                      colalign=("right", *("left",) * len(r.Nd_grid)),
                      disable_numparse=True).splitlines()
    rows = [[c.label, f"{c.wn:.2f}", str(c.Nd), f"{c.search_rms_pct:.4f}",
             f"{c.validation_rms_pct:.4f}", *(f"{c.validation_per_param[p]:.4f}" for p in r.params),
             c.note] for c in r.candidates]
    lines += ["", *tabulate(rows, ["setting", "wn", "Nd", "search %", "valid. %",
                                   *(f"{p} %" for p in r.params), "note"], tablefmt="plain",
                            colalign=("left", *("right",) * (4 + len(r.params)), "left"),
                            disable_numparse=True).splitlines()]
    return "\n".join(lines)


def geometric_wn(lo: float, hi: float, n: int) -> tuple[float, ...]:
    """n values of wn [rad/s] from lo to hi, geometric, rounded to 0.1 rad/s. ValueError from
    numpy for a range it cannot space (e.g. lo = 0)."""
    return tuple(float(round(v, 1)) for v in np.geomspace(lo, hi, n))


def linear_nd(lo: int, hi: int, n: int) -> tuple[int, ...]:
    """Up to n decimation factors from lo to hi, linear, rounded, unique and sorted."""
    return tuple(sorted({int(round(v)) for v in np.linspace(lo, hi, n)}))
