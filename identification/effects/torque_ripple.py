"""`torque_ripple`: a torque A sin(2 pi qm / p + phase) periodic in the motor angle."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows

ORDER = 30


def design(rows: Rows, fixed: dict) -> Design:
    ph = 2 * np.pi * rows.sig.qm / fixed["ripple_period_rad"]
    return rows.extend(("As", np.sin(ph), None), ("Ac", np.cos(ph), None))


def grid(rows: Rows) -> np.ndarray:
    # Periods from encoder-scale steps to the motion span (the column must vary).
    sig = rows.sig
    span = float(np.ptp(sig.qm[sig.sl]))
    return np.geomspace(max(span / 2000, 1e-4), max(span, 2e-4), 160)


def params(v: dict, fixed: dict, rows: Rows) -> dict[str, float]:
    # The bench's ripple adds A sin(2 pi qm / p + phase) to the rotor torque: the logged
    # torque carries -A sin(...).
    return {"ripple_amplitude": float(np.hypot(v["As"], v["Ac"])),
            "ripple_period_rad": fixed["ripple_period_rad"],
            "ripple_phase_rad": float(np.arctan2(-v["Ac"], -v["As"]))}


EFFECT = Effect(
    "torque_ripple", "ripple_amplitude", "N m", "N",
    "torque ripple periodic in the motor angle (cogging, drive ripple)",
    needs_link=False, rigid_axis=True, block=0, k=3, design=design, params=params,
    search="ripple_period_rad", grid=grid, period="ripple_period_rad")
