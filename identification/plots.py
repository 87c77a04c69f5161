"""Plots of the bandpass design, Pham, Gautier, Poignet 2001, section 3.2.

pyplot is imported inside the functions and no backend is chosen here: the caller picks
it (e.g. Agg for headless runs) before the first plot.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from jointbench.identification.design import butterworth_magnitude, central_difference_magnitude
from jointbench.identification.log.write import save_figure_atomic

if TYPE_CHECKING:
    import matplotlib.figure

__all__ = ["Figure1Setup", "figure1_setup", "plot_figure1", "save_figure_atomic"]


@dataclass(frozen=True)
class Figure1Setup:
    """Parameters of the paper's Figure 1.

    Attributes:
        wn: Butterworth cutoff (rad/s). The paper does not state it and its picture is
            lost in the text we have; 100 rad/s, a decade below ws/2, is an assumption.
        ts: sampling period (s); ws/2 = pi / Ts = 1e3 rad/s as stated in section 3.2.
        m: forward Butterworth order (the figure's caption says m = 2).
    """

    wn: float
    ts: float
    m: int


def figure1_setup() -> Figure1Setup:
    """Default parameters for Figure 1: wn = 100 rad/s (assumed), ws/2 = 1e3 rad/s, m = 2."""
    return Figure1Setup(wn=100.0, ts=math.pi / 1.0e3, m=2)


def _finish(fig: matplotlib.figure.Figure, path: str | os.PathLike[str] | None
            ) -> matplotlib.figure.Figure:
    """Lay the figure out and save it at `path` when given (`save_figure_atomic`)."""
    fig.tight_layout()
    if path is not None:
        save_figure_atomic(fig, path)
    return fig


def plot_figure1(
    wn: float,
    ts: float,
    m: int = 2,
    path: str | os.PathLike[str] | None = None,
) -> matplotlib.figure.Figure:
    """Reproduce Figure 1: magnitudes |H|, |D| and |F| = |H| |D| against w, log-log.

    |H| is eq. (25) (forward-reverse Butterworth, order m), |D| is eq. (24) (central
    difference), F = H D is the band-limited derivative filter. The frequency axis runs
    from 1 rad/s to just below ws/2 = pi / Ts, where |D| vanishes (log axes cannot show 0).

    Args:
        wn: Butterworth cutoff (rad/s), > 0.
        ts: sampling period Ts (s), > 0; the paper uses ws/2 = 1e3 rad/s, Ts = pi / 1e3.
        m: forward Butterworth order, >= 1 (the paper: 2).
        path: if given, the PNG is written there atomically.

    Returns:
        The matplotlib Figure.

    Raises:
        ValueError: if wn, ts or m is invalid (see identification.design).
        OSError: if the PNG cannot be written.
    """
    import matplotlib.pyplot as plt

    # Evaluate once so bad wn, m, ts raise ValueError before any figure is created.
    butterworth_magnitude(0.0, wn, m)
    central_difference_magnitude(0.0, ts)
    nyquist = math.pi / float(ts)
    # Stop just short of ws/2: |D(j ws/2)| = 0 has no logarithm.
    w = np.logspace(0.0, math.log10(0.999 * nyquist), 1000)
    h = butterworth_magnitude(w, wn, m)
    d = central_difference_magnitude(w, ts)
    f = h * d

    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    ax.loglog(w, h, label=r"$|H(j\omega)|$ Butterworth, eq. (25)")
    ax.loglog(w, d, label=r"$|D(j\omega)|$ central difference, eq. (24)")
    ax.loglog(w, f, label=r"$|F(j\omega)| = |H||D|$ bandpass")
    ax.loglog(w, w, ":", color="gray", label=r"$\omega$ (ideal derivative)")
    ax.axvline(wn, color="k", lw=0.6, ls="--")
    ax.annotate(r"$\omega_n$", (wn, 1e-3), xytext=(4, 0), textcoords="offset points")
    ax.set_xlabel(r"$\omega$ (rad/s)")
    ax.set_ylabel("magnitude (|H| dimensionless; |D|, |F| in 1/s)")
    ax.set_ylim(1e-4, 2.0 * nyquist)
    ax.set_title(f"Figure 1: magnitude of filters (m = {m})")
    ax.grid(True, which="both", lw=0.3)
    ax.legend(loc="lower left")
    return _finish(fig, path)



def plot_validation(t: np.ndarray, measured: np.ndarray, predicted: np.ndarray,
                    rel_error_pct: float, path: str | os.PathLike[str] | None = None,
                    title: str = "Figure 2: direct validation",
                    unit: str = "N m") -> "matplotlib.figure.Figure":
    """Figure 2: measured and predicted motor torque on the decimated samples, with the
    residual and the relative error 100 ||y - W X^|| / ||y||; `unit` N m, or N for a
    prismatic axis."""
    import matplotlib.pyplot as plt

    fig, (ax, axr) = plt.subplots(2, 1, figsize=(9.0, 6.0), sharex=True,
                                  gridspec_kw={"height_ratios": [3, 1]})
    ax.plot(t, measured, lw=1.0, label="measured $\\tau_m$")
    ax.plot(t, predicted, lw=1.0, ls="--", label="predicted $W\\hat{X}$")
    ax.set_ylabel(f"motor torque tau_m ({unit})")
    ax.set_title(f"{title}: measured and predicted motor torque (relative error "
                 f"{rel_error_pct:.2f} %)")
    ax.legend()
    ax.grid(True, lw=0.3)
    axr.plot(t, measured - predicted, lw=0.8, color="C3")
    axr.set_ylabel(f"measured - predicted ({unit})")
    axr.set_xlabel("t (s)")
    axr.grid(True, lw=0.3)
    return _finish(fig, path)


def plot_frf(f_hz: np.ndarray, measured: np.ndarray, models: dict[str, np.ndarray],
             coherence: np.ndarray | None = None, f1_hz: float | None = None,
             path: str | os.PathLike[str] | None = None,
             title: str = "Frequency response q_m / tau_m",
             units: tuple[str, str] = ("rad", "N m")) -> "matplotlib.figure.Figure":
    """Bode magnitude and phase of the measured q_m / tau_m against model responses;
    `units` (position, torque): rad and N m, or m and N for a prismatic axis."""
    import matplotlib.pyplot as plt

    band = f_hz > 0
    fig, (axm, axp) = plt.subplots(2, 1, figsize=(8.0, 6.5), sharex=True)
    axm.loglog(f_hz[band], np.abs(measured[band]), ".", ms=3, label="measured (from the log)")
    axp.semilogx(f_hz[band], np.degrees(np.angle(measured[band])), ".", ms=3)
    for label, H in models.items():
        axm.loglog(f_hz[band], np.abs(H[band]), lw=1.2, label=label)
        axp.semilogx(f_hz[band], np.degrees(np.angle(H[band])), lw=1.2)
    if f1_hz:
        for a in (axm, axp):
            a.axvline(f1_hz, color="k", ls="--", lw=0.6)
    axm.set_ylabel(f"|q_m / tau_m| ({units[0]} / ({units[1]}))")
    axp.set_ylabel("phase (deg)")
    axp.set_xlabel("f (Hz)")
    axm.set_title(title)
    axm.legend(fontsize=8)
    for a in (axm, axp):
        a.grid(True, which="both", lw=0.3)
    return _finish(fig, path)
