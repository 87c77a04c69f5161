"""`link_coulomb`: Coulomb friction FS sign(qd) on the link side (eq. 13's FS)."""

from __future__ import annotations

from jointbench.identification.effects.base import Design, Effect, Rows, column_value, sign0

ORDER = 20


def design(rows: Rows, fixed: dict) -> Design:
    return rows.extend(("FS", None, sign0(rows.sig.qd)))


def check(v: dict, rows: Rows) -> str:
    return "" if v["FS"] > 0 else f"FS = {v['FS']:.4g} <= 0"


EFFECT = Effect(
    "link_coulomb", "FS", "N m", "N", "Coulomb friction FS sign(qd) on the link side",
    needs_link=True, rigid_axis=False, block=1, k=1, design=design,
    params=column_value("FS", "FS"), check=check)
