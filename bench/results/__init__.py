"""The results of the public API (`bench.api`), one module per command: frozen dataclasses
whose `table()` is the text and whose `to_json()` is the `--json` object the matching
`jointbench` command prints (docs/cli.md, docs/schemas/). The command line builds the same
objects and prints these.
"""

from jointbench.bench.results.campaign import CampaignReport
from jointbench.bench.results.diagnose import DiagnosisResult
from jointbench.bench.results.diagnose_runs import RunsDiagnosis
from jointbench.bench.results.identify import Estimate, Fit
from jointbench.bench.results.import_log import ImportReport
from jointbench.bench.results.runs import RunsFit
from jointbench.bench.results.survey import SurveyResult

__all__ = ["Estimate", "Fit", "DiagnosisResult", "CampaignReport", "SurveyResult",
           "ImportReport", "RunsFit", "RunsDiagnosis"]
