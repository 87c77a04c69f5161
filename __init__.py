"""jointbench: a MuJoCo virtual testbench for identifying joint stiffness and drive-chain
parameters (Pham, Gautier, Poignet, ICRA 2001).

The package maps the repository's top-level folders: `jointbench.identification` (pure
numerics, no MuJoCo), `jointbench.bench` (MuJoCo experiments, analyses, command line) and
`jointbench.models` (MJCF assets and ground truth).
"""

from __future__ import annotations

__version__ = "0.2.0"
