"""Writing: the CSV text of a log (docs/log-format.md) and atomic file writes (text, figures).

Every file jointbench writes goes through `atomic_write`: a temporary file in the same folder
and a rename, so that an interrupted write (an exception, KeyboardInterrupt, a signal turned
into one) never leaves a half-written file: either the old content or the new one, and no
temporary.
"""

from __future__ import annotations

import errno
import io
import os
import stat
import tempfile
from pathlib import Path
from typing import IO, TYPE_CHECKING, Callable

import numpy as np

from jointbench.identification.log.schema import FORMAT_KEY, FORMAT_VERSION, Log

if TYPE_CHECKING:
    import matplotlib.figure

META_NUMBER_FORMAT = ".10g"  # the metadata's numbers: 10 significant digits


def format_meta_number(x: float) -> str:
    """A number as the metadata writes it (10 significant digits)."""
    return format(x, META_NUMBER_FORMAT)


# Characters that end a line for one of the readers (str.splitlines): a metadata key or value
# holding one would be read back as two lines.
LINE_BREAKS = "\n\r\v\f\x1c\x1d\x1e\x85\u2028\u2029"
ROWS_PER_BLOCK = 1 << 16   # rows formatted at a time: the text of a block, not of the log


def check_writable(log: Log) -> None:
    """LogError (naming the key, column or sample) for what the format cannot hold: a
    metadata key that is empty or holds ':' or '#' or a line break, a value with a line break
    (docs/log-format.md: one `# key: value` line each), columns that are not 1-D arrays of
    one length, non-finite samples."""
    from jointbench.identification.log.schema import LogError, shown

    for key, value in log.meta.items():
        key, value = str(key), str(value)
        if not key.strip() or any(c in key for c in ":#" + LINE_BREAKS):
            raise LogError(f"metadata key '{shown(key)}' cannot be written: a key is one word "
                           "on its line, without ':', '#' or a line break", log.path)
        if any(c in value for c in LINE_BREAKS):
            raise LogError(f"metadata '{shown(key)}': the value '{shown(value)}' holds a line "
                           "break; the format has one '# key: value' line per key", log.path)
    cols = log.columns()
    n = len(log.t)
    for name, x in cols.items():
        x = np.asarray(x)
        if x.ndim != 1 or len(x) != n:
            raise LogError(f"column '{name}' has shape {x.shape}, t has {n} samples: the "
                           "columns must be 1-D arrays of one length", log.path)
        bad = np.flatnonzero(~np.isfinite(x))
        if bad.size:
            raise LogError(f"column '{name}' holds {x[bad[0]]} at sample {int(bad[0])} (of "
                           f"{n}): a log holds finite numbers only", log.path)


def _write_log_text(log: Log, handle: IO, precision: int = 12) -> None:
    """The CSV text of `log` written to `handle` (`format_log`), a block of rows at a time."""
    handle.write(f"# {FORMAT_KEY}: {FORMAT_VERSION}\n")
    for key, value in log.meta.items():
        if key == FORMAT_KEY:
            continue
        handle.write(f"# {key}: {value}\n")
    cols = log.columns()
    handle.write(",".join(cols) + "\n")
    table = np.column_stack(list(cols.values()))
    # np.savetxt's text, formatted in one call per block rather than row by row (2x faster:
    # it is most of `simulate`'s time after the simulation)
    row = ",".join([f"%.{precision}g"] * table.shape[1]) + "\n"
    for start in range(0, table.shape[0], ROWS_PER_BLOCK):
        block = table[start:start + ROWS_PER_BLOCK]
        handle.write((row * block.shape[0]) % tuple(block.ravel().tolist()))


def format_log(log: Log, precision: int = 12) -> str:
    """The CSV text of `log` (docs/log-format.md), metadata first. LogError for what the
    format cannot hold (`check_writable`)."""
    check_writable(log)
    out = io.StringIO()
    _write_log_text(log, out, precision)
    return out.getvalue()


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write(path: str | os.PathLike, write: Callable[[IO], object], binary: bool = False,
                 sync: bool = True, check: Callable[[Path], object] | None = None) -> Path:
    """Create `path` by `write(handle)` on a temporary file in the same folder, then rename it
    over `path` (os.replace, atomic on one filesystem); on any exception the temporary is
    removed and the exception goes on. A `path` that exists and is not a regular file (a
    device node, a FIFO, a folder) is refused (OSError). The file gets mode 0666 less the
    umask, as open() would create it. Text handles are UTF-8 with "\\n" line ends; `sync`
    flushes the data to disk before the rename; `check(temporary path)`, when given, reads the
    written file back before the rename and raises to keep `path` as it was. Raises OSError
    when the folder does not exist or is not writable."""
    path = Path(path)
    if os.path.lexists(path) and not stat.S_ISREG(os.lstat(path).st_mode):
        raise IsADirectoryError(errno.EISDIR, "not a regular file: refusing to replace it",
                                str(path))
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        os.fchmod(fd, 0o666 & ~_umask())  # mkstemp creates 0600; a file gets what umask allows
        with (os.fdopen(fd, "wb") if binary else
              os.fdopen(fd, "w", encoding="utf-8", newline="\n")) as handle:
            write(handle)
            if sync:
                handle.flush()
                os.fsync(handle.fileno())
        if check is not None:
            check(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write `text` to `path` atomically (`atomic_write`, synced to disk)."""
    atomic_write(path, lambda handle: handle.write(text))


def save_figure_atomic(fig: matplotlib.figure.Figure, path: str | os.PathLike[str]) -> Path:
    """Save ``fig`` as PNG at ``path`` atomically (`atomic_write`); returns the path.

    Raises:
        OSError: if the directory does not exist or is not writable.
    """
    return atomic_write(path, lambda handle: fig.savefig(handle, format="png"), binary=True,
                        sync=False)


def write_log(log: Log, path: str | os.PathLike) -> None:
    """Write a log as the CSV of docs/log-format.md, atomically, read back by the log reader
    before it replaces `path`: a log jointbench writes is one it reads.

    Parameters
    ----------
    log : Log
        The log.
    path : str or PathLike
        The file (replaced only once complete and read back).

    Raises
    ------
    LogError
        Naming the key, column or sample, or the reader's file, line and column.
    """
    from jointbench.identification.log.read import read_log
    from jointbench.identification.log.schema import LogError

    check_writable(log)

    def read_back(tmp: Path) -> None:
        try:
            read_log(tmp, max_bytes=max(os.path.getsize(tmp), 1))
        except LogError as err:
            where = f":{err.line}" if err.line is not None else ""
            col = f" column '{err.column}':" if err.column is not None else ""
            raise LogError(f"the log written would not read back ({path}{where}:{col} "
                           f"{err.message}); nothing written", log.path) from None

    atomic_write(path, lambda handle: _write_log_text(log, handle), check=read_back)
