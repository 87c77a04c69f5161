"""A voltage drive described by its constants (docs/controller.md section 3.2).

A servo amplifier that applies a voltage u to a DC motor of torque constant Kt [N m/A],
back-EMF constant Ke [V s/rad] and armature resistance R [Ohm], behind a gear of ratio N and
efficiency eta (gear times motor), gives on the joint side

    tau = g_u u - B_emf qm',   g_u = eta N Kt / R [N m/V],   B_emf = eta N^2 Kt Ke / R.

A log records tau_m = g_u u (the command, what the drive knows); the back-EMF is then a
viscous damping on the motor side that the identification finds inside FVm. `import` writes
B_emf as the metadata key `back_emf_damping`, and `identify` reports the mechanical part
FVm - B_emf beside FVm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from jointbench.identification.log.schema import LogError

KEYS = ("Kt", "R", "Ke", "eta")
META_KEY = "back_emf_damping"


@dataclass(frozen=True)
class VoltageDrive:
    """Kt [N m/A], R [Ohm], Ke [V s/rad], eta (0-1] the efficiency, motor side."""

    Kt: float
    R: float
    Ke: float
    eta: float = 1.0

    @classmethod
    def parse(cls, values: dict[str, float | str], path: str | None = None) -> "VoltageDrive":
        """From {"Kt": ..., "R": ..., "Ke": ..., "eta": ...} (eta optional). LogError naming
        the key for a missing, unknown or non-positive constant."""
        unknown = [k for k in values if k not in KEYS]
        if unknown:
            raise LogError(f"--drive: unknown constant '{unknown[0]}' (Kt, R, Ke, eta)", path)
        missing = [k for k in KEYS[:3] if k not in values]
        if missing:
            raise LogError(f"--drive needs {', '.join(missing)} (Kt N m/A, R Ohm, Ke V s/rad)",
                           path)
        out = {}
        for k, v in values.items():
            try:
                x = float(v)
            except ValueError:
                raise LogError(f"--drive {k}={v}: not a number", path) from None
            if not (math.isfinite(x) and x > 0) or (k == "eta" and x > 1):
                raise LogError(f"--drive {k}={v}: must be a positive number"
                               + (" at most 1" if k == "eta" else ""), path)
            out[k] = x
        return cls(**out)

    def volt_to_torque(self, N: float = 1.0) -> float:
        """g_u = eta N Kt / R [N m/V], joint side for the gear ratio N."""
        return self.eta * N * self.Kt / self.R

    def back_emf_damping(self, N: float = 1.0) -> float:
        """B_emf = eta N^2 Kt Ke / R [N m s/rad], joint side."""
        return self.volt_to_torque(N) * N * self.Ke


def fvm_note(FVm: float, meta: dict[str, str]) -> str | None:
    """What identify says of FVm on a log of a voltage drive (metadata back_emf_damping),
    or None."""
    try:
        b = float(meta[META_KEY].split()[0])
    except (KeyError, ValueError, IndexError):
        return None
    return (f"FVm = {FVm:.6g} N m s/rad holds the voltage drive's back-EMF damping "
            f"{b:.6g} (metadata {META_KEY}): the mechanical viscous friction is "
            f"{FVm - b:.6g} N m s/rad")
