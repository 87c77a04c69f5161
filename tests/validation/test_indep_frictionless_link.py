"""Issue 17, helper fs0: an axis without link Coulomb friction (a legal axis: direct-drive
links often have none). The independent simulator's soft family with FS = 0, seed 1, 60 s,
linear sweep, WITHOUT velocity feed-forward: the motor sticks at most reversals of the
chooser's band (decimated cutoff 5.4 Hz for its 4 Hz mode), the instruments predicted
linearly from q_ref cannot follow the stick-slip, and the chooser's fit put K at -51.5 %,
Jm -10.3 %, JL -51.5 % (corrected sigma 23 / 42 / 23 % of the estimate; its model's mode
3.24 Hz against the measured 3.97 Hz). The wide band (Nd 9, 15.6 Hz) fits K +0.82 %, Jm
+3.67 %, JL +0.82 % (sigma 1.06 / 1.61 / 1.06 %: the same Jm as with FS = 4, the known
motor-side residue without feed-forward, tests/validation/test_indep_accuracy.py), but the bands lie
4.7 sigma of their difference apart and the rule kept the chooser's. The measured first mode,
which designed the band and is independent of both fits, now settles the disagreement
(identification/band_choice.py, `mode_gap`). Also the rule itself on stand-in fits."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest

from jointbench.identification.band_choice import (MODE_DISAGREEMENT, choose_band, mode_gap,
                                                   wide_settings)
from jointbench.identification.filter_choice import PAPER_RATE, default_settings
from jointbench.identification.identify import identify
from jointbench.identification.log import Log
from jointbench.testing import FAMILIES


def test_soft_axis_without_link_coulomb_nor_feedforward(indep_log):
    log = indep_log(replace(FAMILIES["soft"], FS=0.0), seed=1, duration=60.0, sweep="linear",
                    feedforward=False)
    result, truth = identify(log, "joint-motor"), log.truth()
    assert result.band.used == "wide", result.band.reason
    # Before the 3-point chain took the motor's stick phases (regressors.py) the chooser's band
    # put K at -51.5 % here, 4.7 sigmas of their difference from the wide band, and the
    # measured first mode had to decide (the stand-in fits below test that rule). With them the
    # chooser's largest relative sigma is 7.5 % and the two agree within 2.0 sigmas of their
    # difference: the wide band wins on precision, and the chooser's is not kept.
    assert not any("the chooser's band kept" in w for w in result.warnings), result.warnings
    for p in ("K", "Jm", "JL"):
        z = (result.physical[p] - truth[p]) / result.physical_sigma_corrected[p]
        assert abs(z) < 3, (p, result.physical[p], z)
    # K and JL as the issue asks (measured +0.82 %); Jm +3.67 % is the no-feed-forward residue
    # the same log with FS = 4 shows (within 3 sigma above), not this case's
    for p in ("K", "JL"):
        assert abs(result.physical[p] / truth[p] - 1) < 0.01, (p, result.physical[p])
    assert abs(result.first_mode.f1_hz / log.truth()["f1_hz"] - 1) < 0.02


@dataclass(frozen=True)
class _Fit:
    settings: object
    physical: dict
    sigma: dict


def _chirp_log(seconds: float = 20.0) -> Log:
    """A 0.1-30 Hz sweep as q_ref (the wide candidate exists below the chooser's band)."""
    t = np.arange(int(seconds * PAPER_RATE)) / PAPER_RATE
    q = 0.1 * np.sin(2 * np.pi * (0.1 * t + (30.0 - 0.1) * t ** 2 / (2 * t[-1])))
    tau = np.gradient(np.gradient(q, t), t)
    return Log(t=t, q_m=q, tau_m=tau, q=q, q_ref=q, meta={"sample_rate_hz": f"{PAPER_RATE}"})


def _two_mass_f1(k: float) -> float:
    return math.sqrt(k * 2.0) / (2 * math.pi)   # Jm = JL = 1


@pytest.mark.parametrize("f1_of, used", [(1.0, "wide"), (0.5, "chooser"), (None, "chooser")])
def test_disagreeing_bands_settled_by_the_measured_mode(f1_of, used):
    """Chooser's K 0.5 +- 0.1, wide K 1.0 +- 0.01 (Jm = JL = 1): 5 sigma of their
    difference apart. A measured mode at the wide model's f1 keeps the wide fit (the
    chooser's model is sqrt(2) - 1 = 41 % off it); at the chooser's, or none, the chooser's."""
    base = default_settings(PAPER_RATE, 4.0)
    chosen = _Fit(base, {"K": 0.5, "Jm": 1.0, "JL": 1.0}, {"K": 0.1, "Jm": 0.01, "JL": 0.01})
    wide = lambda s: _Fit(s, {"K": 1.0, "Jm": 1.0, "JL": 1.0},  # noqa: E731
                          {"K": 0.01, "Jm": 0.001, "JL": 0.001})
    f1 = None if f1_of is None else _two_mass_f1(f1_of)
    candidate = wide_settings(_chirp_log(), base)
    fit, band = choose_band(chosen, wide(candidate[0]), candidate,
                            lambda f: (f.physical, f.sigma), f1)
    assert band.used == used and fit.physical["K"] == (1.0 if used == "wide" else 0.5)
    assert "one of them is biased" in band.warning


def test_mode_gap():
    p = {"K": 1.0, "Jm": 1.0, "JL": 1.0}
    assert mode_gap(p, _two_mass_f1(1.0)) == pytest.approx(0.0, abs=1e-12)
    assert mode_gap(p, _two_mass_f1(1.0) * (1 + MODE_DISAGREEMENT)) == pytest.approx(
        MODE_DISAGREEMENT)
    assert mode_gap(p, None) == math.inf
    assert mode_gap({**p, "K": -1.0}, 1.0) == math.inf
