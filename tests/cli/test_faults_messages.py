"""Issue 16, messages and clipped torque: every bad input names the file, line, column or
option (exit 2, never a traceback); JSON never holds NaN or Infinity; numbers are strictly
numeric; a clipped torque is detected, its rows left out of the fit with a warning, and too
much of it refused. Hypothesis fuzzes design-filter's numbers and diagnose."""

from __future__ import annotations

import dataclasses
import json
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointbench.identification.log import write_log
from jointbench.identification.saturation import MAX_CLIPPED_SHARE, clipped_samples
from test_faults_input import _meta, _rows, sim  # noqa: F401 - the fixture
from test_faults_output import run


def _strict(text: str):
    """json.loads that refuses NaN and Infinity (invalid JSON)."""
    def bad(name):
        raise ValueError(f"{name} in JSON")
    return json.loads(text, parse_constant=bad)


def _cell(row: int, col: int, value: str):
    def edit(text: str) -> str:
        k = {"i": 0}

        def fn(cells):
            k["i"] += 1
            if k["i"] == row:
                cells[col] = value
            return cells
        return _rows(text, fn)
    return edit


# --- 7. Messages that name the file, line, column or option ---------------------------------

LOG_EDITS = [  # (edit of the log text, what the message must hold)
    # {line}: the file line of data row 100 (after the metadata and the header)
    (_cell(100, 3, "1e300"), ":{line}: column 'tau_m': value 1e+300 is out of range"),
    (_cell(100, 3, "1_000"), ":{line}: column 'tau_m': not a number: '1_000'"),
    (_cell(100, 1, "\u0661"), ":{line}: column 'q_m': not a number"),
    (lambda s: _meta(s, "tau_max", "3 kN m"), "metadata 'tau_max' must be a plain number"),
    (lambda s: _meta(s, "gravity", "9.81 ft/s^2"), "metadata 'gravity' must be a plain number"),
    (lambda s: _meta(s, "kp", "1_0"), "metadata 'kp' must be a number"),
]


@pytest.mark.parametrize("edit, says", LOG_EDITS)
@pytest.mark.parametrize("command", ["identify", "diagnose"])
def test_bad_cells_and_metadata_are_named(tmp_path, sim, edit, says, command):
    path = tmp_path / "bad.csv"
    path.write_text(edit(sim[2]))
    rc, out, err = run([command, path, "--json"])
    header = next(i for i, ln in enumerate(sim[2].splitlines()) if not ln.startswith("#"))
    says = says.format(line=header + 1 + 100)
    assert rc == 2 and out == "", err
    assert err.startswith(f"jointbench {command}: error: {path}") and says in err, err


OPTION_ERRORS = [  # (command line; LOG is the 20 s log, what stderr must hold)
    (["simulate", "--config", "axis3=nan"], "--config: angle 'nan' of axis3 is not a finite"),
    (["simulate", "--config", "axis1=1_0"], "--config: angle '1_0'"),
    (["simulate", "--seed", "-1"], "argument --seed: -1 must lie in [0, 2**32)"),
    (["simulate", "--model", "FOLDER"], "is a directory, not an MJCF file"),
    (["simulate", "--substeps", "100000"], "--substeps 100000: must lie in [1, 1000]"),
    (["simulate", "--rate", "0.001"], "--rate 0.001: must lie in"),
    (["simulate", "--duration", "3"], "--duration 3: must be at least 4 s"),
    (["identify", "LOG", "--wn", "1e-9"], "--wn 1e-09: the Butterworth frequency must lie in"),
    (["identify", "LOG", "--order", "60"], "--order 60: must lie in [1, 20]"),
    (["design-filter", "--f1", "1e308", "--nd", "2", "--m", "4"], "--f1 1e+308 Hz"),
    (["design-filter", "--f1", "1e-320", "--nd", "2", "--m", "4", "--json"], "out of floating"),
    (["diagnose", "SHORT"], "3 samples are too few for the diagnosis filter"),
    (["tune-filter", "--duration", "1", "--workers", "1"], "--duration 1: must be at least"),
    (["tune-filter", "--nd", "0,5000", "--workers", "1"], "grid values must be"),
    (["tune-filter", "--wn", "2000", "--workers", "1"], "--wn grid value 2000"),
    (["demo", "--duration", "1", "--out", "DEMO"], "--duration 1: must be at least 4 s"),
]


@pytest.mark.parametrize("args, says", OPTION_ERRORS)
def test_bad_options_are_named(tmp_path, sim, monkeypatch, args, says):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder").mkdir()
    short = tmp_path / "short.csv"
    short.write_text("\n".join(sim[2].splitlines()[:sim[2].count("#") + 4]) + "\n")
    names = {"LOG": sim[0], "FOLDER": tmp_path / "folder", "SHORT": short,
             "DEMO": tmp_path / "demo"}
    rc, out, err = run([names.get(a, a) for a in args])
    assert rc == 2 and says in err, err
    assert "Traceback" not in err and "internal error" not in err and out == ""
    assert sorted(os.listdir(tmp_path)) == ["folder", "short.csv"]


def test_nan_truth_gives_valid_json(tmp_path, sim):
    path = tmp_path / "t.csv"
    path.write_text(_meta(sim[2], "truth_K", "nan"))
    rc, out, err = run(["identify", path, "--json"])
    assert rc == 0, err
    doc = _strict(out)
    assert doc["parameters"]["K"].get("truth") is None


# --- 8. Clipped torque ----------------------------------------------------------------------

