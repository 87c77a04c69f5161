"""The public Python API, for a notebook or a script (re-exported by `import jointbench`):

    import jointbench as jb
    log = jb.simulate("prototype", seed=1)     # a virtual experiment's Log
    fit = jb.identify(log)                     # fit.table(), fit.to_json(), fit.plot()
    fit.parameters["K"]                        # Estimate(value, sigma, sigma_hac, unit)
    d = jb.diagnose(log); d.write("out/")
    c = jb.campaign(runs=20, methods=["mymodule:estimate"], require="K.abs_bias_pct<1")
    print(c.table()); c.passed                 # every method side by side, the gates

Every function takes the options of the `jointbench` command of the same name, and returns a
frozen dataclass (bench.results) whose `table()` and `to_json()` are what that command prints:
the command line parses its arguments, calls these and prints the result.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Sequence

from jointbench.bench.api_campaign import campaign, survey
from jointbench.bench.api_diagnose import diagnose
from jointbench.bench.api_identify import identify
from jointbench.bench.effects import HiddenEffect, parse_effects
from jointbench.bench.results import (CampaignReport, DiagnosisResult, Estimate, Fit,
                                      ImportReport, RunsDiagnosis, RunsFit,
                                      SurveyResult)
from jointbench.bench.sim.experiment import run_experiment
from jointbench.bench.api_args import check
from jointbench.bench.output_files import write_log
from jointbench.identification.log import Log, read_log

__all__ = ["Estimate", "Fit", "DiagnosisResult", "CampaignReport", "SurveyResult",
           "ImportReport", "Log", "simulate", "identify", "diagnose", "campaign", "survey",
           "import_log", "read_log", "write_log", "RunsFit", "RunsDiagnosis"]


def simulate(model: str | os.PathLike = "prototype", joint: str | None = None, *,
             duration: float = 60.0, seed: int = 0, effect: str | HiddenEffect | None = None,
             **options) -> Log:
    """One virtual closed-loop chirp experiment, as a log (`jointbench simulate`).

    Parameters
    ----------
    model : str or PathLike
        prototype, arm6 or an MJCF file following the axis convention.
    joint : str, optional
        The axis to move, by name or index from 1 (default: the first).
    duration : float
        Length of the experiment [s].
    seed : int
        Noise seed: same seed, same log, bit for bit.
    effect : str or HiddenEffect, optional
        A hidden effect, e.g. "backlash=0.002", or several, "offset=5,backlash=0.002"
        (docs/effects.md).
    **options
        The other options of `bench.sim.experiment.run_experiment` (amplitude, config, lock,
        sensors, sample_rate_hz, ...).

    Returns
    -------
    Log
        The experiment's log (docs/log-format.md); its ground truth in `log.truth()`.

    Raises
    ------
    SimulationError
        The closed loop diverged.
    ModelStructureError
        The model does not follow the axis convention.
    ValueError
        A bad option or effect.

    Examples
    --------
    >>> import jointbench as jb
    >>> log = jb.simulate("prototype", seed=1, duration=10)   # doctest: +SKIP
    """
    check("simulate", locals())
    if isinstance(effect, str):
        effect = parse_effects(effect)   # one or several: "offset=5,backlash=0.002"
    return run_experiment(model, joint, duration=duration, seed=seed, effect=effect,
                          **options).log


def _position_loop_checks(result):
    """The import's replay check for a position loop's metadata (docs/controller.md section
    3), which the conversion's check, written for the PI cascade's kp, kv, ki, does not know."""
    from jointbench.bench.sim.controller import controller_from_log, describe, has_controller

    log = result.log
    if log.q_ref is None or "controller" not in log.meta or not has_controller(log):
        return result
    ok = f"replayable: q_ref and the controller ({describe(controller_from_log(log))})"
    checks = tuple(ok if c.startswith("not replayable") else c for c in result.checks)
    return dataclasses.replace(result, checks=checks)


def import_log(file: str | os.PathLike | list | tuple, out: str | os.PathLike | None = None, *,
               columns: dict[str, str] | None = None, units: dict[str, str] | None = None,
               gear_ratio: float | None = None,
               motor_side: Sequence[str] = ("q_m", "tau_m", "q_ref"),
               counts_per_turn: float | None = None,
               link_counts_per_turn: float | None = None,
               torque_constant: float | None = None, rate_hz: float | None = None,
               meta: dict[str, str] | None = None, gains_side: str = "joint",
               delimiter: str | None = None,
               drive: dict[str, float] | None = None) -> ImportReport | list[ImportReport]:
    """Convert a measured file into a jointbench log (`jointbench import`).

    Parameters
    ----------
    file : str or PathLike, or a list of them
        The raw CSV (a header row, then one row of numbers per sample) or MATLAB .mat file
        (v5 through scipy; v7.3 needs the extra [mat73]; identification/raw_sources.py).
        A list: several files converted with the same options, all before any is written
        (bench/api_import_many.py); `out` is then a folder, each log OUT/STEM.csv, and the
        answer a list of ImportReport.
    out : str or PathLike, optional
        The log file to write (never the input; checked before reading); not written when
        None.
    columns : dict of str to str, optional
        Log column -> raw column or an expression of raw columns, e.g. {"t": "time_ms",
        "q": "theta-alpha", "tau_m": "-cur"} (default: the raw columns already named t, q_m,
        q, tau_m, q_ref). Raw columns the map does not name are kept as extra columns.
    units : dict of str to str, optional
        Log column -> unit of the raw column (s|ms|us; rad|deg|rev|counts|m|mm|um;
        Nm|N|A|V).
    gear_ratio : float, optional
        Refers the `motor_side` columns to the joint side (angles / N, torque x N).
    motor_side : sequence of str
        The columns measured on the motor shaft.
    counts_per_turn : float, optional
        Motor encoder counts per turn of the motor shaft.
    link_counts_per_turn : float, optional
        Link encoder counts per turn.
    torque_constant : float, optional
        N m/A (or per V) for a torque column in A or V.
    rate_hz : float, optional
        The drive's fixed sample rate: t rebuilt as k / rate.
    meta : dict of str to str, optional
        Metadata keys of docs/log-format.md section 1.3.
    gains_side : {"joint", "motor"}
        "motor": kv, ki, tau_max in `meta` are motor-side (x N^2, N^2, N).
    delimiter : str, optional
        Column separator (default: found from the header).
    drive : dict of str to float, optional
        A voltage drive's constants {"Kt", "R", "Ke", "eta"} (identification/voltage_drive.py)
        for a torque column in V: tau_m = eta N Kt / R u, and the back-EMF damping
        eta N^2 Kt Ke / R written as `back_emf_damping` (it is part of FVm).

    Returns
    -------
    ImportReport or list of ImportReport
        `log`, `warnings`; `table()`, `to_json()` (a list for a list of files).

    Raises
    ------
    LogError
        What cannot be converted, naming the file, line and column (a ValueError).
    ValueError
        `out` is the input file or a file jointbench did not write.
    """
    if isinstance(file, (list, tuple)):     # several files: bench.api_import_many
        from jointbench.bench.api_import_many import import_many
        return import_many(import_log, list(file), out, columns=columns, units=units,
                           gear_ratio=gear_ratio, motor_side=motor_side,
                           counts_per_turn=counts_per_turn,
                           link_counts_per_turn=link_counts_per_turn,
                           torque_constant=torque_constant, rate_hz=rate_hz, meta=meta,
                           gains_side=gains_side, delimiter=delimiter, drive=drive)
    # argument checks: here, before any reading
    from jointbench.bench.cli.import_memory import read_within_memory
    from jointbench.bench.output_files import check_file
    from jointbench.identification.log.raw import LOG_COLUMNS, ImportSpec, convert
    from jointbench.identification.raw_sources import (MAT_SUFFIX, keep_unmapped, read_source,
                                                       with_expressions)

    src = Path(file)
    target = None if out is None else Path(out)
    if target is not None:
        if src.exists() and target.exists() and target.resolve() == src.resolve():
            raise ValueError(f"--out {target}: is the input file; choose another name")
        check_file(target, "--out")
    if src.suffix.lower() == MAT_SUFFIX:
        raw, skipped = read_source(src, delimiter)     # a .mat file: its vectors
    else:
        raw, skipped = read_within_memory(src, delimiter), {}
    if columns is None:
        columns = {c: c for c in LOG_COLUMNS if c in raw.header}
    raw, columns = with_expressions(raw, columns, skipped)   # q=theta-alpha, tau_m=-cur
    meta = dict(meta or {})
    if drive is not None:     # a voltage drive: its constants make the torque constant per V
        from jointbench.identification.log import LogError
        from jointbench.identification.voltage_drive import META_KEY, VoltageDrive
        vd = VoltageDrive.parse(drive, str(src))
        if (units or {}).get("tau_m") != "V" or torque_constant is not None:
            raise LogError("--drive gives the torque per volt: the torque column needs "
                           "--units tau_m=V and no --torque-constant", str(src))
        torque_constant = vd.volt_to_torque()
        N = gear_ratio if gear_ratio is not None and "tau_m" in motor_side else 1.0
        meta.setdefault(META_KEY, f"{vd.back_emf_damping(N):.10g}")
    spec = ImportSpec(columns=dict(columns), units=dict(units or {}), gear_ratio=gear_ratio,
                      motor_side=tuple(motor_side), counts_per_turn=counts_per_turn,
                      link_counts_per_turn=link_counts_per_turn,
                      torque_constant=torque_constant, rate_hz=rate_hz, meta=meta,
                      gains_side=gains_side)
    result = keep_unmapped(convert(raw, spec), raw, columns)
    if drive is not None:
        result = dataclasses.replace(result, steps=result.steps + (
            f"voltage drive (Kt {vd.Kt:g}, R {vd.R:g}, Ke {vd.Ke:g}, eta {vd.eta:g}): tau_m = "
            f"eta N Kt / R u; the back-EMF damping eta N^2 Kt Ke / R = {meta[META_KEY]} N m s/rad "
            f"is not removed from the torque: it is part of FVm ({META_KEY})",))
    if src.suffix.lower() == ".mat":     # the CSV reader's first step names a delimiter
        result = dataclasses.replace(result, steps=(
            f"read {src}: MATLAB .mat, {len(raw.data)} samples, variables "
            f"{', '.join(raw.header)}",) + result.steps[1:])
    result = _position_loop_checks(result)
    if skipped:
        result = dataclasses.replace(result, steps=result.steps + (
            "left out of the .mat file: " + "; ".join(f"{k} ({v})" for k, v in skipped.items()),))
    if target is not None:
        write_log(result.log, target)
    return ImportReport(result, target)
