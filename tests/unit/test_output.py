"""Unit tests of identification/output_values.py: strict JSON values and the small error measures of
the presentation layer."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from jointbench.identification.output_values import finite_json, pct_error, rms


def test_finite_json_makes_strict_json():
    raw = {"K": np.float64(20341.0), "sigma": float("nan"), "up": math.inf,
           "down": np.float32(-np.inf), "n": np.int64(26), "ok": np.bool_(True),
           "list": [1.5, np.nan, (np.int32(2), np.float32(0.5))], "name": "joint-motor",
           "none": None, "nested": {"a": {"b": np.float64("nan")}}}
    out = finite_json(raw)
    text = json.dumps(out, allow_nan=False)      # raises on any NaN or inf left
    assert json.loads(text) == {
        "K": 20341.0, "sigma": None, "up": None, "down": None, "n": 26, "ok": True,
        "list": [1.5, None, [2, 0.5]], "name": "joint-motor", "none": None,
        "nested": {"a": {"b": None}}}


def test_finite_json_gives_plain_python_types():
    out = finite_json({"x": np.float32(0.25), "i": np.int16(-3), "b": np.bool_(False)})
    assert type(out["x"]) is float and type(out["i"]) is int and type(out["b"]) is bool
    # Tuples become lists (as json would write them anyway).
    assert finite_json((1, 2)) == [1, 2]
    # Plain values pass unchanged.
    assert finite_json(3) == 3 and finite_json("s") == "s" and finite_json(2.5) == 2.5


def test_finite_json_does_not_touch_its_input():
    raw = {"a": [np.nan]}
    finite_json(raw)
    assert math.isnan(raw["a"][0])


def test_rms():
    assert rms(np.array([3.0, -4.0])) == pytest.approx(math.sqrt(12.5))
    assert rms(np.zeros(5)) == 0.0
    # Of a sine over whole periods: amplitude / sqrt(2), to rounding.
    t = np.arange(1000) / 1000
    assert rms(2.0 * np.sin(2 * np.pi * 5 * t)) == pytest.approx(math.sqrt(2), rel=1e-12)
    assert isinstance(rms(np.ones(3)), float)


def test_pct_error():
    assert pct_error(110.0, 100.0) == pytest.approx(10.0)
    assert pct_error(90.0, 100.0) == pytest.approx(-10.0)
    # Relative to |ref|: a value above a negative reference is a positive error.
    assert pct_error(-45.0, -50.0) == pytest.approx(10.0)
    # The paper's Table 3 K against Table 1's: 19552.6214 vs 20341.0458, -3.88 %.
    assert pct_error(19552.6214, 20341.0458) == pytest.approx(-3.876, abs=1e-3)


@pytest.mark.parametrize("value, ref", [(None, 1.0), (1.0, None), (1.0, 0.0), (math.nan, 1.0),
                                        (math.inf, 1.0)])
def test_pct_error_is_none_when_undefined(value, ref):
    assert pct_error(value, ref) is None
