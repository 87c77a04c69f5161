"""`gravity`: the link's gravity torque with a free phase (eq. 13's MX, MY) where the nominal
assumes the rest at the start position qs."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows

ORDER = 10


def design(rows: Rows, fixed: dict) -> Design:
    sig = rows.sig
    return rows.extend(("Q", None, sig.g * np.cos(sig.q - sig.qs)))


def params(v: dict, fixed: dict, rows: Rows) -> dict[str, float]:
    # P g sin(x) + Q g cos(x) vanishes at x = -atan(Q / P): the rest lies that far away.
    offset = float(np.arctan(v["Q"] / v["P"])) if v["P"] != 0 else 0.0
    phi = rows.sig.qs - offset
    # MX g cos q + MY g sin q is P g sin(q - qs) + Q g cos(q - qs) expanded about q = 0 (the
    # nominal's MX = -P sin qs, MY = P cos qs with Q = 0): the expansion is about qs, not the rest.
    qs = rows.sig.qs
    return {"gravity_offset_rad": offset,
            "MX": -v["P"] * np.sin(qs) + v["Q"] * np.cos(qs),
            "MY": v["P"] * np.cos(qs) + v["Q"] * np.sin(qs), "rest_rad": phi}


EFFECT = Effect(
    "gravity", "gravity_offset_rad", "rad", "m",
    "gravity torque MX g cos q + MY g sin q acting away from the rest position",
    needs_link=True, rigid_axis=True, block=1, k=1, design=design, params=params)
