"""`backlash`: a dead zone of half-width b in the transmission deflection qm - q."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import (Design, Effect, Rows, deadzone,
                                                    spring_sign)

ORDER = 40


def design(rows: Rows, fixed: dict) -> Design:
    sig, b = rows.sig, fixed["backlash_rad"]
    return rows.columns(deflection=deadzone(sig.qm - sig.q, b) if b > 0 else None)


# The geometric steps the width's grid takes past the deflections the spring spends most of
# its time at (grid).
TAIL = 10


def grid(rows: Rows) -> np.ndarray:
    """Widths from 0 in 40 equal steps to 0.8 of the 95th percentile of |qm - q|, then TAIL
    geometric steps on to 0.98 of the largest |qm - q|.

    The deflection of a transmission with backlash of half-width b is |qm - q| <= b +
    |tau_s| / K: where the spring is soft against the torque it carries (a lab rig's spring
    holds a few hundredths of a N m over a band of a third of a rad), the link spends most of
    the log inside the band and b lies near or above the deflection's 95th percentile, where
    the equal steps end; a search that stops there returns the grid's top and leaves the
    rest of the band to a hardening engaged at the true width. The tail reaches the largest
    deflection, short of it so that the column K dz(qm - q, b) is never empty, in few steps
    (the search refines between the best point's neighbours)."""
    sig = rows.sig
    d = np.abs((sig.qm - sig.q)[sig.sl])
    typical, top = 0.8 * float(np.percentile(d, 95)), 0.98 * float(np.max(d))
    steps = np.linspace(0.0, typical, 41)
    if not (top > typical > 0):
        return steps
    return np.concatenate([steps, np.geomspace(typical, top, TAIL + 1)[1:]])


def grid_step(rows: Rows, value: float) -> float:
    """The step of `grid` at `value`: the spacing of the grid points around it."""
    g = grid(rows)
    if len(g) < 2:
        return 0.0
    i = min(max(int(np.searchsorted(g, value)), 1), len(g) - 1)
    return float(g[i] - g[i - 1])


def params(v: dict, fixed: dict, rows: Rows) -> dict[str, float]:
    return {"backlash_rad": fixed["backlash_rad"], "K": v["K"]}


def check(v: dict, rows: Rows) -> str:
    return "" if v["K"] > 0 else f"stiffness K = {v['K']:.4g} <= 0"


EFFECT = Effect(
    "backlash", "backlash_rad", "rad", "m",
    "dead zone of half-width b in the transmission deflection qm - q",
    needs_link=True, rigid_axis=False, block=1, k=1, design=design, params=params,
    check=check, search="backlash_rad", grid=grid, own_link_law=True,
    wide_view="width", in_spring=True, at_the_mode=True, limit=spring_sign)
