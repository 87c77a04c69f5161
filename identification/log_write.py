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

from jointbench.identification.log_schema import FORMAT_KEY, FORMAT_VERSION, Log

if TYPE_CHECKING:
    import matplotlib.figure

META_NUMBER_FORMAT = ".10g"  # the metadata's numbers: 10 significant digits


def format_meta_number(x: float) -> str:
    """A number as the metadata writes it (10 significant digits)."""
    return format(x, META_NUMBER_FORMAT)


def format_log(log: Log, precision: int = 12) -> str:
    """The CSV text of `log` (docs/log-format.md), metadata first."""
    out = io.StringIO()
    out.write(f"# {FORMAT_KEY}: {FORMAT_VERSION}\n")
    for key, value in log.meta.items():
        if key == FORMAT_KEY:
            continue
        out.write(f"# {key}: {value}\n")
    cols = log.columns()
    out.write(",".join(cols) + "\n")
    table = np.column_stack(list(cols.values()))
    # np.savetxt's text, formatted in one call rather than row by row (2x faster: it is most
    # of `simulate`'s time after the simulation)
    row = ",".join([f"%.{precision}g"] * table.shape[1]) + "\n"
    out.write((row * table.shape[0]) % tuple(table.ravel().tolist()))
    return out.getvalue()


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write(path: str | os.PathLike, write: Callable[[IO], object], binary: bool = False,
                 sync: bool = True) -> Path:
    """Create `path` by `write(handle)` on a temporary file in the same folder, then rename it
    over `path` (os.replace, atomic on one filesystem); on any exception the temporary is
    removed and the exception goes on. A `path` that exists and is not a regular file (a
    device node, a FIFO, a folder) is refused (OSError). The file gets mode 0666 less the
    umask, as open() would create it. Text handles are UTF-8 with "\\n" line ends; `sync`
    flushes the data to disk before the rename. Raises OSError when the folder does not exist
    or is not writable."""
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
    """Write a log as the CSV of docs/log-format.md, atomically.

    Parameters
    ----------
    log : Log
        The log.
    path : str or PathLike
        The file (replaced only once complete).
    """
    atomic_write_text(path, format_log(log))
