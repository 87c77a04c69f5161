"""`gravity`: the link's gravity torque with a free phase (eq. 13's MX, MY) where the nominal
assumes the rest at the start position qs."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows

ORDER = 10


def design(rows: Rows, fixed: dict) -> Design:
    """Q g cos(q - qs) where the link is not held by friction alone (`free`)."""
    sig = rows.sig
    return rows.extend(("Q", None, sig.g * np.cos(sig.q - sig.qs) * free(rows)))


def free(rows: Rows) -> np.ndarray:
    """0 on the instants where the link rests held by its static friction alone, 1 elsewhere:
    its speed |q'| under the speed v0 of the nominal's link friction law tanh(q' / v0)
    (identification.discrepancy.nominal.link_law) while the spring transmits nothing, its
    deflection inside a dead band that a cause of the reference put in the model
    (`rows.deflection` zero: the motor moves within a backlash). 1 everywhere for a sign law
    (v0 = 0) or a spring without a dead band.

    A link at rest that the spring does not touch is held by static friction, which takes
    any torque up to FS: a pendulum whose motor rattles in a backlash's dead band while its
    link sticks at q* holds P g sin(q* - qs) by friction, a constant over the stuck stretch
    that the law (0 at zero speed) leaves in the link equation's residual. Over the few mrad
    a stuck link moves, Q g cos(q - qs) is that constant, and a rest moved to q* takes it up.
    Those rows carry no evidence of where gravity's rest lies, only the friction's misfit
    near zero speed, part of the nominal's own; a rest away from qs loads the link wherever
    the spring or its motion reads it, and there the column keeps it."""
    sig = rows.sig
    v0 = float(getattr(rows, "link_v0", 0.0))
    d = getattr(rows, "deflection", None)
    if v0 <= 0 or d is None:
        return np.ones(len(sig.q))
    held = (np.abs(np.nan_to_num(sig.qd)) < v0) & (np.asarray(d) == 0)
    return (~held).astype(float)


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
