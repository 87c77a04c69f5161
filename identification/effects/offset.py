"""`offset`: a constant torque (current sensor offset, a constant load)."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows


def design(rows: Rows, fixed: dict) -> Design:
    return rows.extend(("offset", np.ones(len(rows.sig.qm)), None))


def params(v: dict, fixed: dict, rows: Rows) -> dict[str, float]:
    return {"offset": v["offset"]}


EFFECT = Effect(
    "offset", "offset", "N m", "N", "a constant torque (sensor offset, constant load)",
    needs_link=False, rigid_axis=True, block=0, k=1, design=design, params=params)
