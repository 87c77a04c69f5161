"""The discrepancy loop: a log's nominal model, the candidate effects, the named causes, the
extended model and its gain (inverse and forward views).

Modules, imports going down: run (diagnose) -> report (text, JSON, files) -> figures ->
forward (MuJoCo axes, replays, cross-validation) -> types (Diagnosis, ForwardView).
"""

from jointbench.bench.analysis.diagnose.forward import cross_validate
from jointbench.bench.analysis.diagnose.report import dumps, summary_text, write
from jointbench.bench.analysis.diagnose.run import diagnose
from jointbench.bench.analysis.diagnose.types import BLOCK_NAMES, Diagnosis, ForwardView

__all__ = ["BLOCK_NAMES", "Diagnosis", "ForwardView", "cross_validate", "diagnose", "dumps",
           "summary_text", "write"]
