"""Accuracy of `identify` on logs of the independent (non-MuJoCo) simulator, jointbench.testing.

    .venv/bin/python benchmarks/indep_accuracy.py [--duration 60] [--seed 1] [--families a,b]

For every axis family of `jointbench.testing.FAMILIES` (JL/Jm 0.5-10, f1 4-20 Hz), with and without
velocity feedforward, linear and logarithmic sweeps (60 s, seed 1, default sensors: quantised
encoders and torque noise), the log is identified by
`jointbench.identification.identify.identify(log, model)` for the models joint-motor and
motor-only,
  (a) `defaults`: no settings, no f1 (what `jointbench identify FILE` does today);
  (b) `f1+st5`: the true first mode (`f1_hz=truth`, through `defaults.settings_for`) and the
      5-point central difference (`FilterSettings.stencil = 5`).
Printed: the errors of K, Jm and JL against the truth in %, and the filter used.

`--spread 1-6` measures instead the joint-motor model's spread over seeds (the evidence for
an estimator's efficiency, where one seed is one draw): per family and feed-forward on/off,
linear sweep (`--sweep log`: logarithmic), every seed's K, Jm, JL errors and corrected
sigma, then their mean, standard deviation and rms, for `chooser` (the chooser's band
alone), `wide` (the chooser's wn with Nd lowered until the decimated cutoff 0.8 Fs / (2 Nd)
reaches the excitation's top measured on the log, identification/band_choice.py) and
`defaults` (the pick between the two, when there is a wide band; rows say which), after
the noise-free log's (ideal sensors) errors, the reference a bias is measured from
(`--feedforward on|off|both`).

`--cross-check` adds the two simulators side by side: the paper's prototype simulated by
MuJoCo (`run_experiment("prototype")`, seed 1, 60 s) and the same axis (its truth, sensors,
gains rule, gravity and rest angle) simulated here, both identified the same way, with and
without feedforward. Nothing is asserted: this measures.
"""

from __future__ import annotations

import argparse
import math
import sys
import statistics
import time
from dataclasses import replace

from jointbench.identification.band_choice import choose_band, wide_settings
from jointbench.identification.filter_choice import choose_filter, settings_for
from jointbench.identification.estimate import NotIdentifiable
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.identify import Identification, identify
from jointbench.identification.log import Log, LogError
from jointbench.identification.output_values import pct_error
from jointbench.identification.physical import InversionError
from jointbench.testing import FAMILIES, AxisFamily, simulate

MODELS = ("joint-motor", "motor-only")
PARAMS = ("K", "Jm", "JL")


def settings_cases(log: Log) -> dict[str, FilterSettings | None]:
    """(a) the defaults (None: identify chooses), (b) the true f1 and the 5-point stencil."""
    tuned, _ = settings_for(log, log.truth()["f1_hz"])
    return {"defaults": None, "f1+st5": replace(tuned, stencil=5)}


def errors(log: Log, model: str, settings: FilterSettings | None) -> tuple[list[str], str]:
    """The K, Jm, JL errors in % as table cells, and the filter used (or the failure)."""
    try:
        result = identify(log, model, settings=settings)
    except (InversionError, NotIdentifiable, LogError, ValueError) as err:
        return ["-"] * len(PARAMS), f"failed: {err}"
    truth = log.truth()
    cells = []
    for name in PARAMS:
        err = pct_error(result.physical.get(name), truth[name])
        cells.append("nan" if err is None else f"{err:+.2f}")
    s = result.settings
    band = f", {result.band.used} band" if result.band is not None else ""
    return cells, (f"wn {s.wn:.0f} rad/s, Nd {s.Nd} (cut {s.decimated_cutoff_hz:.1f} Hz), "
                   f"stencil {s.stencil}{band}")


