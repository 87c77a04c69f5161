"""`asymmetric_friction`: the motor friction (FV |qm'| + FS) scaled by (1 + a) for qm' > 0 and
(1 - a) for qm' < 0.

The inverse view fits the direction-dependent part with its own viscous-to-Coulomb split: the
extra torque a (theta FV_ref |qm'| + (1 - theta) FS_ref), theta searched in [0, 1]. The
(1 + a s) law has theta = 1/2 with the true FVm, FSm; but the split of the motor friction
into FVm and FSm is what a log identifies worst (the error comes from the rows of the chirp
near and above the mode), and the same error in the column's ratio leaves a part of the
asymmetry that an offset takes up. Searched, theta reads the split from the
direction-dependent torque itself. Its Coulomb part is a constant while the motor moves (the
filtered velocity is never exactly 0), an offset: what the asymmetry adds to an offset is its
viscous part alone (identification.discrepancy.inverse._which), and an offset adds to it only
where the constant opposes the viscous part (theta in [0, 1]: both directions' frictions are
ordered the same way, as in the (1 + a s) law).
"""

from __future__ import annotations

import numpy as np

from jointbench.identification.effects.base import (FOLD_FITS, Column, Design, Effect, Rows, sign0,
                                                    spread)
from jointbench.identification.effects.offset import COLUMN as OFFSET

ORDER = 90

# The viscous part's share theta of the direction-dependent torque (scaled by the reference's
# FV_ref, FS_ref): 0 a constant while moving, 1/2 the reference's own split, 1 viscous alone;
# the viscous-to-Coulomb ratio relative to the reference's, theta / (1 - theta), is 0, 1/8,
# 1/4, 1/2, 1, 2, 4, 8 and infinite.
SHARES = np.array([0.0, 1 / 9, 1 / 5, 1 / 3, 1 / 2, 2 / 3, 4 / 5, 8 / 9, 1.0])


# A Coulomb part beyond the fitted Coulomb friction by more than this many of its standard
# errors is not noise at the bound (one-sided, about 2 % of estimates of a true asymmetry at
# the bound itself).
CHECK_Z = 2.0


def _names(rows: Rows) -> tuple[str, str]:
    # The motor friction the asymmetry scales: the drive chain's, or the whole rigid axis's.
    return ("FVm", "FSm") if rows.sig.has_link else ("FV", "FS")


def reference(rows: Rows) -> dict:
    fv, fs = _names(rows)
    return {"FV_ref": rows.value(fv), "FS_ref": rows.value(fs)}


def grid(rows: Rows) -> np.ndarray:
    return SHARES


def _magnitudes(rows: Rows) -> tuple[np.ndarray, np.ndarray]:
    qmd = rows.sig.qmd[rows.sig.sl]
    return np.abs(np.nan_to_num(qmd)), np.abs(sign0(qmd))


def _share(fixed: dict, beside_offset: bool) -> float:
    # Beside an offset the Coulomb part is collinear with it while the motor moves (at
    # theta -> 0 exactly): the split between the two is then arbitrary, and a fit on top of
    # an offset could hand the asymmetry any Coulomb part, and a replay of that fit can
    # diverge. There the asymmetry keeps the (1 + a s) law's tie to the
    # viscous part, the reference's split, and the offset takes the free constant.
    return 0.5 if beside_offset else fixed.get("viscous_share", 0.5)


def design(rows: Rows, fixed: dict) -> Design:
    # The extra torque a (theta FV_ref |qm'| + (1 - theta) FS_ref |sign qm'|), motor side.
    qmd = rows.sig.qmd
    v, s = np.abs(np.nan_to_num(qmd)), np.abs(sign0(qmd))

    def extended(theta: float) -> Design:
        col = theta * fixed["FV_ref"] * v + (1 - theta) * fixed["FS_ref"] * s
        return rows.extend(("a", col, None))

    theta = _share(fixed, False)
    out = extended(theta)
    return extended(_share(fixed, True)) if OFFSET in out[2] and theta != 0.5 else out


