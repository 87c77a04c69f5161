"""Inverse view of the discrepancy analysis: which unmodelled effect (docs/effects.md) the
residual of the nominal model carries, ranked by what it explains on held-out data.

The nominal model is the linear two-mass axis the paper's eq. (13) describes:

    motor (eq. 6):  tau_m = Jm qm'' + FVm qm' + FSm sign(qm') + K (qm - q)
    link  (eq. 5):  0     = JL q'' + FV q' + FS sign(q') - K (qm - q) + P g sin(q - qs)

Gravity is kept as the experiment assumes it, at rest at the start position qs (docs/controller.md:
an experiment starts at rest in equilibrium), P = m l [kg m]; the `gravity` effect
frees its phase (MX, MY of eq. 13). The link Coulomb friction FS of eq. 13 is nominal (every
real link has it); `link_coulomb` is a candidate only against a nominal built without it
(`nominal(..., link_friction=False)`). Logs without `q` use the motor-side equation only
(rigid axis, tau_m = J qm'' + FV qm' + FS sign(qm')) and test the effects observable there.

Every column, nominal or effect, is built at the raw rate from the same zero-phase Butterworth
signals and goes through the same decimation (section 3.2), so the band-limited equation stays
linear in the parameters. Rows are weighted by 1 / sigma of their block (nominal residual).
Nonlinear effect parameters (backlash width, hardening engagement, lag time constant, ripple
period) are found by a bounded scalar search (scipy.optimize) or a grid, the linear ones by
least squares at each trial.

The package: signals (the filtered signals and the stacked rows), nominal (the nominal model
and its designs), stacked (the nominal extended by several effects), heldout (the out-of-sample
evidence that decides), candidates (one effect of identification.effects tested), inverse (all
of them ranked, the named causes).
"""

from jointbench.identification.discrepancy.candidates import (BIC_MIN, Candidate, design,
                                                              predict)
from jointbench.identification.discrepancy.heldout import ALPHA, FOLDS, MATERIAL, SEGMENTS
from jointbench.identification.discrepancy.inverse import (RIGID_TESTS, WHY_IN_NOMINAL,
                                                           WHY_NOT_RIGID, InverseDiagnosis,
                                                           diagnose_inverse)
from jointbench.identification.discrepancy.nominal import (NOMINAL_RIGID, NOMINAL_TWO_MASS,
                                                           NOMINAL_TWO_MASS_NO_FS, NUMERICS,
                                                           Nominal, nominal, with_parameters)
from jointbench.identification.discrepancy.signals import Signals, signals
from jointbench.identification.discrepancy.stacked import design_many
from jointbench.identification.effects import deadzone
from jointbench.identification.effects.torque_lag import lagged

__all__ = ["ALPHA", "BIC_MIN", "FOLDS", "MATERIAL", "SEGMENTS", "Candidate", "design", "design_many", "predict",
           "RIGID_TESTS", "WHY_IN_NOMINAL", "WHY_NOT_RIGID", "InverseDiagnosis",
           "diagnose_inverse", "NOMINAL_RIGID", "NOMINAL_TWO_MASS", "NOMINAL_TWO_MASS_NO_FS", "NUMERICS",
           "Nominal", "nominal", "with_parameters", "Signals", "signals", "deadzone", "lagged"]