def band_fits(log: Log) -> dict[str, Identification]:
    """The joint-motor fit in (a') the chooser's band (`choose_filter`, what the defaults were
    before `band_choice`), (c) the wide band (`band_choice.wide_settings` from the log, when
    there is one), and (a) the defaults' pick between the two (`band_choice.choose_band`, the
    rule `identify` applies, here on the same two fits)."""
    choice = choose_filter(log)
    fits = {"chooser": identify(log, "joint-motor", settings=choice.settings,
                                first_mode=choice.first_mode)}
    candidate = wide_settings(log, choice.settings)
    wide = candidate[0]
    if wide is not None and choice.first_mode is not None and choice.first_mode.found:
        fits["wide"] = identify(log, "joint-motor", settings=wide, first_mode=choice.first_mode)
        fits["defaults"], band = choose_band(
            fits["chooser"], fits["wide"], candidate,
            lambda r: (r.physical, r.physical_sigma_corrected))
        fits["defaults"] = replace(fits["defaults"], band=band)
    return fits


def spread(families: list[str], seeds: list[int], duration: float, sweep: str = "linear",
           feedforwards: tuple[bool, ...] = (True, False)) -> None:
    """The joint-motor errors and corrected sigmas over `seeds`, and their mean, sd, rms, in
    the chooser's band, the wide band and the defaults' pick (`band_fits`); first the
    noise-free log's (ideal sensors: the same for every seed), from which a bias is told: the
    mean's distance to it against sd / sqrt(n)."""
    print(f"joint-motor spread over seeds {seeds}, {sweep} sweep: error % (corrected sigma %)")
    for name in families:
        for feedforward in feedforwards:
            clean = simulate(FAMILIES[name], 1, duration, sweep, feedforward, ideal_sensors=True)
            for label, result in band_fits(clean).items():
                truth = clean.truth()
                print(f"{name:<12} {'on' if feedforward else 'off':>3} noise-free {label:<8} "
                      + " ".join(f"{p} {100 * (result.physical[p] / truth[p] - 1):+6.2f}"
                                 for p in PARAMS), flush=True)
            rows: dict[str, list[list[float]]] = {}
            for seed in seeds:
                log = simulate(FAMILIES[name], seed, duration, sweep, feedforward)
                fits = band_fits(log)
                truth = log.truth()
                for label, result in fits.items():
                    err = [100 * (result.physical[p] / truth[p] - 1) for p in PARAMS]
                    sig = [100 * result.physical_sigma_corrected[p] / truth[p] for p in PARAMS]
                    rows.setdefault(label, []).append(err + sig)
                    pick = f" {result.band.used}" if result.band is not None else ""
                    print(f"{name:<12} {'on' if feedforward else 'off':>3} seed {seed:<3} "
                          f"{label:<8} Nd {result.settings.Nd:>2} " + " ".join(
                              f"{p} {e:+6.2f} ({sd:.2f})" for p, e, sd in zip(PARAMS, err, sig))
                          + pick, flush=True)
            for label, table in rows.items():
                cols = list(zip(*table))
                stats = " ".join(
                    f"{p} mean {statistics.fmean(cols[i]):+.2f} sd "
                    f"{statistics.stdev(cols[i]) if len(table) > 1 else math.nan:.2f} rms "
                    f"{math.sqrt(statistics.fmean(x * x for x in cols[i])):.2f} sigma "
                    f"{statistics.fmean(cols[i + len(PARAMS)]):.2f}"
                    for i, p in enumerate(PARAMS))
                print(f"{name:<12} {'on' if feedforward else 'off':>3} {label:<8} n {len(table)} "
                      f"{stats}")


def seed_list(text: str) -> list[int]:
    """'1-6' or '1,2,5' as seeds."""
    if "-" in text:
        lo, hi = (int(x) for x in text.split("-"))
        return list(range(lo, hi + 1))
    return [int(x) for x in text.split(",")]


def family_from_log(log: Log) -> AxisFamily:
    """The axis a jointbench virtual log describes: its truth_* keys, tau_max and sensors."""
    tr, meta = log.truth(), log.meta
    return AxisFamily(
        meta.get("joint", "axis"), "from a MuJoCo log", Jm=tr["Jm"], JL=tr["JL"], K=tr["K"],
        FVm=tr["FVm"], FSm=tr["FSm"], FV=tr["FV"], FS=tr["FS"],
        tau_max=float(meta["tau_max"]), torque_noise_std=float(meta["torque_noise_std"]),
        MX=tr["MX"], MY=tr["MY"],
        motor_counts_per_turn=2 * math.pi / float(meta["motor_encoder_resolution_rad"]),
        link_counts_per_turn=2 * math.pi / float(meta["link_encoder_resolution_rad"]))