def params(values: dict, fixed: dict, rows: Rows) -> dict[str, float]:
    """`asymmetry`: the direction-dependent torque E = a (theta FV_ref |qm'| + (1 - theta)
    FS_ref) as a share of the fitted friction O = FV |qm'| + FS (least squares over the log's
    samples: the (1 + a s) law the bench writes, a O, is then the closest to E; for that law
    itself it is a, whatever the split of O); `viscous_asymmetry` and `coulomb_asymmetry`,
    E's parts over O's (a and a for that law)."""
    fv, fs = (values[n] for n in _names(rows))
    a, theta = values["a"], _share(fixed, OFFSET in values)
    dv, ds = a * theta * fixed["FV_ref"], a * (1 - theta) * fixed["FS_ref"]
    v, s = _magnitudes(rows)
    odd = fv * v + fs * s
    den = float(odd @ odd)
    return {"asymmetry": float((dv * v + ds * s) @ odd) / den if den > 0 else float(a),
            "viscous_asymmetry": float(dv / fv) if fv else 0.0,
            "coulomb_asymmetry": float(ds / fs) if fs else 0.0}


def _excess(v: dict, rows: Rows) -> tuple[float, float, float, float]:
    """The Coulomb part dS = a (1 - theta) FS_ref, the fitted Coulomb friction FS, the excess
    |dS| - FS and its standard error (the jackknife over the folds' fits, base.spread)."""
    name = _names(rows)[1]
    share = (1 - _share(v, False)) * v["FS_ref"]

    def excess(x: dict) -> float:
        return abs(x["a"] * share) - x[name]

    return v["a"] * share, v[name], excess(v), spread(v.get(FOLD_FITS, ()), excess)


def beyond(v: dict, rows: Rows) -> float:
    """How many of its standard errors the excess |dS| - FS lies above 0 (check): inf when
    it is positive and the folds give no spread; 0 beside an offset (check)."""
    if OFFSET in v:
        return 0.0
    _, _, ex, sd = _excess(v, rows)
    return ex / sd if sd > 0 else (np.inf if ex > 0 else 0.0)


def check(v: dict, rows: Rows) -> str:
    """Each direction's Coulomb friction stays positive, FS (1 +- a_c) >= 0: a Coulomb part of
    the direction-dependent torque larger than the fitted Coulomb friction itself is not an
    asymmetry of that friction but a constant torque beside it (an offset). The excess
    |dS| - FS is compared with its own standard error (the jackknife over the folds' fits,
    base.spread): an asymmetry at its bound, one direction's Coulomb friction near zero, has
    an estimate that overshoots the bound by noise about half the time, and is unphysical only
    when the excess is more than CHECK_Z standard errors (`beyond`). Beside an offset the
    constant splits between the two at will while the motor moves: no check there."""
    z = beyond(v, rows)
    if z <= CHECK_Z:
        return ""
    ds, fs, _, sd = _excess(v, rows)
    return (f"its Coulomb part {ds:.4g} exceeds the fitted Coulomb friction {fs:.4g}"
            + (f" by {z:.1f} standard errors ({sd:.2g})" if np.isfinite(z) else "")
            + ": one direction's friction would be negative (a constant torque beside it is "
            "an offset)")


def parts(rows: Rows) -> tuple[Column, ...]:
    """The direction-dependent torque's two parts, whatever theta (design): the viscous
    |qm'| and the Coulomb |sign qm'|, a constant on every row where the motor moves."""
    qmd = rows.sig.qmd
    return (("a_viscous", np.abs(np.nan_to_num(qmd)), None),
            ("a_coulomb", np.abs(sign0(qmd)), None))


EFFECT = Effect(
    "asymmetric_friction", "asymmetry", "", "",
    "viscous and Coulomb friction that differ with the direction of motion",
    needs_link=False, rigid_axis=False, block=0, k=2, design=design,
    params=params, reference=reference, search="viscous_share", grid=grid, check=check,
    beyond=beyond, parts=parts,
    # While the motor moves, the Coulomb part of the asymmetry, a FSm, is a constant torque:
    # an offset. The viscous part a FVm |qm'| is what tells the two apart.
    reduces_to="offset")
