"""The independent simulator (jointbench.testing.simulator) as a runner of the battery by
visibility (bench.campaign.battery.Runner): its axis families at the paper's rate, one of them
with a link mass so that the `gravity` effect applies."""

from __future__ import annotations

from dataclasses import replace

from jointbench.bench.campaign.battery import Effect, Place
from jointbench.identification.filter_choice import PAPER_RATE
from jointbench.identification.log import Log
from jointbench.testing.hidden_effects import Hidden
from jointbench.testing.simulator import FAMILIES, AxisFamily, default_reference, simulate

# heavy_link hanging from its hinge: first moment MY = 8 kg m (rest angle 0), a gravity
# torque of 78 N m (20 % of its torque limit) a quarter turn from rest.
BATTERY_FAMILIES: dict[str, AxisFamily] = {**FAMILIES, "pendulum": replace(
    FAMILIES["heavy_link"], name="pendulum",
    description="heavy_link with a link mass (MY = 8 kg m), f1 = 6 Hz", MY=8.0)}
INDEP_PLACES = (Place("indep", "balanced"), Place("indep", "soft"), Place("indep", "wrist"),
                Place("indep", "pendulum", gravity=True))


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
