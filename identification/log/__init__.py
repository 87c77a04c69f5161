"""The jointbench log: the CSV of docs/log-format.md, one package.

- `schema`: the `Log` and its metadata keys, `LogError` (which names the file, the line and
  the column at fault);
- `read`: parse, validate, stream, size limits;
- `write`: CSV text and atomic writes;
- `raw`: a measured file in its own columns and units converted into a log (`jointbench
  import`).

The names of `schema`, `read` and `write` are importable from the package itself.
"""

from __future__ import annotations

from jointbench.identification.log.read import (DEFAULT_MAX_BYTES, DEGREES_SPAN_RAD,
                                                JITTER_TOLERANCE, MAX_BYTES_ENV, MAX_LINE_BYTES,
                                                max_log_bytes, parse_log, parse_size, read_log,
                                                unit_warnings, validate)
from jointbench.identification.log.schema import (BOOLEAN_META, FORMAT_KEY, FORMAT_VERSION,
                                                  NUMERIC_META, OPTIONAL_COLUMNS,
                                                  REQUIRED_COLUMNS, Log, LogError)
from jointbench.identification.log.write import (atomic_write, atomic_write_text,
                                                 format_log, format_meta_number,
                                                 save_figure_atomic, write_log)

__all__ = [
    "BOOLEAN_META", "DEFAULT_MAX_BYTES", "DEGREES_SPAN_RAD", "FORMAT_KEY", "FORMAT_VERSION",
    "JITTER_TOLERANCE", "MAX_BYTES_ENV", "MAX_LINE_BYTES", "NUMERIC_META", "OPTIONAL_COLUMNS",
    "REQUIRED_COLUMNS", "Log", "LogError", "atomic_write", "atomic_write_text", "format_log",
    "format_meta_number", "max_log_bytes", "parse_log", "parse_size", "read_log",
    "save_figure_atomic", "unit_warnings", "validate", "write_log",
]
