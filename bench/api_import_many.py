"""Several measured files imported in one call (`jointbench import A.mat B.mat --out DIR`,
`jointbench.import_log([a, b], out=DIR)`): every file is converted before any log is
written, so that a file that cannot be converted leaves nothing half-written; each log is
then written atomically to DIR/STEM.csv."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable

from jointbench.bench.results import ImportReport
from jointbench.identification.log import write_log


def import_many(import_one: Callable[..., ImportReport], files: list,
                out: str | os.PathLike | None, **options) -> list[ImportReport]:
    """`import_one(file, None, **options)` for each file (the errors name their file), then
    the logs written to `out`/STEM.csv (a folder, created; None: nothing written). ValueError
    for no file, two files of one stem, an `out` that is a file, or a target that is an input
    or a file jointbench did not write (bench.output_files.check_file), all before any reading."""
    from jointbench.bench.output_files import check_file

    if not files:
        raise ValueError("import: no file given")
    targets: list[Path | None] = [None] * len(files)
    if out is not None:
        folder = Path(out)
        if folder.exists() and not folder.is_dir():
            raise ValueError(f"--out {folder}: several files need a folder, this is a file")
        stems = [Path(f).stem for f in files]
        dup = sorted({s for s in stems if stems.count(s) > 1})
        if dup:
            raise ValueError(f"two inputs would both write {dup[0]}.csv in {folder}")
        targets = [folder / f"{s}.csv" for s in stems]
        inputs = {Path(f).resolve() for f in files if Path(f).exists()}
        if not folder.exists() and not folder.resolve().parent.is_dir():
            raise ValueError(f"--out {folder}: its parent folder does not exist")
        for t in targets:
            if t.exists() and t.resolve() in inputs:
                raise ValueError(f"--out {t}: is an input file; choose another folder")
            if folder.exists():
                check_file(t, "--out")
    reports = [import_one(f, None, **options) for f in files]   # all converted, none written
    if out is not None:
        Path(out).mkdir(parents=True, exist_ok=True)
        for i, (rep, target) in enumerate(zip(reports, targets)):
            write_log(rep.log, target)
            reports[i] = ImportReport(rep.result, target)
    return reports