def cross_check(duration: float, seed: int) -> None:
    """The prototype by MuJoCo and by indep_sim (log sweep, the bench's default), identified
    alike: the two simulators should give the same errors."""
    from jointbench.bench.sim.controller import Gains  # MuJoCo only for this section
    from jointbench.bench.sim.experiment import run_experiment

    print("\ncross-check: the paper's prototype by MuJoCo and by indep_sim")
    base = run_experiment("prototype", duration=duration, seed=seed).log
    for feedforward in (True, False):
        gains = replace(Gains.from_log(base), velocity_feedforward=feedforward)
        mj = run_experiment("prototype", duration=duration, seed=seed, gains=gains).log
        family = family_from_log(mj)
        ours = simulate(family, seed, duration, "log", feedforward,
                        center=float(mj.meta["truth_center"]))
        for source, log in (("mujoco", mj), ("indep_sim", ours)):
            for model in MODELS:
                for label, settings in settings_cases(log).items():
                    cells, used = errors(log, model, settings)
                    print(f"{'prototype':<12} {family.f1_hz:6.2f} "
                          f"{family.JL / family.Jm:6.2g} {'on' if feedforward else 'off':>3} "
                          f"{source:<10} {model:<11} {label:<8} "
                          + " ".join(f"{c:>8}" for c in cells) + f"  {used}", flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=60.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--families", default=",".join(FAMILIES))
    parser.add_argument("--cross-check", action="store_true",
                        help="also the prototype by MuJoCo and by indep_sim, side by side")
    parser.add_argument("--spread", type=seed_list, metavar="SEEDS",
                        help="joint-motor spread over these seeds ('1-6' or '1,2,5') only")
    parser.add_argument("--sweep", choices=("linear", "log"), default="linear",
                        help="the sweep of the --spread logs")
    parser.add_argument("--feedforward", choices=("on", "off", "both"), default="both",
                        help="velocity feed-forward of the --spread logs")
    args = parser.parse_args(argv)
    if args.spread:
        start = time.perf_counter()
        ff = {"on": (True,), "off": (False,), "both": (True, False)}[args.feedforward]
        spread(args.families.split(","), args.spread, args.duration, args.sweep, ff)
        print(f"wall time {time.perf_counter() - start:.0f} s")
        return 0
    header = (f"{'family':<12} {'f1 Hz':>6} {'JL/Jm':>6} {'ff':>3} {'sweep':<6} "
              f"{'model':<11} {'settings':<8} {'K %':>8} {'Jm %':>8} {'JL %':>8}  filter")
    print(f"identify on indep_sim logs: {args.duration:g} s, seed {args.seed}, 350.87 Hz, "
          "errors against truth in %")
    print(header)
    print("-" * len(header))
    start = time.perf_counter()
    for name in args.families.split(","):
        family = FAMILIES[name]
        for feedforward in (True, False):
            for sweep in ("linear", "log"):
                log = simulate(family, args.seed, args.duration, sweep, feedforward)
                run = (f"{name:<12} {family.f1_hz:6.2f} {family.JL / family.Jm:6.2g} "
                       f"{'on' if feedforward else 'off':>3} {sweep:<6}")
                for model in MODELS:
                    for label, settings in settings_cases(log).items():
                        cells, used = errors(log, model, settings)
                        print(f"{run} {model:<11} {label:<8} "
                              + " ".join(f"{c:>8}" for c in cells) + f"  {used}", flush=True)
                print(f"{'':<12} (saturated samples {log.meta['saturated_samples']}, amplitude "
                      f"reductions {log.meta['amplitude_reductions']}, substeps "
                      f"{log.meta['substeps']})")
    if args.cross_check:
        cross_check(args.duration, args.seed)
    print(f"wall time {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
