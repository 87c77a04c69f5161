"""`asymmetric_friction`: the motor friction (FV |qm'| + FS) scaled by (1 + a) for qm' > 0 and
(1 - a) for qm' < 0."""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import Design, Effect, Rows, column_value, sign0


def reference(rows: Rows) -> dict:
    # The nominal motor friction (drive chain, or the whole rigid axis) the asymmetry scales.
    link = rows.sig.has_link
    return {"FV_ref": rows.value("FVm" if link else "FV"),
            "FS_ref": rows.value("FSm" if link else "FS")}


def design(rows: Rows, fixed: dict) -> Design:
    # Friction (1 + a s)(FV |qm'| + FS): the extra torque a (FV |qm'| + FS), motor side.
    qmd = rows.sig.qmd
    col = fixed["FV_ref"] * np.abs(np.nan_to_num(qmd)) + fixed["FS_ref"] * np.abs(sign0(qmd))
    return rows.extend(("a", col, None))


EFFECT = Effect(
    "asymmetric_friction", "asymmetry", "", "",
    "viscous and Coulomb friction that differ with the direction of motion",
    needs_link=False, rigid_axis=False, block=0, k=1, design=design,
    params=column_value("a", "asymmetry"), reference=reference,
    # While the motor moves, the Coulomb part of the asymmetry, a FSm, is a constant torque:
    # an offset. The viscous part a FVm |qm'| is what tells the two apart.
    reduces_to="offset")
