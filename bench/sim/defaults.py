"""The default reference of a virtual experiment, the one source for the code and for the
command line's help (standard library only: `simulate --help` reads it without numpy)."""

AMPLITUDE_RAD = 0.1        # chirp amplitude [rad] (bench.sim.experiment.default_chirp)
ACCELERATION_SHARE = 0.4   # the rigid-body torque (Jm + JL) A (2 pi f)^2 <= share x tau_max
AMPLITUDE_REDUCTION = 0.7  # the amplitude's factor at each automatic reduction (saturation)
MAX_REDUCTIONS = 6         # automatic reductions at most
# MuJoCo steps a control period: the plant's friction switches inside the sample interval,
# as a real axis' does, so the bench's logs identify through everyone's path
# (docs/design-notes.md, "Simulator-free estimator"). With the shipped models' dead-beat
# Coulomb friction (semi-implicit Euler, the constraint's time constant two physics steps,
# bench/sim/friction.py) 8 steps a period and 16 identify K, Jm, JL within 0.01 % of each other
# on arm6; an Euler step costs a quarter of an RK4 step.
DEFAULT_SUBSTEPS = 8


def amplitude_help() -> str:
    """The `--amplitude` help of `simulate`, from the values above (argparse expands '%%')."""
    return (f"chirp amplitude in rad (default {AMPLITUDE_RAD:g}, capped at high frequency so "
            f"that the rigid-body torque stays under {100 * ACCELERATION_SHARE:g} %% of the torque "
            f"limit, and multiplied by {AMPLITUDE_REDUCTION:g} up to {MAX_REDUCTIONS} times "
            "while the torque saturates; the log's `chirp` metadata gives the amplitude used)")
