"""`spring_damping`: viscous damping D (qmd - qd) in parallel with the joint spring."""

from __future__ import annotations

from jointbench.identification.effects.base import Design, Effect, Rows, column_value

ORDER = 50


def design(rows: Rows, fixed: dict) -> Design:
    dd = rows.sig.qmd - rows.sig.qd
    return rows.extend(("D", dd, -dd))


def check(v: dict, rows: Rows) -> str:
    return "" if v["D"] > 0 else f"D = {v['D']:.4g} <= 0"


EFFECT = Effect(
    "spring_damping", "D", "N m s/rad", "N s/m",
    "viscous damping D (qmd - qd) in parallel with the joint spring",
    needs_link=True, rigid_axis=False, block=1, k=1, design=design,
    params=column_value("D", "D"), check=check, in_spring=True,
    at_the_mode=True)
