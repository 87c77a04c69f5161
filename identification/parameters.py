"""The parameter names of every identification model, their units and groups: one table.

Names follow the paper: eq. (11) for the joint-motor model (eq. 13), eq. (19) for the
motor-only model (eqs. 18-20), eq. (6) with q = qm for the rigid model. Units are those of a
revolute axis; a prismatic axis (log metadata `axis: prismatic`) uses m and N in place of
rad and N m, so inertias become masses.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Parameter:
    """One physical parameter: its paper name, units and the group it belongs to."""

    name: str
    unit: str            # revolute axis
    unit_prismatic: str  # prismatic axis
    group: str           # "inertia", "stiffness", "friction", "gravity", "offset"
    what: str

    def unit_for(self, prismatic: bool) -> str:
        return self.unit_prismatic if prismatic else self.unit


PARAMETERS: dict[str, Parameter] = {p.name: p for p in (
    Parameter("Jm", "kg m^2", "kg", "inertia", "drive-chain (motor and gears) inertia"),
    Parameter("K", "N m/rad", "N/m", "stiffness", "joint stiffness"),
    Parameter("JL", "kg m^2", "kg", "inertia", "link inertia about the joint"),
    Parameter("FVm", "N m s/rad", "N s/m", "friction", "drive-chain viscous friction"),
    Parameter("FSm", "N m", "N", "friction", "drive-chain Coulomb friction"),
    Parameter("FV", "N m s/rad", "N s/m", "friction", "link viscous friction"),
    Parameter("FS", "N m", "N", "friction", "link Coulomb friction"),
    Parameter("MX", "kg m", "kg", "gravity", "first moment of the link, x"),
    Parameter("MY", "kg m", "kg", "gravity", "first moment of the link, y"),
    Parameter("J", "kg m^2", "kg", "inertia", "total inertia of a rigid axis (Jm + JL)"),
    Parameter("offset", "N m", "N", "offset", "constant torque of the rigid model"),
)}

# The estimated vector X of each model, in the regressor's column order.
JOINT_MOTOR = ("Jm", "FVm", "FSm", "K", "JL", "MX", "MY", "FV", "FS")          # eq. (11)
MOTOR_ONLY = ("X1", "X2", "X3", "X4", "X5", "X6", "X7")                     # eq. (19)
MOTOR_ONLY_CORRECTED = MOTOR_ONLY + ("X8", "X9", "X10", "X11")
RIGID = ("J", "FV", "FS", "offset")                                            # eq. (6), q = qm

# The physical parameters of the two-mass axis: eq. (11) in the order of Table 1's text.
TWO_MASS = ("Jm", "K", "JL", "FVm", "FSm", "FV", "FS", "MX", "MY")
STIFFNESS_AND_INERTIAS = ("K", "Jm", "JL")
FRICTIONS = ("FVm", "FSm", "FV", "FS")
# The physical parameters Table 3 recovers from X1..X7 (motor-only model).
MOTOR_ONLY_PHYSICAL = ("Jm", "K", "JL", "FVm", "FV", "FSm")


def units(prismatic: bool) -> dict[str, str]:
    """Unit of every physical parameter name for a revolute or prismatic axis."""
    return {n: p.unit_for(prismatic) for n, p in PARAMETERS.items()}
