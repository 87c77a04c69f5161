"""What labs record, made a raw table for `identification.log.raw.convert`: MATLAB `.mat`
files, column expressions in the map, and the columns the map does not name.

- `.mat`, MATLAB v5 (and v4, v6, v7) through scipy.io.loadmat; v7.3 (HDF5) through h5py, the
  optional extra `jointbench[mat73]`. Each numeric vector becomes a column named as its
  variable; an n x k matrix gives k columns `NAME_1` ... `NAME_k`; a struct's fields are
  named `STRUCT.FIELD` (a Simulink "structure with time" gives `s.time`, `s.signals.values`).
  Scalars, text and vectors of another length than the table's are left out, and named in the
  table's `skipped`.
- Expressions: a mapped "column" may be an arithmetic expression of raw columns and numbers,
  `+ - * /`, unary minus and parentheses (`q=theta-alpha`, `tau_m=-cur`, `tau_m=0.5*u`);
  it is evaluated element by element into a new column named as its text.
- Unmapped columns are kept as the log's extra columns (docs/log-format.md: extra columns are
  kept), in the raw units; a raw name that is a log column's gets the prefix `raw_`.

Errors are LogErrors naming the file and the variable or the expression.
"""

from __future__ import annotations

import ast
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from jointbench.identification.log.raw import LOG_COLUMNS, ImportResult, RawTable, read_raw
from jointbench.identification.log.schema import LogError

MAT_SUFFIX = ".mat"
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
MAT73_EXTRA = "pip install 'jointbench[mat73]' (h5py)"


@dataclass(frozen=True)
class MatTable:
    """A raw table read from a .mat file and what was left out of it (`skipped`: variable
    -> why)."""

    raw: RawTable
    skipped: dict[str, str]


def _is_hdf5(path: Path) -> bool:
    with open(path, "rb") as f:
        head = f.read(512 + 8)
    return HDF5_SIGNATURE in (head[:8], head[512:520])


def _flatten_v5(name: str, value, out: dict[str, np.ndarray], skipped: dict[str, str]) -> None:
    """Numeric arrays of a loadmat answer (squeezed, structs as objects) into `out`."""
    if hasattr(value, "_fieldnames"):                     # a struct (mat_struct)
        for field in value._fieldnames:
            _flatten_v5(f"{name}.{field}", getattr(value, field), out, skipped)
        return
    arr = np.asarray(value)
    if arr.dtype == object and arr.size == 1:
        _flatten_v5(name, arr.item(), out, skipped)
        return
    if arr.dtype.kind not in "biuf":
        skipped[name] = f"not numeric ({arr.dtype.kind})"
        return
    out[name] = arr.astype(float)


def _read_v73(path: Path, out: dict[str, np.ndarray], skipped: dict[str, str]) -> None:
    try:
        import h5py
    except ImportError:
        raise LogError("a MATLAB v7.3 (HDF5) file: reading it needs h5py, the optional extra "
                       f"[mat73]: {MAT73_EXTRA}; or save it as v7 in MATLAB "
                       "(save(file, '-v7'))", str(path)) from None

    def visit(key: str, obj) -> None:
        if key.startswith("#"):
            return
        if isinstance(obj, h5py.Dataset):
            name = key.replace("/", ".")
            if obj.dtype.kind not in "biuf":
                skipped[name] = f"not numeric ({obj.dtype.kind})"
                return
            out[name] = np.asarray(obj, dtype=float).T     # MATLAB's column-major order

    with h5py.File(path, "r") as f:
        f.visititems(visit)


def read_mat(path: str | os.PathLike) -> MatTable:
    """The raw table of a .mat file (module docstring): its columns are the numeric vectors
    of the most common length n >= 3 (and the columns of n x k matrices). LogError naming
    the file when it cannot be read or holds no such vector."""
    p = Path(path)
    name = str(path)
    if not p.is_file():
        raise LogError("no such file", name)
    arrays: dict[str, np.ndarray] = {}
    skipped: dict[str, str] = {}
    if _is_hdf5(p):
        _read_v73(p, arrays, skipped)
    else:
        from scipy import io as sio
        try:
            content = sio.loadmat(p, squeeze_me=True, struct_as_record=False)
        except NotImplementedError:     # scipy's answer to v7.3
            _read_v73(p, arrays, skipped)
            content = {}
        except (ValueError, TypeError, OSError) as err:
            raise LogError(f"not a readable MATLAB .mat file: {err}", name) from None
        for key, value in content.items():
            if not key.startswith("__"):
                _flatten_v5(key, value, arrays, skipped)
    columns: dict[str, np.ndarray] = {}
    for key, arr in arrays.items():
        if arr.ndim == 0 or arr.size == 1:
            skipped[key] = "a scalar"
        elif arr.ndim == 1 or min(arr.shape) == 1:
            columns[key] = arr.reshape(-1)
        elif arr.ndim == 2:
            rows = arr if arr.shape[0] >= arr.shape[1] else arr.T
            for j in range(rows.shape[1]):
                columns[f"{key}_{j + 1}"] = rows[:, j]
        else:
            skipped[key] = f"{arr.ndim}-dimensional"
    lengths = [len(v) for v in columns.values() if len(v) >= 3]
    if not lengths:
        raise LogError("no numeric vector of 3 or more samples in the file (variables: "
                       f"{', '.join(sorted(arrays)) or 'none'})", name)
    n = max(set(lengths), key=lambda m: (lengths.count(m), m))
    kept = {}
    for key, col in columns.items():
        if len(col) != n:
            skipped[key] = f"{len(col)} samples, the table has {n}"
        elif not np.all(np.isfinite(col)):
            k = int(np.flatnonzero(~np.isfinite(col))[0])
            raise LogError(f"variable '{key}': non-finite value at sample {k + 1}", name)
        else:
            kept[key] = col
    header = tuple(kept)
    data = np.column_stack([kept[h] for h in header])
    # "lines" of a .mat table: the sample numbers, 1-based (what an error names)
    return MatTable(RawTable(name, header, data, np.arange(1, n + 1), ""), skipped)


