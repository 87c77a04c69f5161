"""The independent simulator: a two-mass axis in plain numpy (no MuJoCo) that writes jointbench
logs, its hidden effects written again from docs/effects.md, and its runner of the battery by
visibility. Accuracy is measured on its logs as well as on the bench's, so that no figure is a
figure of MuJoCo alone.

    simulator        the axis families, the controller of docs/controller.md, `simulate`
    hidden_effects   the hidden effects' terms inside the RK4 stages (`Hidden`, `parse_hidden`)
    battery_runner   `IndepRunner`, `INDEP_PLACES`, `LabRigRunner` and `LAB_PLACES` for
                     bench.campaign.battery
"""

from jointbench.testing.battery_runner import (BATTERY_FAMILIES, INDEP_PLACES, LAB_PLACES,
                                               IndepRunner, LabRigRunner)
from jointbench.testing.hidden_effects import Hidden, parse_hidden
from jointbench.testing.simulator import (FAMILIES, LAB_RIG, AxisFamily, LabRig, PositionLoop,
                                          Reference, default_reference, simulate_lab_rig,
                                          default_substeps, energy, frictionless, open_loop,
                                          simulate)

__all__ = ["BATTERY_FAMILIES", "FAMILIES", "INDEP_PLACES", "LAB_PLACES", "AxisFamily", "Hidden",
           "IndepRunner", "LabRigRunner",
           "Reference", "default_reference", "default_substeps", "energy", "frictionless",
           "open_loop", "parse_hidden", "simulate", "LAB_RIG", "LabRig", "PositionLoop",
           "simulate_lab_rig"]
