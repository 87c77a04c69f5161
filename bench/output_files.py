"""The one output layer: every file and folder a command writes is checked and written here.

Rules:
- a target that exists and is not a regular file (a device node, a FIFO, a socket, a folder,
  a symbolic link) is refused: `OutputError`, exit status 2;
- a file jointbench did not write is never replaced. Ours are the logs and campaign tables,
  which carry their marker (`# source: jointbench ...`, `# jointbench-campaign`), and every
  other file recorded, with the SHA-256 of its content, in the manifest of its folder
  (`.jointbench-manifest.json`): a file edited since is no longer ours;
- the folder and its permissions are checked before any computation (`check_file`,
  `OutputFolder`), so that a missing or read-only folder costs nothing;
- a folder (`diagnose --out`, `demo --out`) is written as a whole or not at all: our previous
  files are moved aside first, and put back if the command fails or is interrupted (a signal
  turned into an exception); on success they are deleted, so no stale file of an earlier run
  (an `extended.xml` the new report does not mention) stays beside the new ones; the
  manifest is written last, with `"complete": true`;
- files are written atomically with the permissions the umask allows
  (identification.log.write.atomic_write).

Standard library only, no numerical import.
"""

from __future__ import annotations

import os
import signal
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterable, Iterator

MANIFEST = ".jointbench-manifest.json"
MARKERS = ("\n# source: jointbench ", "# jointbench-campaign")  # in the first 8 KiB
_BACKUP_PREFIX = ".jointbench-previous-"


class OutputError(ValueError):
    """An output target that cannot or must not be written (exit status 2)."""


def file_kind(mode: int) -> str | None:
    """What a non-regular file is (by its `st_mode`), None for a regular one."""
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISSOCK, "a socket"), (stat.S_ISLNK, "a symbolic link")):
        if test(mode):
            return name
    return None


def sha256(path: Path) -> str:
    import hashlib   # imported here: `simulate` starts without it (README, start-up)
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def read_manifest(folder: Path) -> dict[str, str]:
    """name (relative to `folder`) -> SHA-256 of the files jointbench wrote there; {} when
    there is no readable manifest."""
    import json
    path = folder / MANIFEST
    try:
        if not stat.S_ISREG(os.lstat(path).st_mode):
            return {}
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    files = doc.get("files") if isinstance(doc, dict) else None
    return {str(k): str(v) for k, v in files.items()} if isinstance(files, dict) else {}


def _write_manifest(folder: Path, files: dict[str, str], complete: bool = True) -> None:
    import json
    from jointbench.identification.log.write import atomic_write_text

    doc = {"written_by": "jointbench", "complete": complete, "files": dict(sorted(files.items()))}
    atomic_write_text(folder / MANIFEST, json.dumps(doc, indent=1) + "\n")


def is_ours(path: Path, manifest: dict[str, str] | None = None, name: str | None = None) -> bool:
    """True when the regular file `path` was written by jointbench: its marker, or an entry
    of the folder's manifest whose hash matches the content."""
    try:
        with open(path, "rb") as f:
            head = f.read(8192).decode("utf-8", "replace")
    except OSError:
        return False
    if head.startswith(MARKERS[1]) or MARKERS[0] in head or \
            (path.name == MANIFEST and '"written_by": "jointbench"' in head):
        return True
    manifest = read_manifest(path.parent) if manifest is None else manifest
    key = name or path.name
    return key in manifest and manifest[key] == sha256(path)


def _check_folder(folder: Path, flag: str, what: str) -> None:
    if not folder.is_dir():
        raise OutputError(f"{flag} {what}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputError(f"{flag} {what}: folder {folder} is not writable")


def check_target(path: Path, flag: str = "--out", manifest: dict[str, str] | None = None,
                 name: str | None = None) -> None:
    """OutputError unless `path` is absent, or a regular file jointbench wrote (empty files
    count as nobody's)."""
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        return
    except OSError as err:
        raise OutputError(f"{flag} {path}: cannot inspect it: {err.strerror}") from None
    kind = file_kind(info.st_mode)
    if kind is not None:
        raise OutputError(f"{flag} {path}: is {kind}, not a regular file: refusing to "
                          "replace it")
    if info.st_size > 0 and not is_ours(path, manifest, name):
        raise OutputError(f"{flag} {path}: refusing to overwrite an existing file that "
                          "jointbench did not write (no '# source: jointbench ...' metadata, "
                          f"not in {MANIFEST}); remove it or choose another name")


def check_file(path: str | os.PathLike, flag: str = "--out") -> Path:
    """Check an output file before computing: its folder exists and is writable, the target
    is absent or ours (`check_target`). Returns the path."""
    path = Path(path)
    _check_folder(path.parent if str(path.parent) else Path("."), flag, str(path))
    check_target(path, flag)
    return path


def record(path: str | os.PathLike) -> None:
    """Add the file just written at `path` to its folder's manifest (for files that carry no
    marker: figures, models, reports, JSON)."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    files = read_manifest(folder)
    files[path.name] = sha256(path)
    _write_manifest(folder, files)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write `text` atomically and record it in the folder's manifest."""
    from jointbench.identification.log.write import atomic_write_text

    atomic_write_text(path, text)
    record(path)
    return Path(path)


@contextmanager
def _signals_held() -> Iterator[None]:
    """SIGTERM, SIGHUP and SIGINT held back (delivered on exit) while the folder is swapped:
    a signal then lands before or after the swap, never in the middle of it."""
    sigs = {signal.SIGTERM, signal.SIGINT}
    if hasattr(signal, "SIGHUP"):
        sigs.add(signal.SIGHUP)
    old = signal.pthread_sigmask(signal.SIG_BLOCK, sigs) if hasattr(signal, "pthread_sigmask") \
        else None
    try:
        yield
    finally:
        if old is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _entries(folder: Path) -> set[str]:
    """Every file below `folder` (relative names), the backup folders left out."""
    out = set()
    for root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if not d.startswith(_BACKUP_PREFIX)]
        rel = Path(root).relative_to(folder)
        out |= {str(rel / f) if str(rel) != "." else f for f in files}
    return out


