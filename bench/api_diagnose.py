"""`jointbench.diagnose`: what the simulation gets wrong on a log, with every option of
`jointbench diagnose` (cross-validation, the user's MJCF, the output folder), as one
DiagnosisResult (bench.results.diagnose)."""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import Callable

from jointbench.bench.api_args import check
from jointbench.bench.api_log import LogLike, as_log, log_name
from jointbench.bench.results.diagnose import DiagnosisResult
from jointbench.bench.results.diagnose_runs import RunsDiagnosis
from jointbench.identification.log import Log


def diagnose(log: LogLike | list[LogLike] | tuple[LogLike, ...], forward: bool = True,
             progress: Callable[[str], None] | None = None, *,
             model: str | os.PathLike | None = None, joint: str | None = None,
             config: dict[str, float] | None = None, validate: LogLike | None = None,
             disturbance_column: str | None = None, disturbance_gain: float = 1.0,
             disturbance_at: str = "link", out: str | os.PathLike | None = None,
             warn: Callable[[str], None] | None = None) -> DiagnosisResult | RunsDiagnosis:
    """What the simulation gets wrong on a log (`jointbench diagnose`).

    Against the log's own nominal model: the candidate effects, the named causes, the
    extended model and its gain in the inverse and (with `forward`) the closed-loop forward
    views. With `model`, against the user's MJCF: its parameter errors, the corrected and
    extended models.

    Parameters
    ----------
    log : Log, str or PathLike, or a list or tuple of them
        The log, or its file (docs/log-format.md). A list: several runs of one axis, each
        diagnosed and cross-validated on the next (bench.results.diagnose_runs); a cause is
        named for the axis only where every run names it; the answer is a RunsDiagnosis
        (only `forward`, `progress` and `warn` apply).
    forward : bool
        Run the closed-loop replays (forward view); False: `--no-forward`.
    progress : callable, optional
        Called with one line per step.
    model : str or PathLike, optional
        An MJCF (prototype, arm6 or a file following the axis convention) to compare with.
    joint : str, optional
        With `model`: the axis the log moves (default: the log's joint metadata).
    config : dict of str to float, optional
        With `model`: locked angles of the other axes [rad] (default: the log's).
    validate : Log, str or PathLike, optional
        Another log: cross-validation of the models identified on `log`.
    disturbance_column : str, optional
        A column of the `validate` log applied as a disturbance in its replay.
    disturbance_gain : float
        Scale of the disturbance column (e.g. N/V).
    disturbance_at : {"link", "motor"}
        Where the disturbance acts.
    out : str or PathLike, optional
        Folder for figures, report.md, diagnosis.json and the models; checked before any
        computation, written all or nothing.
    warn : callable, optional
        Called with each warning on the log (units, clipped torque).

    Returns
    -------
    DiagnosisResult or RunsDiagnosis
        `named_cause`, `warnings`, `files`; `table()`, `to_json()`, `write()`. For a list
        of logs a RunsDiagnosis: `results`, `supported`, `unsupported`; `table()`,
        `to_json()`.

    Raises
    ------
    LogError
        An unusable log, or no such disturbance column.
    ModelStructureError
        `model` does not follow the axis convention.
    ValueError
        A bad option (LogError and ModelStructureError are ValueErrors too).

    Examples
    --------
    >>> import jointbench as jb
    >>> d = jb.diagnose(jb.simulate(seed=1, effect="backlash=0.002"))   # doctest: +SKIP
    >>> d.named_cause                                                   # doctest: +SKIP
    """
    if isinstance(log, (list, tuple)):
        if len(log) < 2:
            raise ValueError("diagnose over runs needs at least two logs")
        if any(x is not None for x in (model, joint, config, validate, disturbance_column,
                                       out)):
            raise ValueError("several runs: each is cross-validated on the next; --model, "
                             "--validate, --disturbance-column and --out apply to one log")
        loaded = [as_log(x) for x in log]
        names = [log_name(x, lg) for x, lg in zip(log, loaded)]
        n = len(loaded)
        results = tuple(replace(diagnose(lg, forward, progress, validate=loaded[(i + 1) % n],
                                         warn=warn),
                                source=names[i], validate_source=names[(i + 1) % n])
                        for i, lg in enumerate(loaded))
        return RunsDiagnosis(results, tuple(names))
    check("diagnose", locals())
    from jointbench.identification.log import LogError
    from jointbench.identification.saturation import clipping_warnings

    say = progress or (lambda msg: None)
    loaded = as_log(log)
    source = log_name(log, loaded)
    if model is not None:
        # against a model the parameters are identify's, which refuses over a third clipped
        # (identification.saturation): before any computation. Without one, diagnose states
        # itself what a clipped log can say (bench.analysis.diagnose.clipped).
        clipping_warnings(loaded)
    folder = None if out is None else Path(out)
    if folder is not None:
        if model is not None:
            from jointbench.bench.analysis.diagnose.model_report import output_folder
        else:
            from jointbench.bench.analysis.diagnose.report import output_folder
        output_folder(folder)
    other = None if validate is None else as_log(validate)
    if other is not None and not isinstance(log, Log) and not isinstance(validate, Log) \
            and Path(validate).resolve() == Path(log).resolve():
        raise ValueError("--validate must name another log than FILE (cross-validation)")
    if model is not None:
        from jointbench.bench.analysis.diagnose.against_model import diagnose_against_model
        md = diagnose_against_model(loaded, model, joint, config or {}, forward=forward,
                                    validate=other, progress=say)
        result = DiagnosisResult(md, source=source)
        return result if folder is None else result.write(folder, say)
    from jointbench.bench.analysis.diagnose import cross_validate
    from jointbench.bench.analysis.diagnose import diagnose as diagnose_log
    from jointbench.bench.analysis.diagnose.run import diagnosis_settings

    dist = None
    if disturbance_column is not None:
        if other is None:
            raise ValueError("--disturbance-column applies to the --validate log")
        if disturbance_column not in other.extra:
            raise LogError(f"no column '{disturbance_column}' (columns: "
                           f"{', '.join(['t', 'q_m', 'tau_m', *other.extra])})", other.path,
                           column=disturbance_column)
        dist = disturbance_gain * other.extra[disturbance_column]
    d = diagnose_log(loaded, forward=forward, progress=say)
    for text in d.warnings:   # units, clipped torque (left out of the fits)
        (warn or (lambda text: None))(text)
    xval, validate_source = None, None
    if other is not None:
        validate_source = log_name(validate, other)
        say(f"cross-validation on {validate_source} (its own band)")
        xval = cross_validate(d, other, dist, disturbance_at, diagnosis_settings(other)[0])
    result = DiagnosisResult(d, xval, source, validate_source)
    return result if folder is None else result.write(folder, say)
