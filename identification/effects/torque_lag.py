"""`torque_lag`: the applied torque lags the command (first-order current-loop lag)."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows, searched_value

ORDER = 60

# scipy.signal (lfilter here, the filtering module for zoh_align) is imported by the functions
# that run only in diagnose: the effect registry is loaded by every virtual experiment, whose
# start-up should not pay scipy.signal's 0.8 s.


def lagged(tau: np.ndarray, T: float, ts: float) -> np.ndarray:
    """A zero-order-hold command through a first-order lag of time constant T: the lag state
    at the start of each period, x[k] = a x[k-1] + (1 - a) u[k-1], a = exp(-ts / T), x[0] = u[0]
    (the experiment starts at rest). This is what MuJoCo's exact filter actuator applies over
    the period; the mean over the period instead overestimates T by 8-30 % on the bench."""
    tau = np.asarray(tau, float)
    if T <= 0:
        return tau
    from scipy import signal

    a = np.exp(-ts / T)
    x = signal.lfilter([0.0, 1 - a], [1.0, -a], tau, zi=[a * tau[0]])[0]
    x[0] = tau[0]
    return x


def design(rows: Rows, fixed: dict) -> Design:
    # No extra column: the command of a current loop lagging by T is (1 + T d/dt) of the
    # torque the motor equation needs, so its columns are led by T and the measured torque
    # stays the left-hand side. (Lagging the measured torque instead, `lagged`, shrinks the
    # left-hand side with T and the residual with it: the search ran to its longest lag.)
    return rows.columns(lead=fixed["lag_s"])


STEP = 250.0 ** (1 / 39)   # the ratio of successive trials: 40 from 0.2 ts to 50 ts


def grid(rows: Rows) -> np.ndarray:
    """No lag, then geometric trials of ratio STEP from a fifth of the sample period ts to
    50 ts, continued at the same ratio up to D / 2 pi, D the record's length n ts.

    The led columns x + T x' tell T from the parameters' scale through the frequencies at and
    below the lag's corner 1 / (2 pi T), where the two terms are comparable. The lowest
    frequency a record holds is 1 / D (one period over the whole of it): a lag whose corner
    lies below that acts on every component the record holds as T d/dt alone, a scale the
    fitted parameters take up, and T is not identified. Up to D / 2 pi the record resolves it
    (a voltage drive under a position loop lags by a good part of a second, its corner below
    the first mode). The excitation's own lowest frequency would bound it more tightly where
    it is known, but a log need not say it; the record's length it always holds. Past 50 ts
    the trials are added on the same ratio, so the trials up to there, and a short lag's
    search, are the same on every log."""
    ts = rows.sig.ts
    short = np.geomspace(0.2 * ts, 50 * ts, 40)
    end = len(rows.sig.qm) * ts / (2 * np.pi)
    n = int(np.floor(np.log(end / (50 * ts)) / np.log(STEP) + 1e-9)) if end > 50 * ts else 0
    return np.r_[0.0, short, 50 * ts * STEP ** np.arange(1, n + 1)]


# No physical-range check on T: a current loop slower than the first mode still drives the
# axis (a voltage drive under a position loop lags with a corner below the locked mode
# sqrt(K (1/Jm + 1/JL)) / 2 pi), so the corner's place against the mode is no prior; what
# the data cannot support the held-out test, the wide view and the forward view reject.


EFFECT = Effect(
    "torque_lag", "lag_s", "s", "s",
    "the applied torque lags the command (first-order current-loop lag)",
    needs_link=False, rigid_axis=True, block=0, k=1, design=design,
    params=searched_value("lag_s"), search="lag_s", grid=grid,
    wide_view="sweep")
