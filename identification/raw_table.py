"""A raw CSV table, as a drive or a data logger writes it (identification.log.raw converts
it into a jointbench log): a header row of the raw columns' names, then one row of numbers
per sample. Numbers are read as the log reader reads them (log_schema.is_number: ASCII, no
digit separator), the rows held as 8-byte floats so that the memory a table takes is known
while it is read (`max_values`).
"""

from __future__ import annotations

import array
import math
import os
from dataclasses import dataclass

import numpy as np

from jointbench.identification.log.read import read_lines
from jointbench.identification.log.schema import LogError, is_number, shown

DELIMITERS = (",", ";", "\t", "|")
NUMBER_CHARACTERS = ".+-_# \"'"   # never a delimiter: part of a number, a comment or quoting


@dataclass(frozen=True)
class RawTable:
    """A raw CSV table: `header` names, `data` (rows x columns, float), `lines` the file
    line of each row, `delimiter` found."""

    path: str
    header: tuple[str, ...]
    data: np.ndarray
    lines: np.ndarray
    delimiter: str

    def column(self, name: str) -> np.ndarray:
        return self.data[:, self.header.index(name)]


def _split(line: str, delimiter: str) -> list[str]:
    return [cell.strip().strip('"').strip() for cell in line.split(delimiter)]


class TooLarge(LogError):
    """A raw table with more values than the caller allows (`max_values`): `values` read so
    far, `rows` of them."""

    def __init__(self, message: str, path: str, line: int, values: int):
        super().__init__(message, path, line)
        self.values = values


def _header(text: str, delimiter: str, path: str, lineno: int) -> list[str]:
    """The raw header's names; LogError for an empty or repeated name, or a row of numbers
    (a file without a header)."""
    header = _split(text, delimiter)
    if all(is_number(h) for h in header if h) and any(header):
        raise LogError(f"the first row must be the header (the raw columns' names), found "
                       f"numbers: '{shown(text, 80)}'; add a header row naming the columns",
                       path, lineno)
    if "" in header:
        hint = f" (a {delimiter!r} at the end of the line?)" if header[-1] == "" else ""
        raise LogError(f"empty column name in the header{hint}", path, lineno)
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise LogError(f"duplicate column '{shown(dup[0])}' in the header", path, lineno)
    return header


def _bad_cell(cells: list[str], header: list[str], path: str, lineno: int) -> LogError:
    """The error of the first cell that is not a number as the log reader reads one
    (log_schema.is_number: ASCII, no digit separator), or not finite."""
    for name, cell in zip(header, cells):
        if not is_number(cell):
            what = "empty cell" if not cell else f"not a number: '{shown(cell)}'"
            return LogError(what, path, lineno, name)
        if not math.isfinite(float(cell)):
            return LogError(f"non-finite value '{shown(cell)}'", path, lineno, name)
    return LogError("unreadable row", path, lineno)  # pragma: no cover - a cell failed above


def parse_raw(lines, path: str, delimiter: str | None = None,
              max_values: int | None = None) -> RawTable:
    """A raw table from numbered text lines: `#` comment lines and blank lines skipped, the
    first other line the header (delimiter `,`, `;`, tab or `|`, found from it unless given),
    then one row of numbers per line, each read as the log reader reads a number
    (log_schema.is_number: `1_000` and non-ASCII digits are refused). Raises LogError naming
    file, line and column; TooLarge past `max_values` values (the rows are held as 8-byte
    floats, so that the memory the table takes is known as it is read)."""
    if delimiter is not None and (len(delimiter) != 1 or delimiter.isalnum()
                                  or delimiter in NUMBER_CHARACTERS):
        raise LogError(f"--delimiter {delimiter!r}: give one character that is not part of a "
                       "number or a name (e.g. ',' ';' '|' or a tab)", path)
    header: list[str] | None = None
    values = array.array("d")
    where = array.array("q")
    for lineno, line in lines:
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        if header is None:
            if delimiter is None:
                delimiter = max(DELIMITERS, key=text.count)
            header = _header(text, delimiter, path, lineno)
            continue
        cells = _split(text, delimiter)
        if len(cells) != len(header):
            raise LogError(f"expected {len(header)} cells, found {len(cells)}", path, lineno)
        if "_" in text or not text.isascii():
            raise _bad_cell(cells, header, path, lineno)
        try:
            row = [float(cell) for cell in cells]
        except ValueError:
            raise _bad_cell(cells, header, path, lineno) from None
        if not all(map(math.isfinite, row)):
            raise _bad_cell(cells, header, path, lineno)
        values.extend(row)
        where.append(lineno)
        if max_values is not None and len(values) > max_values:
            raise TooLarge(f"more than {max_values} values", path, lineno, len(values))
    if header is None:
        raise LogError("empty file: no header row", path)
    if not where:
        raise LogError("no data rows after the header", path)
    data = np.frombuffer(values, dtype=float).reshape(len(where), len(header))
    return RawTable(path, tuple(header), data, np.frombuffer(where, dtype=np.int64),
                    delimiter or ",")


def read_raw(path: str | os.PathLike, delimiter: str | None = None,
             max_values: int | None = None) -> RawTable:
    """`parse_raw` on a file, streamed with the log reader's checks (size limit, binary
    content; identification.log.read.read_lines). Raises LogError (TooLarge past
    `max_values`)."""
    return read_lines(path, lambda lines, name: parse_raw(lines, name, delimiter, max_values))
