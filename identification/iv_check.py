"""The instrumental-variable estimate held against least squares on the same rows.

The joint-motor model is solved with instruments Z built from q_ref
(identification/instruments.py): X_IV = (Z^T W)^-1 Z^T y. They remove the closed loop's
torque-noise bias only when Z is uncorrelated with the equation error. A model error that
follows the motion deterministically breaks that: where the motor sticks (no feed-forward, no
torque noise to dither it) the Coulomb column's error is a function of the motion, and the
reference's linear prediction of that motion is correlated with it as much as the motion is.
Least squares projects the error orthogonally onto W; the instruments project it obliquely,
through (Z^T W)^-1, and a direction that Z predicts poorly (on a frictionless link, the scale
shared by K, JL and FV, which the link equation leaves free and only the motor equation's
deflection column fixes) amplifies it. The reversal passes (`identify._place_reversals`) then
build the motor's stick phases from that estimate, which makes the model error larger still.

The test (`compare`) is Hausman's (1978): both estimates come from the same rows, so
when both are consistent their difference d = X_IV - X_LS is noise alone. Hausman's variance
of d, V_IV - V_LS, holds only when least squares is efficient, which the filtered,
decimated residuals' colour rules out (the reason for the corrected covariance,
identification/uncertainty.py): with the two corrected sigmas nearly equal it shrinks to almost
nothing, and clean logs would fail it. Whatever their correlation, though,
sd(d) <= sigma_IV + sigma_LS (the triangle inequality for standard deviations), so

    z_p = |X_IV,p - X_LS,p| / (sigma_IV,p + sigma_LS,p),   p in K, Jm, JL,

exceeds the two-sided normal quantile z* = Phi^-1(1 - ALPHA / (2 m)) with probability at most
ALPHA / m per parameter when both are consistent, and at most ALPHA for the largest of the
m = 3 (Bonferroni). ALPHA is the stated false-alarm rate per fit. Least squares' own
closed-loop bias, though, is a fixed share of the parameters while both sigmas shrink as the
log grows, so on long noisy logs the test fires on it (the six-axis arm, 240 s: 4.2). A
disagreement alone therefore does not reject the instruments (`identify._check_instruments`):
the instrument passes are run again from the chain without instruments (least squares and
its reversal passes), and the instruments are rejected only when the two instrumental fits
differ by the same test, that is when the passes' answer depends on their start, which is
what a first pass correlated with the model's error and fed back does. Then least squares is
kept with a warning naming the cause; otherwise the instruments' fit stays, unchanged, with a
warning that names both explanations (the test cannot tell least squares' bias from
instruments invalid wherever they start). Pure numerics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.stats import norm

from jointbench.identification.estimate import LSResult

IV_PARAMS = ("K", "Jm", "JL")
ALPHA = 1e-3   # false-alarm rate per fit when both estimates are consistent


def z_threshold(alpha: float = ALPHA, m: int = len(IV_PARAMS)) -> float:
    """The largest of m two-sided standard normal deviates exceeds this with probability at
    most alpha: Phi^-1(1 - alpha / (2 m)) (Bonferroni). 3.59 for alpha = 1e-3, m = 3."""
    if not 0 < alpha < 1 or m < 1:
        raise ValueError(f"alpha must lie in (0, 1) and m be >= 1, got {alpha}, {m}")
    return float(norm.isf(alpha / (2 * m)))


@dataclass(frozen=True)
class Gap:
    """`compare`'s outcome: the parameter `name` of IV_PARAMS whose two estimates lie
    farthest apart, `z` that distance in units of sigma_a + sigma_b (corrected sigmas), the
    two values `a`, `b` and sigmas there, the false-alarm rate `alpha` and its threshold z*."""

    name: str
    z: float
    a: float
    b: float
    sigma_a: float
    sigma_b: float
    threshold: float
    alpha: float = ALPHA

    @property
    def fired(self) -> bool:
        """True when the two estimates are farther apart than the bound allows at the
        stated false-alarm rate."""
        return self.z > self.threshold

    def kept_warning(self, restarted: float | None) -> str:
        """The warning for an instrumental fit `a` kept against least squares `b`: its
        passes started from least squares gave `restarted` (None: no passes)."""
        again = ("" if restarted is None else
                 f"; started from least squares' estimate the instrument passes give "
                 f"{restarted:.4g}, so the gap is not their start")
        return (f"instruments and least squares disagree: the instruments put {self.name} at "
                f"{self.a:.4g} +- {self.sigma_a:.2g}, least squares on the same rows at "
                f"{self.b:.4g} +- {self.sigma_b:.2g}, {self.z:.1f} times the sum of their "
                f"sigmas apart (at most {self.threshold:.2f} when both are consistent, "
                f"false-alarm rate {self.alpha:g}){again}: least squares' closed-loop bias (the "
                "torque noise moves the positions; more sigmas the longer the log), or "
                "instruments correlated with the model's error wherever they start; "
                "instruments kept")

    def warning(self, restarted: float) -> str:
        """The warning that names the cause, for an instrumental fit `a` rejected against
        least squares `b`, whose passes started from least squares gave `restarted`."""
        return (f"instruments from q_ref rejected: their passes put {self.name} at "
                f"{self.a:.4g} +- {self.sigma_a:.2g}, least squares on the same rows at "
                f"{self.b:.4g} +- {self.sigma_b:.2g}, {self.z:.1f} times the sum of their "
                f"sigmas apart (at most {self.threshold:.2f} when both are consistent, "
                f"false-alarm rate {self.alpha:g}), and started from least squares' estimate the "
                f"same passes give {restarted:.4g}: the instruments are correlated with the "
                "model's error (the reference's prediction misses motion, such as a sticking "
                "motor's, that the error follows too) and the reversal passes fed it back; "
                "least squares kept, the other corrections as they were")


def compare(a: LSResult, b: LSResult, params: tuple[str, ...] = IV_PARAMS,
            alpha: float = ALPHA) -> Gap | None:
    """The largest z_p = |X_a,p - X_b,p| / (sigma_a,p + sigma_b,p) over `params` (module
    docstring) of two fits of the same log, with their corrected sigmas, and the threshold
    for `alpha`; None when a parameter is missing from either or a sigma is not finite
    (nothing to test)."""
    z, worst = -1.0, None
    for p in params:
        if p not in a.names or p not in b.names:
            return None
        va, vb = a.value(p), b.value(p)
        sa, sb = a.std_corrected(p), b.std_corrected(p)
        if not all(math.isfinite(x) for x in (va, vb, sa, sb)) or not sa + sb > 0:
            return None
        zp = abs(va - vb) / (sa + sb)
        if zp > z:
            z, worst = zp, (p, va, vb, sa, sb)
    if worst is None:
        return None
    return Gap(worst[0], z, *worst[1:], z_threshold(alpha, len(params)), alpha)