def _clipped(log, share: float, with_limit: bool):
    level = float(np.quantile(np.abs(log.tau_m), 1 - share))
    meta = dict(log.meta, source="jointbench test: clipped")
    meta["tau_max"] = repr(level) if with_limit else "3000"
    return dataclasses.replace(log, tau_m=np.clip(log.tau_m, -level, level), meta=meta)


@pytest.mark.parametrize("share, with_limit, status, says", [
    (0.0, True, 0, None),
    (0.10, True, 0, "at the metadata's tau_max"),
    (0.10, False, 0, "a flat top at"),
    (0.30, True, 0, "left out of the fit"),
    (0.40, True, 2, "over 33.3 %"),
])
def test_clipped_torque_is_left_out_or_refused(tmp_path, sim, share, with_limit, status, says):
    """Clipping 10 % of the 20 s log's torque at the metadata's tau_max gave K -38 % (30 %:
    -95 %, exit 0, no warning); left out, K is within 1 % of the truth (measured -0.57 %
    and, at 30 %, -2.7 % with a 2 sigma of 1.6 %: what stays excites the mode less), with a
    warning; over a third is refused."""
    log = sim[1] if share == 0 else _clipped(sim[1], share, with_limit)
    path = tmp_path / "c.csv"
    write_log(log, path)
    rc, out, err = run(["identify", path, "--json", "--model", "joint-motor"])
    assert rc == status, err
    if says is None:
        assert clipped_samples(log).count == 0 and "clipped" not in err
    else:
        assert says in err
    if status == 0:
        K = _strict(out)["physical"]["K"]
        assert abs(K / float(log.meta["truth_K"]) - 1) < (0.01 if share <= 0.1 else 0.04)


def test_clipping_limit_is_a_third():
    assert MAX_CLIPPED_SHARE == pytest.approx(1 / 3)


# --- Fuzzing --------------------------------------------------------------------------------

NUMBERS = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                    st.sampled_from([1e308, 1e-320, 5e-324, -0.0, 3.9, 1e-9]))


@settings(max_examples=80, deadline=None)
@given(f1=NUMBERS, ratio=NUMBERS, nd=st.integers(-2, 300), m=st.integers(-2, 40),
       as_json=st.booleans())
def test_fuzz_design_filter_numbers(f1, ratio, nd, m, as_json):
    """design-filter: status 0 with finite numbers (strict JSON), or 2 with a message."""
    args = ["design-filter", "--f1", repr(f1), "--ratio", repr(ratio), "--nd", str(nd),
            "--m", str(m)] + (["--json"] if as_json else [])
    rc, out, err = run(args)
    assert rc in (0, 2), err
    assert "Traceback" not in err and "internal error" not in err
    if rc == 0 and as_json:
        assert all(np.isfinite(v) for v in _strict(out).values())
    elif rc == 0:
        assert "inf" not in out and "nan" not in out


@st.composite
def diagnose_log(draw):
    """The 20 s log cut to 500-2000 rows, a few cells or metadata values replaced."""
    return draw(st.integers(500, 2000)), draw(st.lists(st.tuples(
        st.integers(1, 499), st.integers(0, 4),
        st.sampled_from(["nan", "1e300", "0", "-1e6", "abc", "1_0", "", "3.5"])), max_size=3)),\
        draw(st.sampled_from([None, ("sample_rate_hz", "353"), ("tau_max", "1"),
                              ("kv", "-5188"), ("gravity", "1e9"), ("axis", "prismatic")]))


@pytest.mark.slow
@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(case=diagnose_log())
def test_fuzz_diagnose(sim, case):
    """diagnose on cut, edited logs: status 0 with one strict JSON object, or 2 naming the
    file; never a traceback."""
    n, cells, meta = case
    lines = sim[2].splitlines()
    head = sim[2].count("\n#") + 2
    text = "\n".join(lines[:head + n]) + "\n"
    for row, col, value in cells:
        text = _cell(row, col, value)(text)
    if meta is not None:
        text = _meta(text, *meta)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzz.csv"
        path.write_text(text)
        rc, out, err = run(["diagnose", path, "--json", "--no-forward"])
    assert rc in (0, 2), err
    assert "Traceback" not in err and "internal error" not in err
    if rc == 0:
        assert isinstance(_strict(out), dict)
    else:
        assert err.startswith("jointbench diagnose: error: ")


@settings(max_examples=150, deadline=None)
@given(cell=st.one_of(st.text(st.characters(blacklist_categories=("Cc", "Cs", "Zl", "Zp"),
                                            blacklist_characters=",\x1c\x1d\x1e\x85"),
                              max_size=12), st.sampled_from(
    ["1_000", "\u0661", "\uff11", "1e300", "-1e13", "+3.5", " 2 ", "0x10", "nan", "1e-320"])))
def test_fuzz_loader_cells_are_strict_numbers(cell):
    """A cell the loader accepts is an ASCII number without digit separators, finite and at
    most 1e12 in magnitude; anything else is an error naming line 4, column 'tau_m'."""
    from jointbench.identification.log import LogError, parse_log
    text = f"t,q_m,tau_m\n0,0,1\n0.01,0,1\n0.02,0,{cell}\n0.03,0,1\n"
    try:
        log = parse_log(text, "f.csv")
    except LogError as err:
        assert str(err).startswith("f.csv")
        return
    assert cell.isascii() and "_" not in cell
    assert np.isfinite(log.tau_m[2]) and abs(log.tau_m[2]) <= 1e12
