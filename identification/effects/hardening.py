"""`hardening`: a stiffness that rises by Kh beyond a deflection (piecewise linear, harmonic-
drive style): a second spring with a dead band in parallel with K."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import (Design, Effect, Rows, deadzone, hat,
                                                    spring_sign)

ORDER = 70


def design(rows: Rows, fixed: dict) -> Design:
    sig = rows.sig
    dz = hat(deadzone(sig.qm - sig.q, fixed["deflection_rad"]))   # paired as K's column
    return rows.extend(("Kh", dz, -dz))


def grid(rows: Rows) -> np.ndarray:
    # Geometric grid over the log's own deflection range: the engagement may sit near the
    # encoder scale on a stiff joint, or near the largest deflection (a stiff second spring
    # engaged by a few peaks, which a grid stopping at a high percentile misses). The top is short of the largest deflection,
    # so that the column is never empty.
    sig = rows.sig
    d = np.abs((sig.qm - sig.q)[sig.sl])
    typical, top = float(np.percentile(d, 99)), float(np.max(d))
    return np.geomspace(0.02 * typical, 0.98 * max(top, typical), 64)


def params(v: dict, fixed: dict, rows: Rows) -> dict[str, float]:
    return {"hardening_ratio": v["Kh"] / v["K"], "deflection_rad": fixed["deflection_rad"],
            "K": v["K"]}


def check(v: dict, rows: Rows) -> str:
    # K -> 0 with a large Kh is a dead band: that is backlash, not hardening.
    K0 = rows.value("K")
    if v["K"] < 0.25 * K0 or v["Kh"] <= 0:
        return (f"K = {v['K']:.4g} and Kh = {v['Kh']:.4g}: not a stiffness rising "
                f"from the nominal K = {K0:.4g} (a dead band is backlash)")
    return ""


EFFECT = Effect(
    "hardening", "hardening_ratio", "", "",
    "stiffness that rises with deflection (piecewise linear)",
    needs_link=True, rigid_axis=False, block=1, k=2, design=design, params=params,
    check=check, search="deflection_rad", grid=grid, wide_view="deflection",
    in_spring=True, engages=True, limit=spring_sign)
