"""A deliberately wrong plug-in, to see what the campaign and its accuracy gates make of it:
the joint-motor least squares of the public API (`jointbench.identify`, eq. 13) with every
estimate scaled by 1 + BIAS and the paper's (white-residual) sigma kept.

    jointbench campaign --method examples/biased_ls.py:estimate --require "K.abs_bias_pct<0.5"

The campaign's table shows its bias (+1 % on top of the built-in's), its +-2 sigma coverage
collapses, and the gate above fails for it (exit status 3) while the built-in passes.
"""

from __future__ import annotations

import jointbench

BIAS = 0.01


def estimate(log: jointbench.Log) -> dict[str, tuple[float, float]]:
    fit = jointbench.identify(log, "joint-motor")
    return {name: ((1.0 + BIAS) * e.value, e.sigma) for name, e in fit.parameters.items()}
