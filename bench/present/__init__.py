"""The presentation layer: text tables, JSON objects, figures and report files of the
analyses' results (one module per analysis). The estimators return frozen dataclasses and
never format; the command line and the public API (`jointbench.bench.api`) call these."""
