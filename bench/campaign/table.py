"""A campaign's table (CSV): `# jointbench-campaign: 1`, `# spec: {json}`, a header, then one row
per run: run, repeat, seed, status (ok / failed), reason, the run's settings, the truth and,
per identification model, each parameter's estimate, the paper's sigma and the corrected sigma
(`identification.uncertainty`, when the LS result carries one).

Rows are appended as the runs finish, each with one write, flush and fsync: a campaign killed
part way is resumed by running the same command again; the rows present are kept, a trailing
partial line is dropped and only the missing and the failed runs are done (a failed row is
replaced by its new outcome). When all runs are in, the table is rewritten sorted by run (atomically): the same spec gives the same file, byte for byte,
whatever the engine.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path
from typing import Sequence

from jointbench.bench.campaign.settings import CampaignError
from jointbench.bench.campaign.spec import CampaignSpec, spec_difference, spec_from_json
from jointbench.identification.log import atomic_write_text

TABLE_MAGIC = "# jointbench-campaign: 1"


def _csv_line(values: Sequence[str]) -> str:
    """One CSV record, newline-terminated (the csv module's quoting)."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(values)
    return buf.getvalue()


class CampaignTable:
    """The CSV table of a campaign, opened for appending; resumes an existing one.

    `rows` maps run index -> row (dict of strings) for every run recorded so far.
    """

    def __init__(self, path: Path, spec: CampaignSpec):
        self.path = Path(path)
        self.spec = spec
        self.columns = spec.columns()
        self.rows: dict[int, dict[str, str]] = {}
        self.dropped_partial = False
        if self.path.exists():
            self._resume()
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            head = TABLE_MAGIC + "\n" + "# spec: " + spec.to_json() + "\n" + _csv_line(self.columns)
            atomic_write_text(self.path, head)
        self._handle = open(self.path, "a", encoding="utf-8", newline="")

    def _preamble(self) -> list[str]:
        return [TABLE_MAGIC, "# spec: " + self.spec.to_json(), _csv_line(self.columns).rstrip("\n")]

    def _resume(self) -> None:
        if self.path.is_dir():
            raise CampaignError(f"{self.path}: is a directory")
        raw = self.path.read_bytes()
        text = raw.decode("utf-8", errors="replace")
        complete = text[: text.rfind("\n") + 1]
        if complete != text:
            # A run killed in the middle of a write: drop the partial line, keep the rest.
            self.dropped_partial = True
            with open(self.path, "r+b") as f:
                f.truncate(len(complete.encode("utf-8")))
                f.flush()
                os.fsync(f.fileno())
        lines = complete.split("\n")[:-1]
        expected = self._preamble()
        for lineno, (have, want) in enumerate(zip(lines, expected), start=1):
            if have != want:
                what = {1: "is not a jointbench campaign table (first line)",
                        2: spec_difference(have, self.spec),
                        3: "has a different header"}[lineno]
                raise CampaignError(f"{self.path}:{lineno}: {what}")
        if len(lines) < len(expected):
            raise CampaignError(f"{self.path}: incomplete header ({len(lines)} lines); "
                                "delete the file to start afresh")
        for lineno, values in enumerate(csv.reader(lines[len(expected):]),
                                        start=len(expected) + 1):
            if len(values) != len(self.columns):
                raise CampaignError(f"{self.path}:{lineno}: {len(values)} columns, "
                                    f"expected {len(self.columns)}")
            try:
                index = int(values[0])
            except ValueError:
                raise CampaignError(f"{self.path}:{lineno}: column 'run': not an integer: "
                                    f"{values[0]!r}") from None
            if not 0 <= index < self.spec.total:
                raise CampaignError(f"{self.path}:{lineno}: run {index} outside this campaign "
                                    f"(0-{self.spec.total - 1})")
            row = dict(zip(self.columns, values))
            if row["status"] != "failed":  # a failed run is run again on resume
                self.rows.setdefault(index, row)

    def append(self, row: dict[str, str]) -> None:
        """One row, one write, then flush and fsync: a kill leaves at most a partial last line."""
        index = int(row["run"])
        if index in self.rows:
            return
        self._handle.write(_csv_line([row.get(c, "") for c in self.columns]))
        self._handle.flush()
        os.fsync(self._handle.fileno())
        self.rows[index] = {c: row.get(c, "") for c in self.columns}

    def close(self) -> None:
        if not self._handle.closed:
            self._handle.close()

    def finalize(self) -> None:
        """Rewrite the complete table sorted by run (atomically)."""
        self.close()
        body = "".join(_csv_line([self.rows[i][c] for c in self.columns])
                       for i in sorted(self.rows))
        atomic_write_text(self.path, "\n".join(self._preamble()) + "\n" + body)


def read_table(path: str | Path) -> tuple[CampaignSpec, list[dict[str, str]]]:
    """The spec and rows (sorted by run) of a campaign table."""
    path = Path(path)
    lines = path.read_text(encoding="utf-8").split("\n")
    if not lines or lines[0] != TABLE_MAGIC or len(lines) < 3 or not lines[1].startswith("# spec: "):
        raise CampaignError(f"{path}:1: not a jointbench campaign table")
    spec = spec_from_json(lines[1][len("# spec: "):])
    reader = csv.DictReader([ln for ln in lines[2:] if ln])
    rows = sorted(reader, key=lambda r: int(r["run"]))
    return spec, rows
