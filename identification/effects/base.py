"""The identification half of an effect (docs/effects.md): its names and units, and what
the inverse view of `diagnose` (identification.discrepancy) needs to test it. No MuJoCo here;
the bench half (jointbench.bench.effects) writes the same names into a simulation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Protocol

import numpy as np

Design = tuple[np.ndarray, np.ndarray, tuple[str, ...]]   # y, W, column names
Column = tuple[str, "np.ndarray | None", "np.ndarray | None"]   # name, motor row, link row


class Rows(Protocol):
    """The nominal regression of one log an effect extends (identification.discrepancy.Nominal).
    `sig` holds its band-limited raw-rate signals (qm, qmd, q, qd, tau_raw, qs, g, ts, sl, lp)."""

    sig: Any
    # the speed v0 of the nominal's link friction law tanh(q' / v0), 0 for a sign
    # (identification.discrepancy.nominal.link_law)
    link_v0: float
    # the spring deflection the nominal columns are built with when a cause rebuilt it (a
    # backlash's dead zone), None for qm - q
    deflection: np.ndarray | None

    def value(self, name: str) -> float:
        """A nominal parameter."""

    def extend(self, *columns: Column,
               rated: tuple[np.ndarray | None, ...] | None = None) -> Design:
        """The nominal columns plus these raw-rate columns (motor and link equation rows).
        `rated`: for each column, the raw-rate motor rows whose 3-point difference is the
        rate a torque lag leads it by (identification.discrepancy.stacked.led_extra); None:
        its motor rows themselves."""

    def columns(self, tau: np.ndarray | None = None,
                deflection: np.ndarray | None = None, lead: float | None = None) -> Design:
        """The nominal columns rebuilt with another torque or spring deflection, or with the
        motor columns led by `lead` [s] (a lagging current loop's command)."""


@dataclass(frozen=True)
class Effect:
    """One unmodelled effect: names, units and its extended regression.

    `design(rows, fixed)` builds the extended regression with the nonlinear values `fixed`;
    those come from `reference(rows)` (values carried over from the nominal) and, for
    `search`, from a scalar search of the weighted residual over `grid(rows)`. The linear
    parameters come from least squares; `params(values, fixed, rows)` turns them into the
    reported parameters, `check(values, rows)` says why a fit is not a physical instance
    (`values`: the fitted columns and the `fixed` values, and under FOLD_FITS each fold's
    training fit of the columns, from which `spread` gives the fit's own uncertainty).
    """

    name: str
    parameter: str            # its strength in `extended_parameters`
    unit: str                 # of `parameter` on a revolute axis
    unit_prismatic: str
    what: str
    # The inverse view needs the link position q: its columns use q, or the rigid
    # motor-side model could not tell it from the nominal.
    needs_link: bool
    # A rigid bench axis (no spring, one friction) can hide it. Differs from needs_link for
    # gravity (a rigid link has gravity; its column is the link equation's) and
    # asymmetric_friction (seen on the motor side, but the bench scales the drive-chain
    # friction FVm, FSm, which a rigid axis does not split from the link's).
    rigid_axis: bool
    block: int                # 0 motor equation, 1 link equation: where its size is measured
    k: int                    # extra parameters, nonlinear ones included
    design: Callable[[Rows, dict], Design]
    params: Callable[[dict, dict, Rows], dict[str, float]]
    check: Callable[[dict, Rows], str] | None = None
    # How many of its own standard errors an unphysical fit lies beyond the physical bound
    # `check` tests (values as check's): where it is within the round's bar the fit is not
    # named but not excluded either, and may be the alternative of the effect it reduces to
    # (identification.discrepancy.inverse). None: an unphysical fit is excluded.
    beyond: Callable[[dict, Rows], float] | None = None
    search: str = ""          # the nonlinear parameter searched, a key of `fixed`
    grid: Callable[[Rows], np.ndarray] | None = None
    reference: Callable[[Rows], dict] | None = None
    # The simpler effect this one reduces to where its distinguishing part vanishes: it is
    # named over that one only when what it adds to it is significant held out
    # (identification.discrepancy.inverse). "" for none.
    reduces_to: str = ""
    # Its parts, spanning its design at every value of its search (raw-rate columns, as
    # Rows.extend takes them): the effect it reduces to can be told apart from the part
    # they share only where its column leaves their span beside the nominal's columns
    # (identification.discrepancy.inverse._shared). None: no such parts.
    parts: Callable[[Rows], tuple[Column, ...]] | None = None
    # For a torque periodic in the motor angle, the parameter holding its period [rad]: the
    # forward view judges it only where a replay keeps its phase
    # (bench.analysis.diagnose.forward). "" for none.
    period: str = ""
    # Its extended model holds its own link friction law near zero speed, searched on its
    # design (identification.discrepancy.candidates._own_law): its misfit sits where the law
    # acts (a dead band's, at the link-torque reversals) and the nominal's law, searched
    # without it, takes part of it up.
    own_link_law: bool = False
    # The view it gets in a band reaching the excitation's top when the chooser's band does
    # not find it (identification.discrepancy.lag_band.second_view): "sweep" (every segment
    # and the top of the sweep), "deflection" (the spring's engagements at large
    # deflections), "width" (every segment, its width against the chooser's band's); ""
    # none.
    wide_view: str = ""
    # It acts in the spring's law or its damping (the deflection and its rate), and whether
    # the sweep shows it where it passes the mode: tested against a model holding another
    # effect of the spring it gets a view where it is visible (lag_band.where_visible).
    in_spring: bool = False
    at_the_mode: bool = False
    # Its column is zero until |qm - q| passes its searched value (a hardening's engagement):
    # its held-out test counts each engagement of the spring apart, in every band
    # (identification.discrepancy.heldout.engagement_units).
    engages: bool = False
    # The columns its design tends to, beyond the nominal's, as its searched value goes to 0
    # (a dead band's first order in its width: a torque of the spring's sign): it is tested
    # against the reference extended by them (identification.discrepancy.candidates.
    # beyond_limit), so that what it is credited with is what that limit cannot explain.
    # None: its limit is the nominal itself.
    limit: Callable[[Rows], tuple[Column, ...]] | None = None

    def unit_for(self, prismatic: bool) -> str:
        return self.unit_prismatic if prismatic else self.unit


def column_value(column: str, parameter: str) -> Callable[[dict, dict, Rows], dict]:
    """`params` of an effect that reports one fitted column under its parameter name."""
    return lambda v, fixed, rows: {parameter: v[column]}


def searched_value(key: str) -> Callable[[dict, dict, Rows], dict]:
    """`params` of an effect that reports its searched value alone (no extra column)."""
    return lambda v, fixed, rows: {key: fixed[key]}


# The key of `check`'s values holding each held-out fold's training fit (a tuple of dicts of
# the fitted columns; empty when the folds were not fitted).
FOLD_FITS = "fold_fits"


def spread(folds: tuple[dict, ...], f: Callable[[dict], float]) -> float:
    """The standard error of a fitted quantity f(values) by the delete-a-group jackknife over
    the k training fits (each leaves one fold out): var = (k - 1) / k sum (f_i - mean f)^2.
    The folds are contiguous pieces spread over the whole log, so the spread holds what the
    residual's correlation in time does to the fit, which the least-squares covariance of
    white noise understates. 0 without folds."""
    if len(folds) < 2:
        return 0.0
    v = np.array([f(x) for x in folds], dtype=float)
    k = len(v)
    return float(np.sqrt((k - 1) / k * np.sum((v - v.mean()) ** 2)))


def sign0(x: np.ndarray) -> np.ndarray:
    """sign(x) with NaN (undefined derivative samples) counted as 0."""
    return np.sign(np.nan_to_num(x))


def spring_sign(rows: Rows) -> tuple[Column, ...]:
    """The first order of a spring law with a dead band in its searched value (Effect.limit):
    the spring torque's sign s(qm - q), in both equations (action and reaction, eqs. 5-6),
    hat-weighted as the nominal's deflection (hat).

    Beyond a band of half-width b, dz(d, b) = d - b s(d) (d = qm - q): a backlash K dz(d, b)
    and a hardening K d + Kh dz(d, dh) whose band is narrower than the deflections the
    spring spends its time at add to the nominal's K d a torque of the spring's sign, and
    differ from it only on the rows inside the band. A torque of the spring's sign is also
    part of the nominal's own misfit near zero speed: a link or motor that sticks is held by
    friction against the spring, with the spring torque's sign, where the friction law
    claims FS tanh(q' / v0) of the filtered speed and the motor's FSm s(qm'). On an axis
    whose motor a torque ripple makes stick, a band of a few link-encoder counts takes that
    misfit up at the link's reversals late in the sweep, where the link creeps, and passes
    its test. What only the spring law explains is the band (the spring holding no torque,
    or K alone, inside it): it is tested against the reference holding this column."""
    s = hat(sign0(rows.sig.qm - rows.sig.q))
    return (("spring_sign", s, -s),)


def deadzone(d: np.ndarray, b: float) -> np.ndarray:
    """d - b sign(d) beyond +-b, 0 inside: the spring deflection of a transmission with
    backlash of half-width b (MuJoCo's two-valued tendon springlength)."""
    return np.sign(d) * np.maximum(np.abs(d) - b, 0.0)


def hat(x: np.ndarray) -> np.ndarray:
    """x as the 3-point second difference sees it: (x[k-1] + 10 x[k] + x[k+1]) / 12.

    The second difference (x[k+1] - 2 x[k] + x[k-1]) / T^2 is the mean of x'' over
    [t[k-1], t[k+1]] weighted by the hat (T - |s|) / T^2, so the equation it enters pairs the
    acceleration with the hat-weighted mean of the forces; for the spring torque K (qm - q),
    that mean is K d + K T^2 / 12 d'' + ..., which the (1, 10, 1) / 12 taps give. (The held
    torque's mean of zoh_align is already exact for it.) Sampled instead, the spring torque is
    off by (w T)^2 / 12 of itself, 0.4 % at 12 Hz and the paper's rate (PAPER_RATE).
    """
    x = np.asarray(x, dtype=float)
    out = x.copy()
    out[1:-1] = (x[:-2] + 10 * x[1:-1] + x[2:]) / 12
    return out
