"""`hardening` on the bench: a second spring of stiffness ratio x K stacked in parallel with
the joint spring, engaging beyond +-deflection (option, joint-side units)."""

from __future__ import annotations

import mujoco

from jointbench.bench.effects.base import BenchEffect, Uniform, nonnegative

OPTIONS = {"deflection": 0.003}   # |qm - q| beyond which stiffness rises by ratio K


def mjcf(spec: mujoco.MjSpec, axis: str, strength: float, options: dict, K: float) -> None:
    d = options["deflection"]
    extra = spec.add_tendon(name=f"{axis}_hardening")
    extra.stiffness[0] = strength * K
    extra.springlength = [-d, d]
    extra.wrap_joint(f"{axis}_motor", 1.0)
    extra.wrap_joint(axis, -1.0)


def extended(p: dict) -> tuple[float, dict]:
    return max(p["hardening_ratio"], 0.0), {"deflection": p["deflection_rad"]}


def draw(u: Uniform, sign: float, tau_max: float, f1_hz: float, K: float):
    # Engagement at a fraction of the deflection a tenth of the torque limit gives, so the
    # stiffer spring takes part on every axis without being engaged all the time. That
    # deflection is 0.6-2.2 times the RMS deflection of the battery's chirps with velocity
    # feedforward (clean 40 s logs at the paper's rate), 0.9-5.8 times it without, where the
    # median deflection is far smaller still (3 urad on the independent soft family): there the
    # spring engages only at the sweep's largest deflections, and a target visibility can
    # ask for a second spring hundreds of times K: a hard stop, one count of the link
    # encoder worth tens of N m, which no spring law describes.
    return u(1.0, 2.0), {"deflection": u(0.25, 0.5) * 0.1 * tau_max / K}


# The battery's search stops at a second spring LARGEST times K: beyond it the spring is a
# hard stop (its visibility barely grows: the loop holds the motor whatever the link does),
# and the simulation's step, set by the stiffest spring, grows with sqrt(1 + ratio).
LARGEST = 100.0

EFFECT = BenchEffect("hardening", draw, options=OPTIONS, check=nonnegative, mjcf=mjcf,
                     extended=extended, largest=LARGEST)
