"""The independent simulator (jointbench.testing.simulator) as runners of the battery by
visibility (bench.campaign.battery.Runner): its axis families at the paper's rate, one of them
with a link mass so that the `gravity` effect applies; and its lab-rig family (a voltage
drive under a P loop, 500 Hz, simulate_lab_rig) at its own rate."""

from __future__ import annotations

from dataclasses import replace

from jointbench.bench.campaign.battery import Effect, Place
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.log import Log
from jointbench.testing.hidden_effects import Hidden
from jointbench.testing.simulator import (FAMILIES, LAB_RIG, LAB_RIG_RATE, AxisFamily, LabRig,
                                          default_reference, simulate, simulate_lab_rig)

# heavy_link hanging from its hinge: first moment MY = 8 kg m (rest angle 0), a gravity
# torque of 78 N m (20 % of its torque limit) a quarter turn from rest.
BATTERY_FAMILIES: dict[str, AxisFamily] = {**FAMILIES, "pendulum": replace(
    FAMILIES["heavy_link"], name="pendulum",
    description="heavy_link with a link mass (MY = 8 kg m), f1 = 6 Hz", MY=8.0)}
INDEP_PLACES = (Place("indep", "balanced"), Place("indep", "soft"), Place("indep", "wrist"),
                Place("indep", "pendulum", gravity=True))
LAB_PLACES = (Place("lab", "lab_rig"),)


class IndepRunner:
    """Battery cases on the independent simulator: `duration` s logs, linear chirp. Every
    run of a family and feedforward setting keeps the reference of its clean run (shrunk
    as that run needed), so that an effect changes nothing else."""

    rate_hz = PAPER_RATE

    def __init__(self, duration: float = 40.0):
        self.duration = duration
        self._reductions: dict[tuple[str, bool], int] = {}

    def scales(self, place: Place) -> tuple[float, float, float]:
        f = BATTERY_FAMILIES[place.model]
        return f.tau_max, f.f1_hz, f.K

    def log(self, place: Place, effects: tuple[Effect, ...], seed: int, feedforward: bool,
            noise: bool) -> Log:
        family = BATTERY_FAMILIES[place.model]
        key = (place.model, feedforward)
        if key not in self._reductions:
            clean = simulate(family, seed, self.duration, feedforward=feedforward,
                             sample_rate_hz=self.rate_hz, torque_noise_std=0.0)
            self._reductions[key] = int(clean.meta["amplitude_reductions"])
        return simulate(family, seed, self.duration, feedforward=feedforward,
                        sample_rate_hz=self.rate_hz,
                        effects=tuple(Hidden(n, s, o) for n, s, o in effects),
                        torque_noise_std=None if noise else 0.0,
                        reference=default_reference(family, self.duration,
                                                    reductions=self._reductions[key]))


class LabRigRunner:
    """Battery cases on the lab-rig family (simulate_lab_rig): `duration` s logs at the rig's
    500 Hz, its P loop on the motor encoder and its multisine reference (the seed's: the same
    with or without an effect, so that an effect changes nothing else). The loop has no
    velocity feed-forward, so a case's feed-forward setting changes nothing; torque noise off
    is the rig without its voltage noise."""

    rate_hz = LAB_RIG_RATE
    seeded_excitation = True   # the multisine's phases are the seed's

    def __init__(self, duration: float = 40.0, rig: LabRig = LAB_RIG):
        self.duration, self.rig = duration, rig

    def scales(self, place: Place) -> tuple[float, float, float]:
        f = self.rig.family
        return f.tau_max, f.f1_hz, f.K

    def log(self, place: Place, effects: tuple[Effect, ...], seed: int, feedforward: bool,
            noise: bool) -> Log:
        rig = self.rig if noise else replace(self.rig, voltage_noise_std=0.0)
        return simulate_lab_rig(rig, seed, self.duration,
                                effects=tuple(Hidden(n, s, o) for n, s, o in effects))
