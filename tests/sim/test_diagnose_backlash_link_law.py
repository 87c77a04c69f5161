"""A weak backlash named with its own link friction law, and a wide one with a grid that
reaches its width (identification.discrepancy.candidates._own_law, identification.effects.
backlash.grid).

The soft case: the independent simulator's soft family (f1 4 Hz), without velocity
feedforward or torque noise, a backlash of half-width 2.4 mrad (7 % visibility). Its sweep
passes the mode in the log's first quarter; later the deflection stays inside the band. The
nominal's link friction law, searched without the dead band, comes out sharper than the
simulator's tanh(q' / 1 mrad/s) and takes up part of the dead band's misfit at the link-torque
reversals: tested against it with that law, the dead band fails its bar; with the law its
own model fits best (the simulator's, within a factor of two), it passes.

The feed-forward case: the same family with velocity feedforward, a backlash of half-width
4.45 mrad (7 % visibility). Its evidence is in the harmonics of the dead band's kink, which
the chooser's band cuts: there it fails, and the wide band's view over every segment
confirms it at half the round's level (identification.discrepancy.lag_band).

The lab-rig case: the independent simulator's lab rig, a soft spring behind a backlash of
half-width 0.33 rad, where the link spends most of the log inside the band: the width lies
beyond 0.8 of the deflection's 95th percentile, where the width's grid used to stop.
"""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose import diagnose
from jointbench.bench.analysis.diagnose.claims import failing_claims
from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.campaign.battery import Place
from jointbench.bench.campaign.visibility import visibility
from jointbench.identification.discrepancy.candidates import (_searched, candidate, design,
                                                              reference)
from jointbench.identification.discrepancy.nominal import nominal, with_link_law
from jointbench.identification.effects import EFFECTS
from jointbench.identification.output_values import finite_json
from jointbench.testing import IndepRunner, LabRigRunner

SOFT = Place("indep", "soft")
SOFT_BACKLASH = ("backlash", 0.0024, {})
SOFT_SEED = 1222795584
V_S = 1e-3   # the simulator's Coulomb smoothing speed [rad/s] (tests/indep/simulator.py)

FF_BACKLASH = ("backlash", 0.00445, {})
FF_SEED = 98210002

LAB = Place("lab", "lab_rig")
LAB_BACKLASH = ("backlash", 0.3296, {})
LAB_SEED = 1268252601


@pytest.fixture(scope="module")
def soft_runner():
    return IndepRunner(40.0)


@pytest.fixture(scope="module")
def soft_log(soft_runner):
    return soft_runner.log(SOFT, (SOFT_BACKLASH,), SOFT_SEED, False, False)


@pytest.fixture(scope="module")
def lab_log():
    return LabRigRunner(40.0).log(LAB, (LAB_BACKLASH,), LAB_SEED, True, False)


def test_the_soft_backlash_is_weak(soft_runner, soft_log):
    """It changes the in-band motor torque by 5 to 10 % (the battery's visibility)."""
    _, f1, _ = soft_runner.scales(SOFT)
    clean = soft_runner.log(SOFT, (), SOFT_SEED, False, False).tau_m
    assert 0.05 < visibility(clean, soft_log.tau_m, f1, soft_runner.rate_hz) < 0.10


def test_the_soft_backlash_is_named_alone_with_its_test(soft_log):
    d = diagnose(soft_log, forward=False)
    assert [c.effect for c in d.causes] == ["backlash"]
    assert d.causes[0].test.passes
    assert d.causes[0].parameters["backlash_rad"] == pytest.approx(0.0024, rel=0.25)
    assert failing_claims(finite_json(d.to_json())) == []


def test_the_nominal_law_takes_part_of_the_dead_band(soft_log):
    """The nominal's law is sharper than the simulator's by more than a factor of two; the law
    searched beside the dead band is the simulator's within a factor of two. Against the
    nominal, the dead band with the nominal's law fails its round's bar, with its own law it
    passes, and explains more of the held-out residual."""
    settings, _ = diagnosis_settings(soft_log)
    nom = nominal(soft_log, settings)
    ref = reference(nom)
    own = candidate(nom, "backlash", ref)
    held = _searched(nom, EFFECTS["backlash"], ref, [])   # with the nominal's law
    law = with_link_law(nom, design(nom, "backlash", own.fixed)).link_v0
    assert 0 < nom.link_v0 < V_S / 2
    assert V_S / 2 < law < 2 * V_S
    assert held.p_heldout > held.level and not held.significant
    assert own.significant and own.p_heldout < own.level
    assert own.heldout_pct > held.heldout_pct > 0


def test_the_wide_band_confirms_a_backlash_the_chooser_band_misses(soft_runner):
    log = soft_runner.log(SOFT, (FF_BACKLASH,), FF_SEED, True, False)
    _, f1, _ = soft_runner.scales(SOFT)
    clean = soft_runner.log(SOFT, (), FF_SEED, True, False).tau_m
    assert 0.05 < visibility(clean, log.tau_m, f1, soft_runner.rate_hz) < 0.10
    d = diagnose(log, forward=False)
    assert [c.effect for c in d.causes] == ["backlash"]
    c = d.causes[0]
    assert not c.own_test.passes and c.test.passes
    assert c.test.view.startswith("wide band") and c.test.level <= c.alpha / 2
    assert c.second.agree
    assert c.parameters["backlash_rad"] == pytest.approx(0.00445, rel=0.25)
    assert failing_claims(finite_json(d.to_json())) == []


def test_the_wide_lab_backlash_is_within_the_grid(lab_log):
    """The width lies beyond 0.8 of the 95th percentile of |qm - q|; the grid reaches it, and
    the backlash is named alone at its width within 3 % (no hardening engaged at the width
    beside it)."""
    settings, _ = diagnosis_settings(lab_log)
    nom = nominal(lab_log, settings)
    sig = nom.sig
    d = np.abs((sig.qm - sig.q)[sig.sl])
    assert 0.8 * np.percentile(d, 95) < 0.3296 < EFFECTS["backlash"].grid(nom)[-1]
    answer = diagnose(lab_log, forward=False)
    assert [c.effect for c in answer.causes] == ["backlash"]
    assert answer.causes[0].test.passes
    assert answer.causes[0].parameters["backlash_rad"] == pytest.approx(0.3296, rel=0.03)
