"""`backlash`: a dead zone of half-width b in the transmission deflection qm - q."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows, deadzone

ORDER = 40


def design(rows: Rows, fixed: dict) -> Design:
    sig, b = rows.sig, fixed["backlash_rad"]
    return rows.columns(deflection=deadzone(sig.qm - sig.q, b) if b > 0 else None)


def grid(rows: Rows) -> np.ndarray:
    sig = rows.sig
    dmax = float(np.percentile(np.abs((sig.qm - sig.q)[sig.sl]), 95))
    return np.linspace(0.0, 0.8 * dmax, 41)


def params(v: dict, fixed: dict, rows: Rows) -> dict[str, float]:
    return {"backlash_rad": fixed["backlash_rad"], "K": v["K"]}


def check(v: dict, rows: Rows) -> str:
    return "" if v["K"] > 0 else f"stiffness K = {v['K']:.4g} <= 0"


EFFECT = Effect(
    "backlash", "backlash_rad", "rad", "m",
    "dead zone of half-width b in the transmission deflection qm - q",
    needs_link=True, rigid_axis=False, block=1, k=1, design=design, params=params,
    check=check, search="backlash_rad", grid=grid)