class OutputFolder:
    """A folder a command fills (`diagnose --out`, `demo --out`). Construct it before the
    computation (it checks the folder, its permissions and every file `names` would replace);
    write inside `with folder.writing():` (module docstring: all or nothing).

    `names`: the files the command may write, relative to the folder (a trailing `/*` covers
    a sub-folder); a file of that name already there must be ours."""

    def __init__(self, path: str | os.PathLike, names: Iterable[str], flag: str = "--out"):
        self.path, self.flag = Path(path), flag
        self.names = tuple(names)
        p = self.path
        if os.path.lexists(p):
            kind = file_kind(os.lstat(p).st_mode)
            if kind != "a directory" and not p.is_dir():
                raise OutputError(f"{flag} {p}: exists and is not a folder"
                                  + (f" ({kind})" if kind else ""))
            _check_folder(p, flag, str(p))
            self._check_links()
            manifest = read_manifest(p)
            for name in self._present():
                check_target(p / name, flag, manifest, name)
        else:
            parent = p.parent if str(p.parent) else Path(".")
            _check_folder(parent, flag, str(p))

    def _check_links(self) -> None:
        """OutputError when a sub-folder the command writes into (`logs/` of `logs/*`) is a
        symbolic link or not a folder: files written there would land in another folder,
        past every check of this one."""
        for name in self.names:
            parts = Path(name.removesuffix("/*")).parts
            for k in range(1, len(parts) if not name.endswith("/*") else len(parts) + 1):
                sub = self.path.joinpath(*parts[:k])
                if os.path.islink(sub) or (os.path.lexists(sub) and not sub.is_dir()):
                    what = "a symbolic link" if os.path.islink(sub) else "not a folder"
                    raise OutputError(f"{self.flag} {self.path}: {sub} is {what}; refusing to "
                                      f"write {name} through it")

    def _declared(self, name: str) -> bool:
        return any(name == n or (n.endswith("/*") and name.startswith(n[:-1]))
                   for n in self.names) or name == MANIFEST

    def _present(self) -> list[str]:
        return sorted(n for n in _entries(self.path) if self._declared(n))

    @contextmanager
    def writing(self) -> Iterator[Path]:
        """Yields the folder to write into; all or nothing (class docstring)."""
        import shutil
        p = self.path
        self._check_links()   # again: the folder may have changed during the computation
        created = not p.exists()
        p.mkdir(exist_ok=True)
        backup = Path(tempfile.mkdtemp(prefix=_BACKUP_PREFIX, dir=p))
        manifest = read_manifest(p)
        moved: list[str] = []
        with _signals_held():
            # ours (manifest, markers) and the empty files of the names we write go aside
            for name in sorted(set(manifest) | set(self._present()) | {MANIFEST}):
                if Path(name).is_absolute() or ".." in Path(name).parts:
                    continue  # a manifest names files below its folder only
                src = p / name
                if src.is_file() and not src.is_symlink() and (
                        name == MANIFEST or src.stat().st_size == 0
                        or is_ours(src, manifest, name)):
                    (backup / name).parent.mkdir(parents=True, exist_ok=True)
                    os.replace(src, backup / name)
                    moved.append(name)
        before = _entries(p)
        try:
            yield p
        except BaseException:
            with _signals_held():
                new = _entries(p) - before
                for name in new:
                    (p / name).unlink(missing_ok=True)
                for name in moved:
                    (p / name).parent.mkdir(parents=True, exist_ok=True)
                    os.replace(backup / name, p / name)
                shutil.rmtree(backup, ignore_errors=True)
                _prune(p, new | set(moved), remove_root=created)
            raise
        with _signals_held():
            new = _entries(p) - before - {MANIFEST}
            _write_manifest(p, {n: sha256(p / n) for n in sorted(new)})
            shutil.rmtree(backup, ignore_errors=True)
            _prune(p, set(moved), remove_root=False)


def _prune(folder: Path, names: set[str], remove_root: bool) -> None:
    """Remove the sub-folders of `names` (files below `folder`) that are left empty, deepest
    first, and `folder` itself when asked and empty; never another folder."""
    dirs = {folder / parent for n in names for parent in Path(n).parents if str(parent) != "."}
    for d in sorted(dirs, key=lambda d: len(d.parts), reverse=True) + \
            ([folder] if remove_root else []):
        try:
            os.rmdir(d)
        except OSError:
            pass  # not empty, or gone


def write_log(log, path: str | os.PathLike, flag: str = "path") -> Path:
    """Write a log as the CSV of docs/log-format.md, under the output rule: the target is
    checked first (never a file jointbench did not write), the log written atomically and
    read back by the log reader before it counts as written.

    Parameters
    ----------
    log : Log
        The log.
    path : str or PathLike
        The file.
    flag : str
        The name of the argument or option in error messages.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    OutputError
        `path` is a file jointbench did not write, or cannot be written (a ValueError).
    LogError
        The log would not read back, naming the key, column or sample (a ValueError).
    TypeError
        `log` is not a Log or `path` not a file name.
    """
    from jointbench.identification.log.schema import Log
    from jointbench.identification.log.write import write_log as write

    if not isinstance(log, Log):
        raise TypeError(f"log: expected a jointbench Log, got {type(log).__name__}")
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{flag}: expected a file name (str or os.PathLike), got "
                        f"{type(path).__name__}")
    path = check_file(path, flag)
    write(log, path)
    return path
