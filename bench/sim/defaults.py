"""The default reference of a virtual experiment, the one source for the code and for the
command line's help (standard library only: `simulate --help` reads it without numpy), and
the physics steps a control period."""

import math

AMPLITUDE_RAD = 0.1        # chirp amplitude [rad] (bench.sim.experiment.default_chirp)
ACCELERATION_SHARE = 0.4   # the rigid-body torque (Jm + JL) A (2 pi f)^2 <= share x tau_max
AMPLITUDE_REDUCTION = 0.7  # the amplitude's factor at each automatic reduction (saturation)
MAX_REDUCTIONS = 6         # automatic reductions at most
# MuJoCo steps a control period: the plant's friction switches inside the sample interval,
# as a real axis' does, so the bench's logs identify through everyone's path
# (docs/design-notes.md, "Simulator-free estimator"). The shipped models' Coulomb friction is
# dead-beat at the physics step h (semi-implicit Euler, the constraint's time constant 2 h,
# bench/sim/friction.py), the held torque is placed on the step's leapfrog grid and each
# slip-through's switch at the crossing (bench/sim/loop.py). What is left is first order in
# h (Euler's implicit joint damping adds h FV / 2 to each inertia); the longest step and the
# fewest steps a period below are the coarsest that keep every accuracy bar of the suite at
# the paper's rate and at the arm's design rate (docs/design-notes.md, "The default physics
# step"). DEFAULT_SUBSTEPS is the count at the paper's rate.
PHYSICS_STEP = 2.5e-4      # the longest physics step [s] of a default run
MIN_SUBSTEPS = 12          # at least this many steps a period at any rate


def default_substeps(sample_rate_hz: float) -> int:
    """Physics steps a control period at `sample_rate_hz` [Hz]: the fewest that keep the step
    within PHYSICS_STEP, at least MIN_SUBSTEPS."""
    return max(MIN_SUBSTEPS, math.ceil(1.0 / (sample_rate_hz * PHYSICS_STEP) - 1e-9))


PAPER_RATE_HZ = 350.87     # the prototype's control and log rate (paper, section 4)
DEFAULT_SUBSTEPS = default_substeps(PAPER_RATE_HZ)   # 12 at the paper's rate


def amplitude_help() -> str:
    """The `--amplitude` help of `simulate`, from the values above (argparse expands '%%')."""
    return (f"chirp amplitude in rad (default {AMPLITUDE_RAD:g}, capped at high frequency so "
            f"that the rigid-body torque stays under {100 * ACCELERATION_SHARE:g} %% of the torque "
            f"limit, and multiplied by {AMPLITUDE_REDUCTION:g} up to {MAX_REDUCTIONS} times "
            "while the torque saturates; the log's `chirp` metadata gives the amplitude used)")
