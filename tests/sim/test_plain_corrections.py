"""The paper's chain alone and the named corrections beyond it (identification.corrections):
`identify(..., corrections=())` / `identify --plain` runs eqs. (26)-(29), (22), (13) or
(18)-(20) and least squares; each correction switches on by name, and the report lists
those that ran. On the prototype (seed 1, 60 s, the demo's log)."""

from __future__ import annotations

import json

import pytest

from jointbench.bench.cli import main
from jointbench.identification.corrections import CORRECTIONS
from jointbench.identification.filter_choice import PAPER_ND, PAPER_WN
from jointbench.identification.identify import identify
from jointbench.identification.log import write_log


@pytest.fixture(scope="module")
def plain(prototype_log):
    return identify(prototype_log, "joint-motor", corrections=())


def test_plain_is_the_papers_chain(plain):
    # the section 4 filter (wn 176 rad/s, Nd 26 at 350.87 Hz), eq. (22)'s 3 points, the torque
    # as logged, least squares, sign(qm') and sign(q') columns
    s = plain.settings
    assert (s.wn, s.Nd, s.stencil, s.zoh) == (PAPER_WN, PAPER_ND, 3, False)
    assert plain.corrections == () and plain.band is None
    assert not plain.ls.instrumental
    assert not any("reversals placed" in n for n in plain.notes)


def test_plain_is_within_its_sigma_of_the_truth_on_k(plain, prototype_log):
    # the paper's chain identifies the prototype: K, Jm, JL within 3 % (its own bias, which the
    # corrections remove, is about 1 % here) and positive
    truth = prototype_log.truth()
    for name in ("K", "Jm", "JL"):
        assert abs(plain.physical[name] / truth[name] - 1) < 0.03, name


def test_default_lists_the_corrections_that_ran(prototype_joint_motor):
    full = prototype_joint_motor
    assert {"zoh", "instruments", "reversals", "stick_phases"} <= set(full.corrections)
    assert set(full.corrections) <= set(CORRECTIONS)
    assert full.ls.instrumental


@pytest.mark.parametrize("name", ["instruments", "zoh", "reversals"])
def test_one_correction_alone(prototype_log, name):
    r = identify(prototype_log, "joint-motor", corrections=(name,))
    assert r.corrections == (name,)
    assert r.ls.instrumental == (name == "instruments")
    assert r.settings.zoh == (name == "zoh")


def test_stick_phases_need_the_reversals(prototype_log):
    r = identify(prototype_log, "joint-motor", corrections=("stick_phases",))
    assert r.corrections == ()


def test_motor_only_plain_is_eqs_18_20(prototype_log):
    r = identify(prototype_log, "motor-only", corrections=())
    assert r.model == "motor-only-printed" and r.corrections == ()
    assert r.physical == r.physical_eqs18_20   # no link reconstruction


def test_unknown_correction_is_refused(prototype_log):
    with pytest.raises(ValueError, match="unknown correction.*'instrument'"):
        identify(prototype_log, "joint-motor", corrections=("instrument",))


def test_cli_plain_json_and_bad_options(prototype_log, tmp_path, capsys):
    path = tmp_path / "proto.csv"
    write_log(prototype_log, path)
    assert main(["identify", str(path), "--model", "joint-motor", "--plain", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["corrections"] == [] and out["filter"]["stencil"] == 3
    assert main(["identify", str(path), "--model", "joint-motor", "--corrections",
                 "instruments,zoh"]) == 0
    assert "corrections beyond the paper: zoh, instruments" in capsys.readouterr().out
    assert main(["identify", str(path), "--corrections", "bogus"]) == 2
    assert "--corrections bogus" in capsys.readouterr().err
    assert main(["identify", str(path), "--plain", "--corrections", "zoh"]) == 2
    assert main(["identify", str(path), "--plain", "--stencil", "5"]) == 2


def test_plain_designs_the_band_by_eq_28_away_from_the_papers_rate():
    # at another rate the filter comes from eqs. (26)-(29): f1 = 3.9 Hz, nd = 2, m = 4 gives the
    # paper's design wn = 181.04 rad/s (ERRATA.md; section 4 rounds it to 176 at 350.87 Hz)
    from jointbench.bench.sim.experiment import run_experiment

    log = run_experiment("prototype", duration=20.0, seed=2, sample_rate_hz=500.0).log
    r = identify(log, "joint-motor", corrections=(), f1_hz=3.9)
    assert r.settings.wn == pytest.approx(181.04, abs=0.01) and r.corrections == ()
