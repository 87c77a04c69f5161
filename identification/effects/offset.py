"""`offset`: a constant torque (current sensor offset, a constant load)."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows, column_value

ORDER = 80

COLUMN = "offset"     # its one column's name in an extended design


def design(rows: Rows, fixed: dict) -> Design:
    return rows.extend((COLUMN, np.ones(len(rows.sig.qm)), None))


EFFECT = Effect(
    "offset", "offset", "N m", "N", "a constant torque (sensor offset, constant load)",
    needs_link=False, rigid_axis=True, block=0, k=1, design=design,
    params=column_value(COLUMN, "offset"))
