"""Helpers of the presentation layer shared by every writer: strict JSON values and the small
error measures printed beside estimates. No I/O here."""

from __future__ import annotations

import math

import numpy as np


def finite_json(x):
    """`x` made strict JSON: NaN and inf become null, numpy scalars plain Python numbers,
    recursively through dicts, lists and tuples."""
    if isinstance(x, dict):
        return {k: finite_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [finite_json(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def rms(x: np.ndarray) -> float:
    """Root mean square of an array."""
    return float(np.sqrt(np.mean(np.square(x))))


# A truth this small is zero up to rounding (MuJoCo's first moment of a vertical axis comes out
# as 1e-15 kg m, say): an error in % of it means nothing, and is not printed.
ZERO_TRUTH = 1e-12


def pct_error(value: float | None, ref: float | None) -> float | None:
    """100 (value - ref) / |ref|, or None when either is missing, ref is 0 (|ref| <=
    ZERO_TRUTH) or value is not finite."""
    if value is None or ref is None or not abs(ref) > ZERO_TRUTH or not math.isfinite(value):
        return None
    return 100.0 * (value - ref) / abs(ref)
