"""jointbench: a MuJoCo virtual testbench for identifying joint stiffness and drive-chain
parameters (Pham, Gautier, Poignet, ICRA 2001).

The package maps the repository's top-level folders: `jointbench.identification` (pure
numerics, no MuJoCo), `jointbench.bench` (MuJoCo experiments, analyses, command line) and
`jointbench.models` (MJCF assets and ground truth).

The public API (`jointbench.bench.api`) is loaded on first use, so that `import jointbench`
stays light:

    import jointbench as jb
    log = jb.simulate("prototype", seed=1)
    fit = jb.identify(log)                 # fit.table(), fit.to_json(), fit.plot()
    fit.parameters["K"]                    # Estimate(value, sigma, sigma_hac, unit)
    d = jb.diagnose(log); d.write("out/")
"""

from __future__ import annotations

__version__ = "0.2.0"

_API = ("simulate", "identify", "diagnose", "campaign", "survey", "import_log", "read_log",
        "write_log", "Log", "Fit", "Estimate", "DiagnosisResult", "CampaignReport",
        "SurveyResult", "ImportReport", "RunsFit", "RunsDiagnosis")
__all__ = ["__version__", *_API]


def __getattr__(name: str):
    """`jointbench.simulate` and the other names of the public API, imported on first use."""
    if name in _API:
        from jointbench.bench import api  # lazy: numpy, scipy and MuJoCo load here

        return getattr(api, name)
    raise AttributeError(f"module 'jointbench' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_API])
