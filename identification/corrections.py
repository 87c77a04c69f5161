"""The corrections beyond the paper's chain, by name (docs/method.md).

The paper's chain is eqs. (26)-(29) for the filter design, eq. (22) for the central
differences, eq. (13) (joint-motor) or eqs. (18)-(20) (motor-only) for the model, and least
squares. `identification.identify.identify(..., corrections=...)` applies the named ones;
an empty collection is the paper's chain alone (`identify --plain`). Standard library only:
the command line's help reads the names.
"""

from __future__ import annotations

from collections.abc import Iterable

# The corrections beyond the paper's chain (eqs. 26-29 design, eq. 22 central differences,
# eq. 13 or eqs. 18-20, least squares), each switchable by name (docs/method.md):
# - zoh: the torque, held over each sample interval, paired with the positions by its
#   interval means (`filtering.zoh_align`);
# - stencil5: the 5-point central difference where eq. (22)'s distortion at the decimated
#   cutoff passes 1 % (`defaults.stencil_for`);
# - instruments: eq. (13) solved with instruments built from q_ref (`identification.instruments`);
# - reversals: the Coulomb columns rebuilt from the previous pass's FS / J, the reversals
#   placed where the friction's kink has them (`identify._place_reversals`);
# - stick_phases: with reversals, the motor's Coulomb state in its stick phases
#   (`friction_state`); in the motor-only link reconstruction too (`link_fit`);
# - wide_band: a joint-motor fit in the wide band too, the more precise kept (`band_choice`);
# - motor_only_columns: the columns eq. (18) as printed drops, and gravity (`regressors`);
# - link_reconstruction: the motor-only parameters from the link reconstructed out of q_m
#   (`link_fit`).
CORRECTIONS = ("zoh", "stencil5", "instruments", "reversals", "stick_phases", "wide_band",
               "motor_only_columns", "link_reconstruction")


def check_corrections(corrections: Iterable[str]) -> frozenset[str]:
    """The set of correction names (CORRECTIONS); ValueError naming an unknown one."""
    if isinstance(corrections, str):
        raise ValueError(f"corrections must be a collection of names, got the string "
                         f"{corrections!r}")
    wanted = frozenset(corrections)
    unknown = sorted(wanted - set(CORRECTIONS))
    if unknown:
        raise ValueError(f"unknown correction(s) {', '.join(map(repr, unknown))} (choices: "
                         f"{', '.join(CORRECTIONS)})")
    return wanted
