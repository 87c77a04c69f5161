"""`asymmetric_friction` on the bench: the motor friction (FVm qmd + FSm sign qmd) scaled by
(1 + a) for qmd > 0 and (1 - a) for qmd < 0, in the bench loop; an extended MJCF carries it
as the custom numeric `{axis}_asymmetry` = (a, FVm, FSm)."""

from __future__ import annotations

import mujoco

from jointbench.bench.effects.base import BenchEffect, Term, Uniform, positive_part

NUMERIC = "asymmetry"


def check(strength: float) -> str:
    return "" if -1 < strength < 1 else "strength must lie in (-1, 1)"


def _term(a: float, FVm: float, FSm: float) -> Term:
    # Friction force opposing motion is (1 + a s)(FVm |qmd| + FSm), s = sign(qmd): the extra
    # part acts against the positive direction whatever the sign of qmd.
    return lambda q_m, qd_m: -(a * (FVm * abs(qd_m) + FSm)) if qd_m != 0.0 else 0.0


def loop(strength: float, options: dict, gear_ratio: float | None, FVm: float,
         FSm: float) -> Term | None:
    return _term(strength, FVm, FSm) if strength else None


def from_numeric(values: list[float], axis: str) -> Term | None:
    if len(values) != 3:
        raise ValueError(f"numeric {axis}_{NUMERIC} must hold a, FVm, FSm")
    return _term(*values) if values[0] else None


def extend(spec: mujoco.MjSpec, axis: str, p: dict, K: float) -> None:
    # The drive-chain friction of a two-mass axis; the whole axis's of a rigid one (K = 0).
    FVm = positive_part(p, "FVm") if K else positive_part(p, "FV")
    FSm = positive_part(p, "FSm") if K else positive_part(p, "FS")
    a = p["asymmetry"]
    if a and "viscous_asymmetry" in p:
        # the direction-dependent part's own split (identification.effects.
        # asymmetric_friction): a (FVm' |qmd| + FSm') = a_v FVm |qmd| + a_c FSm
        FVm, FSm = FVm * p["viscous_asymmetry"] / a, FSm * p["coulomb_asymmetry"] / a
    spec.add_numeric(name=f"{axis}_{NUMERIC}", data=[p["asymmetry"], FVm, FSm])


def draw(u: Uniform, sign: float, tau_max: float, f1_hz: float, K: float):
    return sign * u(0.3, 0.5), {}


EFFECT = BenchEffect("asymmetric_friction", draw, check=check, extend=extend, loop=loop,
                     numeric=NUMERIC, from_numeric=from_numeric, largest=0.95)
