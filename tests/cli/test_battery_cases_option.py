"""benchmarks/battery.py --cases: only the chosen plan indices run, each drawn as in the whole
plan (same seed, place, condition, targets); a bad index is refused with exit 2."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from jointbench.bench.campaign.battery import plan

ROOT = Path(__file__).resolve().parents[2]


def _battery():
    spec = importlib.util.spec_from_file_location("battery_cases_option",
                                                  ROOT / "benchmarks" / "battery.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _record(spec) -> dict:
    """What run_one records, without running the case: nothing named, no visibility."""
    p = spec.place
    return {"index": spec.index, "kind": spec.kind, "source": p.source, "model": p.model,
            "joint": p.joint or "", "family": p.family, "seed": spec.seed,
            "feedforward": spec.feedforward, "noise": spec.noise,
            "effects": list(spec.effects), "targets": list(spec.targets),
            "strengths": [0.0] * len(spec.effects), "options": [{}] * len(spec.effects),
            "visibilities": list(spec.targets), "combined": 0.0, "clipped_pct": 0.0,
            "named": [], "ambiguity": [], "error": "", "seconds": 0.0,
            "saturated": [False] * len(spec.effects)}


def test_cases_runs_the_chosen_indices_as_drawn_in_the_whole_plan(tmp_path, monkeypatch):
    battery = _battery()
    ran = []
    monkeypatch.setattr(battery, "_init", lambda duration: None)
    monkeypatch.setattr(battery, "run_one", lambda spec: ran.append(spec) or _record(spec))
    out = tmp_path / "out"
    assert battery.main(["--seed", "77", "--pairs", "28", "--cases", "111,39, 55,39",
                         "--out", str(out)]) == 0
    whole = plan(battery.PLACES, 8, 24, 28, 77)
    assert ran == [whole[39], whole[55], whole[111]]
    cases = json.loads((out / "cases.json").read_text())["cases"]
    assert [c["index"] for c in cases] == [39, 55, 111]
    assert [c["seed"] for c in cases] == [whole[i].seed for i in (39, 55, 111)]
    assert not (out / "detection.png").exists()       # no figure of a subset unless asked


@pytest.mark.parametrize("value, why", [("3,x", "'x' is not a case index"),
                                        ("-1", "'-1' is not a case index"),
                                        ("", "'' is not a case index"),
                                        ("5,500", "no case 500 in a plan of 116 cases")])
def test_a_bad_case_index_is_refused_with_exit_2(value, why, tmp_path, capsys):
    battery = _battery()
    with pytest.raises(SystemExit) as stop:
        battery.main(["--pairs", "28", "--cases", value, "--out", str(tmp_path / "o")])
    assert stop.value.code == 2
    assert why in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
