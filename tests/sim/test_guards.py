"""Issue 16 items 4-5, issue 14 item 4: no confident wrong answer from `diagnose` or
`identify` on a log that is mislabelled, too short or clipped. One parametrised test per class;
every attack is derived from one 20 s prototype log (seed 1)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from jointbench.bench.analysis.diagnose import cross_validate, diagnose
from jointbench.bench.analysis.diagnose.run import diagnosis_settings
from jointbench.bench.sim.experiment import run_experiment
from jointbench.identification.identify import identify
from jointbench.identification.checks.plausibility import sanity_warnings


@pytest.fixture(scope="module")
def base(bench_log):
    return bench_log("prototype", duration=20.0, seed=1)


def _rows(log, a: int, b: int):
    pick = slice(a, b)
    return dataclasses.replace(log, t=log.t[pick] - log.t[a], q_m=log.q_m[pick],
                               q=log.q[pick], tau_m=log.tau_m[pick], q_ref=log.q_ref[pick])


def _attack(log, name: str):
    if name == "clean":
        return log
    if name == "slice":          # 1000 rows from the middle of the chirp
        return _rows(log, 3000, 4000)
    if name == "head":           # the first 1000 rows (0.05 Hz start: one line)
        return _rows(log, 0, 1000)
    if name == "swapped":        # q and q_m exchanged
        return dataclasses.replace(log, q=log.q_m, q_m=log.q)
    if name == "sign":           # torque with the wrong sign
        return dataclasses.replace(log, tau_m=-log.tau_m)
    if name == "degrees":
        k = 180 / np.pi
        return dataclasses.replace(log, q=k * log.q, q_m=k * log.q_m, q_ref=k * log.q_ref)
    if name == "clipped":        # 30 % of the torque at the metadata's tau_max
        lim = float(np.quantile(np.abs(log.tau_m), 0.70))
        return dataclasses.replace(log, tau_m=np.clip(log.tau_m, -lim, lim),
                                   meta={**log.meta, "tau_max": repr(lim)})
    raise ValueError(name)


# (attack, verdict, words of the reason): measured before this change: swapped named torque_lag
# on a nominal K = -7.0 (now nothing passes on it); sign: none, no reason; degrees: none with K
# 57 times off and no warning; clean: none. (The slice, which does not start at rest, names
# gravity: test_slice_names_gravity_at_the_true_rest.)
@pytest.mark.parametrize("attack, verdict, says", [
    ("swapped", "inconclusive", "q and q_m look swapped"),
    ("sign", "inconclusive", "wrong sign"),
    ("degrees", "none", "no effect is significant"),   # a warning, never a veto by itself
    ("clean", "none", "no effect is significant"),
])
def test_diagnose_never_names_a_cause_that_cannot_be_true(base, attack, verdict, says):
    d = diagnose(_attack(base, attack))
    assert d.verdict == verdict and says in d.reason
    doc = d.to_json()
    assert doc["verdict"] == verdict and says in doc["reason"] and doc["named_cause"] == "none"
    assert doc["extended_parameters"] == {}
    if attack == "swapped":
        # torque_lag was the rejected cause while its search lagged the measured torque, whose
        # shrinking made any long lag fit; with the lag on the model's side nothing passes
        assert "rejected_cause" not in doc


def test_slice_names_gravity_at_the_true_rest(base):
    """1000 rows from the middle of the chirp start in motion, away from the rest the nominal
    assumes (gravity at rest at the first position): `gravity`, with its free phase, is the
    named cause, MX and MY those of the axis, and the forward view improves. (Before the
    gravity effect's MX, MY were expanded about the rest instead of the first position: MX
    came out 9 N m off, the replay 3.97 % -> 6.42 %, and the slice was inconclusive.)"""
    d = diagnose(_attack(base, "slice"))
    assert d.named_cause == "gravity"
    truth = base.truth()
    M = np.hypot(truth["MX"], truth["MY"])
    for k in ("MX", "MY"):   # measured -0.71 and -52.6 for -0.72 and -53.4
        assert abs(d.extended_parameters[k] - truth[k]) < 0.05 * M
    assert d.forward_extended.tau_rel_pct < d.forward_nominal.tau_rel_pct   # 4.68 % -> 2.96 %


# (attack, words each warning must hold; () = no warning). Before: none of them warned
# (slice: rigid with J +23.6 %, a note; swapped: relative error 66.8 %, a note; sign: notes).
@pytest.mark.parametrize("attack, says", [
    ("head", ("too short or too narrow-band",)),
    ("swapped", ("look swapped", "explains too little")),
    ("sign", ("wrong sign", "explains too little")),
    ("clean", ()),
])
def test_identify_warns_with_the_likely_cause(base, attack, says):
    log = _attack(base, attack)
    warnings = sanity_warnings(identify(log), log)
    assert len(warnings) == len(says)
    for text, words in zip(warnings, says):
        assert words in text


def test_diagnose_warns_on_units_and_leaves_clipped_rows_out(base):
    """Degrees: the units warning identify gives. 30 % clipped: the nominal K from the rows
    left (before: K = 1360 against the truth 20341, -93 %, and torque_lag named)."""
    d = diagnose(_attack(base, "degrees"), forward=False)
    assert any("look like degrees" in w for w in d.warnings)
    d = diagnose(_attack(base, "clipped"), forward=False)
    assert any("left out of the fit" in w for w in d.warnings)
    K = d.nominal_parameters["K"]
    truth = base.truth()["K"]
    assert abs(K / truth - 1) < 0.05    # measured -2.7 % (identify: -2.69 %)
    assert d.inverse.nominal.sig.keep is not None and not d.inverse.nominal.sig.keep.all()


def test_validate_designs_the_other_logs_band_from_it(base):
    """B at 1000 Hz: with A's band (wn 176 rad/s, Nd 26 at 350.87 Hz) its inverse errors were
    63 % and 81 %; with its own they are those of a model that fits."""
    other = run_experiment("prototype", duration=20.0, seed=3, sample_rate_hz=1000.0).log
    d = diagnose(base, forward=False)
    own = cross_validate(d, other, settings=diagnosis_settings(other)[0])["inverse"]["nominal"]
    assert own["motor"] < 2.0 and own["link"] < 4.0   # measured 0.79 %, 2.04 %
