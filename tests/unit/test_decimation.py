"""The diagnosis's common decimation (identification.discrepancy.signals): its zero-phase
anti-alias filter against scipy.signal.sosfiltfilt on the columns a dead band makes (exact
zeros inside the band, where the filter's states would decay into subnormal numbers), and
Signals.dec's results kept by the content of the column (no MuJoCo)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import signal

from jointbench.identification.discrepancy.inverse import diagnose_inverse
from jointbench.identification.discrepancy.signals import _antialias, _filtfilt, signals
from jointbench.identification.effects.base import deadzone
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.filtering import FilterSettings
from jointbench.identification.log import Log


def _deflection(n: int) -> np.ndarray:
    """A swept deflection that dwells near 0 for most of its length: a dead band of 2 mrad
    leaves long runs of exact zeros in its column."""
    t = np.arange(n) / PAPER_RATE
    return 3e-3 * signal.chirp(t, 0.2, t[-1], 15.0) * np.exp(-t / 8.0)


@pytest.mark.parametrize("q", [2, 5, 9, 26])
@pytest.mark.parametrize("column", ["dead band", "noise", "step"])
def test_filtfilt_is_sosfiltfilt_bit_for_bit(q, column):
    n = 21049
    x = {"dead band": lambda: deadzone(_deflection(n), 2e-3),
         "noise": lambda: np.random.default_rng(q).normal(size=n),
         "step": lambda: np.r_[np.ones(300), np.zeros(n - 300)]}[column]()
    if column == "dead band":
        assert np.mean(x == 0) > 0.5   # the case the states' flush is for
    # the same recursion, by chunks, with states under sqrt(tiny) (1.5e-154) set to 0: what
    # that changes (the flushed states times the sections' gains, and the rounding of the
    # outputs that small) stays in outputs under 1e-100; every larger one is the same double
    # (no tolerance: a changed bit is a changed result)
    ref = signal.sosfiltfilt(_antialias(q)[0], x)
    got = _filtfilt(q, x)
    big = np.abs(ref) > 1e-100
    assert np.array_equal(got[big], ref[big])
    assert np.all(np.abs(got - ref) <= 1e-120)


def test_chunk_keeps_states_out_of_the_subnormal_range():
    # over one chunk the fastest pole takes a state at sqrt(tiny) no lower than tiny
    for q in (2, 9, 26):
        sos, _, _, chunk = _antialias(q)
        r = min(np.abs(np.roots([1.0, *a])).max() for a in sos[:, 4:])
        tiny = np.finfo(float).tiny
        assert np.sqrt(tiny) * r ** chunk >= tiny * (1 - 1e-9)


def _log(seconds: float = 20.0) -> Log:
    t = np.arange(int(seconds * PAPER_RATE)) / PAPER_RATE
    qm = 0.1 * signal.chirp(t, 0.1, t[-1], 20.0) * signal.windows.tukey(len(t), 0.2)
    tau = np.gradient(np.gradient(qm, t), t) + 0.3 * np.sign(np.gradient(qm, t))
    return Log(t=t, q_m=qm, tau_m=tau, q=qm - 1e-3 * tau, q_ref=qm,
               meta={"sample_rate_hz": f"{PAPER_RATE}"})


def test_dec_keeps_results_by_content_not_by_array():
    s = signals(_log(), FilterSettings(wn=176.0, m=4, Nd=9, ts=1 / PAPER_RATE))
    x = deadzone(s.qm - s.q, 1e-4)
    first = s.dec(x)
    first[:] = np.nan                       # a caller's own copy: the kept one is not touched
    again = s.dec(x.copy())                 # the same content in another array
    full, e = _filtfilt(9, x[s.sl])[::9], s.settings.edge
    assert np.array_equal(again, full[e:len(full) - e])
    assert not np.array_equal(s.dec(1.5 * x), again)
    # a copy with other rows kept gets its own results, not the original's
    kept = np.arange(len(s.index)) % 2 == 0
    half = dataclasses.replace(s, keep=kept, index=s.index[kept])
    assert np.array_equal(half.dec(x), again[kept])


def test_a_diagnosis_answer_does_not_hold_the_trials():
    # the rounds decimate hundreds of trial columns; the answer keeps the nominal's rows only
    settings = FilterSettings(wn=176.0, m=4, Nd=9, ts=1 / PAPER_RATE)
    inv = diagnose_inverse(_log(), settings, effects=("backlash", "offset"))
    assert len(inv.nominal.sig._decimated) == 0
    assert inv.nominal.sig.dec(inv.nominal.sig.qm).shape == inv.nominal.sig.index.shape
