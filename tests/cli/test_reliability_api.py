"""The Python API checks its arguments before any numerics (bench/api_args.py): TypeError or
ValueError naming the argument and what was expected. Every refusal the command line makes
(exit 2) has its API twin raising for the same reason: both are run here side by side."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import jointbench as jb
from jointbench.bench.cli import main


@pytest.fixture(scope="module")
def log():
    return jb.simulate("prototype", duration=10.0, seed=2)


def _nan(log):
    q_m = log.q_m.copy()
    q_m[100] = np.nan
    return dataclasses.replace(log, q_m=q_m)


def _few(log):
    return dataclasses.replace(log, t=log.t[:2], q_m=log.q_m[:2], tau_m=log.tau_m[:2],
                               q=log.q[:2], q_ref=log.q_ref[:2], extra={})


def _log_file(log, path: Path) -> Path:
    """The log's CSV text, written plainly (the writer refuses what these cases hold)."""
    cols = log.columns()
    rows = np.column_stack(list(cols.values()))
    lines = [f"# {k}: {v}" for k, v in log.meta.items()] + [",".join(cols)]
    lines += [",".join(f"{x:.12g}" for x in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


# name -> (CLI arguments (a log file as {log}), API call, words both messages hold)
TWINS = {
    "negative seed": (["simulate", "--seed", "-1", "--duration", "10"],
                      lambda log: jb.simulate(seed=-1, duration=10.0), ["seed", "-1"]),
    "duration over the memory limit": (
        ["simulate", "--duration", "1e9"], lambda log: jb.simulate(duration=1e9),
        ["duration", "MB of memory", "over the", "JOINTBENCH_MAX_MEMORY_MB"]),
    "duration under the chirp's fades": (
        ["simulate", "--duration", "1"], lambda log: jb.simulate(duration=1.0),
        ["duration", "must be at least 4"]),
    "rate no log may have": (
        ["simulate", "--rate", "5", "--duration", "10"],
        lambda log: jb.simulate(sample_rate_hz=5.0, duration=10.0),
        ["must lie in [10, 1e+06]"]),
    "NaN sample": (["identify", "{nan}"], lambda log: jb.identify(_nan(log)),
                   ["q_m", "nan"]),
    "first mode beyond the Nyquist frequency": (
        ["identify", "{ok}", "--f1", "1e9"], lambda log: jb.identify(log, f1_hz=1e9),
        ["f1_hz", "the first mode must lie in [0.1, 175.4) hz"]),
    "two samples": (["identify", "{few}"], lambda log: jb.identify(_few(log)),
                    ["2 samples", "at least 3"]),
}


@pytest.mark.parametrize("case", sorted(TWINS))
@pytest.mark.parametrize("surface", ["cli", "api"])
def test_cli_refusal_and_its_api_twin(case, surface, log, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("JOINTBENCH_MAX_MEMORY_MB", "4000")
    monkeypatch.chdir(tmp_path)
    args, call, words = TWINS[case]
    if surface == "cli":
        files = {"{nan}": _log_file(_nan(log), tmp_path / "nan.csv"),
                 "{few}": _log_file(_few(log), tmp_path / "few.csv"),
                 "{ok}": _log_file(log, tmp_path / "ok.csv")}
        try:
            code = main([str(files.get(a, a)) for a in args])
        except SystemExit as exit_:        # argparse's refusal of an option's type
            code = exit_.code
        assert code == 2
        message = capsys.readouterr().err
        assert "Traceback" not in message
    else:
        with pytest.raises((TypeError, ValueError)) as err:
            call(log)
        message = str(err.value)
    for word in words:
        assert word.lower() in message.lower(), message
    assert list(tmp_path.glob("*_seed*.csv")) == []


@pytest.mark.parametrize("call, error, words", [
    (lambda log: jb.identify(dataclasses.replace(log, q_m=log.q_m[:-5])), ValueError,
     ["log.q_m", "one length"]),
    (lambda log: jb.identify(dataclasses.replace(log, q_m=list(log.q_m))), TypeError,
     ["log.q_m", "numpy array", "list"]),
    (lambda log: jb.identify(dataclasses.replace(log, tau_m=None)), TypeError,
     ["log.tau_m", "NoneType"]),
    (lambda log: jb.identify(dataclasses.replace(log, q=log.q.astype(str))), TypeError,
     ["log.q", "real numbers"]),
    (lambda log: jb.identify(jb.Log(t=np.array([]), q_m=np.array([]), tau_m=np.array([]))),
     ValueError, ["0 samples", "at least 3"]),
    (lambda log: jb.identify(log, model="joint motor"), ValueError, ["model", "joint-motor"]),
    (lambda log: jb.identify(log, f1_hz=0.0), ValueError, ["f1_hz", "above 0"]),
    (lambda log: jb.identify(42), TypeError, ["log", "file name", "int"]),
    (lambda log: jb.diagnose(log, forward="yes"), TypeError, ["forward"]),
    (lambda log: jb.simulate(sample_rate_hz=0), ValueError, ["sample_rate_hz"]),
    (lambda log: jb.simulate(seed=1.5), TypeError, ["seed", "integer"]),
    (lambda log: jb.simulate(seed=True), TypeError, ["seed", "integer"]),
    (lambda log: jb.simulate(duration=float("nan")), ValueError, ["duration", "finite"]),
    (lambda log: jb.simulate(duration="60"), TypeError, ["duration", "number", "str"]),
    (lambda log: jb.simulate(model=None), TypeError, ["model", "file name"]),
    (lambda log: jb.campaign(id_models="joint-motor", runs=1), TypeError,
     ["id_models", "('joint-motor',)", "letter by letter"]),
    (lambda log: jb.campaign(runs=0), ValueError, ["runs", ">= 1"]),
    (lambda log: jb.campaign(runs=1, method_timeout=1e10), ValueError,
     ["method_timeout", "must lie in (0,"]),
    (lambda log: jb.campaign(runs=1, seed=-1), ValueError, ["seed"]),
    (lambda log: jb.campaign(runs=1, workers=0), ValueError, ["workers"]),
    (lambda log: jb.campaign(runs=1, sweep=("noise", [1.0, float("inf")])), ValueError,
     ["sweep values[1]", "finite"]),
    (lambda log: jb.simulate(seed=2**32), ValueError, ["seed", "[0, 2**32)"]),
    (lambda log: jb.simulate(substeps=0), ValueError, ["substeps", "[1, 1000]"]),
    (lambda log: jb.simulate(foo=1), TypeError, ["unknown option", "foo", "sample_rate_hz"]),
    (lambda log: jb.simulate(effect=42), TypeError, ["effect", "backlash=0.002"]),
    (lambda log: jb.simulate("arm6", "axis2", config={"axis3": "a"}), TypeError,
     ["config['axis3']", "number"]),
    (lambda log: jb.identify(log, settings="x"), TypeError, ["settings", "FilterSettings"]),
    (lambda log: jb.diagnose(log, forward=False).write(None), TypeError, ["out", "file name"]),
    (lambda log: jb.write_log([1, 2, 3], "x.csv"), TypeError, ["log", "list"]),
    (lambda log: jb.write_log(log, None), TypeError, ["path"]),
])
def test_api_misuse_is_named_before_any_numerics(call, error, words, log, tmp_path,
                                                 monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(error) as err:
        call(log)
    for word in words:
        assert word in str(err.value), str(err.value)
    assert list(tmp_path.iterdir()) == []