def read_source(path: str | os.PathLike, delimiter: str | None = None) -> tuple[RawTable, dict]:
    """The raw table of a file: a .mat file (`read_mat`), else a CSV (`read_raw`); and what
    a .mat file left out (variable -> why; empty for a CSV)."""
    if Path(path).suffix.lower() == MAT_SUFFIX:
        t = read_mat(path)
        return t.raw, t.skipped
    return read_raw(path, delimiter), {}


_OPS = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.divide}


def is_expression(text: str) -> bool:
    """Is a mapped source an expression rather than a plain column name?"""
    return any(c in text for c in "+-*/() ") and not text.lstrip("-").replace(".", "").isdigit()


def evaluate(text: str, raw: RawTable, col: str) -> np.ndarray:
    """The expression `text` on the columns of `raw` (module docstring). LogError naming the
    file and the mapping for a name that is no column, an operator that is not allowed, or
    a non-finite result."""
    where = f"--map {col}={text}"
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError:
        raise LogError(f"{where}: not an expression of columns and numbers "
                       "(+ - * / and parentheses)", raw.path) from None

    def ev(node):
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            v = ev(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
                and not isinstance(node.value, bool):
            return float(node.value)
        if isinstance(node, ast.Name):
            if node.id not in raw.header:
                raise LogError(f"{where}: no column '{node.id}' (the file has "
                               f"{', '.join(raw.header)})", raw.path)
            return raw.column(node.id)
        raise LogError(f"{where}: only columns, numbers, + - * / and parentheses are "
                       f"allowed ({type(node).__name__} is not)", raw.path)

    with np.errstate(all="ignore"):
        value = np.broadcast_to(np.asarray(ev(tree), float), (len(raw.data),)).copy()
    bad = np.flatnonzero(~np.isfinite(value))
    if bad.size:
        raise LogError(f"{where}: not finite at row {int(bad[0]) + 1} (a division by zero?)",
                       raw.path, int(raw.lines[bad[0]]))
    return value


def with_expressions(raw: RawTable, columns: dict[str, str],
                     skipped: dict[str, str] | None = None) -> tuple[RawTable, dict[str, str]]:
    """`raw` with a column for each mapped expression (named as its text) and the mapping
    onto those columns; plain column names pass unchanged (convert checks them). A mapped
    variable that a .mat file left out (`skipped`) is a LogError naming it and why."""
    for col, source in columns.items():
        if skipped and source in skipped:
            raise LogError(f"--map {col}={source}: variable '{source}' cannot be a column: "
                           f"{skipped[source]}", raw.path)
    extra = {}
    for col, source in columns.items():
        if source not in raw.header and is_expression(source):
            extra[source] = evaluate(source, raw, col)
    if not extra:
        return raw, dict(columns)
    header = raw.header + tuple(extra)
    data = np.column_stack([raw.data] + [extra[k] for k in extra])
    return replace(raw, header=header, data=data), dict(columns)


def keep_unmapped(result: ImportResult, raw: RawTable, columns: dict[str, str]) -> ImportResult:
    """`result` with every raw column the map does not name (an expression's column is named
    by it) as an extra column of the log, in its raw units; a name that is a log column's
    gets `raw_`."""
    used = set(columns.values())
    extra = dict(result.log.extra)
    kept = []
    for name in raw.header:
        if name in used:
            continue
        key = f"raw_{name}" if name in LOG_COLUMNS else name
        extra[key] = raw.column(name).copy()
        kept.append(key)
    if not kept:
        return result
    steps = result.steps + (f"kept unmapped columns as they are (raw units): {', '.join(kept)}",)
    return replace(result, log=replace(result.log, extra=extra), steps=steps)
