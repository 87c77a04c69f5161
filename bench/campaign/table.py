"""A campaign's table (CSV): `# jointbench-campaign: 2`, `# spec: {json}`, a header, then one row
per run: run, repeat, seed, status (ok / failed), reason, the run's settings, the truth and,
per identification model, each parameter's estimate, the paper's sigma and the corrected sigma
(`identification.uncertainty`, when the LS result carries one), and last the row's `digest`.

Rows are appended as the runs finish, each with one write, flush and fsync: a campaign killed
part way is resumed by running the same command again; the rows present are kept, a trailing
partial line is dropped and only the missing and the failed runs are done (a failed row is
replaced by its new outcome). When all runs are in, the table is rewritten sorted by run
(atomically): the same spec gives the same file, byte for byte, whatever the engine.

A resumed row is trusted only when it is what the campaign wrote: its `digest` (the first 16
hex digits of the SHA-256 of the spec line and the row's other cells) matches, its status is
one the campaign writes, every number cell holds a finite number, `nan` or nothing, and (with
`expected`, bench.campaign.run.expected_cells) its settings and truth are the spec's for that
run. Any other row refuses the resume (CampaignError naming the line, the run and the column):
a hand edit cannot slip into the statistics. The digest guards against slips and edits, not
against someone who recomputes it.
"""

from __future__ import annotations

import csv
import hashlib
import io
import os
import re
from pathlib import Path
from typing import Callable, Sequence

from jointbench.bench.campaign.settings import CampaignError
from jointbench.bench.campaign.spec import CampaignSpec, spec_difference, spec_from_json
from jointbench.identification.log import atomic_write_text

TABLE_MAGIC = "# jointbench-campaign: 2"
EARLIER_MAGIC = ("# jointbench-campaign: 1",)   # tables without row digests
DIGEST = "digest"
STATUSES = ("ok", "failed")
# The text of a number cell as the campaign writes it (run._fmt: an integer or a float's repr).
_NUMBER = re.compile(r"-?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\Z")
_TEXT = {"status", "reason", "model", "joint", "effect", DIGEST}


def _csv_line(values: Sequence[str]) -> str:
    """One CSV record, newline-terminated (the csv module's quoting)."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(values)
    return buf.getvalue()


def row_digest(spec: CampaignSpec, values: Sequence[str]) -> str:
    """The digest of a row: SHA-256 of the spec line and the row's cells (its digest cell
    aside), first 16 hex digits."""
    text = "# spec: " + spec.to_json() + "\n" + _csv_line(values)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def _is_text(column: str) -> bool:
    return column in _TEXT or column.endswith((".status", ".reason"))


class CampaignTable:
    """The CSV table of a campaign, opened for appending; resumes an existing one.

    `rows` maps run index -> row (dict of strings) for every run recorded so far.
    """

    def __init__(self, path: Path, spec: CampaignSpec,
                 expected: Callable[[int], dict[str, str]] | None = None):
        self.path = Path(path)
        self.spec = spec
        self.expected = expected
        self.columns = spec.columns() + [DIGEST]
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
                if lineno == 1 and have in EARLIER_MAGIC:
                    raise CampaignError(f"{self.path}:1: a campaign table of an earlier "
                                        "format (rows without a digest): it cannot be "
                                        "resumed; move it aside or choose another --out")
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
            if row["status"] not in STATUSES:
                self._refuse(lineno, index, "status", f"{row['status']!r} is not a status the "
                             f"campaign writes ({' or '.join(STATUSES)})")
            if row["status"] != "failed":  # a failed run is run again on resume
                if index not in self.rows:
                    self._check_row(lineno, index, row, values)
                self.rows.setdefault(index, row)

    def _refuse(self, lineno: int, index: int, column: str, what: str):
        raise CampaignError(f"{self.path}:{lineno}: run {index}: column '{column}': {what}; "
                            "the table was edited after the campaign wrote it: restore it, "
                            "or delete this line to have the run done again")

    def _check_row(self, lineno: int, index: int, row: dict[str, str],
                   values: list[str]) -> None:
        """CampaignError unless the row of an `ok` run is as the campaign wrote it (module
        docstring): number cells, method statuses, settings and truth, digest."""
        for column, text in row.items():
            if _is_text(column):
                if column.endswith(".status") and text not in STATUSES:
                    self._refuse(lineno, index, column, f"{text!r} is not a status the "
                                 f"campaign writes ({' or '.join(STATUSES)})")
            elif text not in ("", "nan") and not _NUMBER.match(text):
                self._refuse(lineno, index, column, f"{text!r} is not a number")
        if self.expected is not None:
            for column, want in self.expected(index).items():
                if column in row and row[column] != want:
                    self._refuse(lineno, index, column, f"{row[column]!r} is not this "
                                 f"campaign's value for run {index} ({want!r})")
        if row[DIGEST] != row_digest(self.spec, values[:-1]):
            self._refuse(lineno, index, DIGEST, "the row's cells do not match it")

    def append(self, row: dict[str, str]) -> None:
        """One row, one write, then flush and fsync: a kill leaves at most a partial last line."""
        index = int(row["run"])
        if index in self.rows:
            return
        values = [row.get(c, "") for c in self.columns[:-1]]
        values.append(row_digest(self.spec, values))
        self._handle.write(_csv_line(values))
        self._handle.flush()
        os.fsync(self._handle.fileno())
        self.rows[index] = dict(zip(self.columns, values))

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
    if not lines or lines[0] not in (TABLE_MAGIC, *EARLIER_MAGIC) or len(lines) < 3 or not lines[1].startswith("# spec: "):
        raise CampaignError(f"{path}:1: not a jointbench campaign table")
    spec = spec_from_json(lines[1][len("# spec: "):])
    reader = csv.DictReader([ln for ln in lines[2:] if ln])
    rows = sorted(reader, key=lambda r: int(r["run"]))
    return spec, rows
