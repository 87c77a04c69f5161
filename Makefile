# `make demo` and `make test` set everything up from a fresh clone (Python >= 3.11 and make).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo check test fuzz bench bench-peers bench-campaign bench-diagnose battery validate clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,fast]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/jointbench demo --out demo_out

# Test processes (pytest-xdist): one per core by default; `make test JOBS=0` runs in one process.
# Each test file stays in one process (--dist loadfile), so its module fixtures run once; the
# files go out in collection order (--no-loadscope-reorder), which tests/conftest.py sets
# longest first, so that the processes end together.
JOBS ?= auto
XDIST = -n $(JOBS) --dist loadfile --no-loadscope-reorder

# The edit loop: tests/unit and tests/cli without the tests marked slow (under a minute).
check: $(STAMP)
	$(BIN)/python -m pytest -q $(XDIST) tests/unit tests/cli -m 'not slow'

# Everything: unit, cli, sim and validation (what CI runs).
test: $(STAMP)
	$(BIN)/python -m pytest -q $(XDIST)

# The property tests (hypothesis) with fresh random examples; `make test` draws the same ones
# on every run. A failing example is kept in .hypothesis/ and replayed first next time.
fuzz: $(STAMP)
	HYPOTHESIS_PROFILE=explore $(BIN)/python -m pytest -q $(XDIST) tests -m hypothesis

# The speed figures, then the estimator's cost ratios (benchmarks/speed_ratios.py), written
# with the commit, date and machine into docs/validation.md (section speed-ratios).
bench: $(STAMP)
	$(BIN)/python benchmarks/run.py
	$(BIN)/python benchmarks/validate.py --sections speed-ratios --show

# Peer methods side by side (mujoco.sysid needs MuJoCo's `sysid` extra) and the campaign
# benchmark (200-run coverage, filter search); both print figures and assert nothing.
bench-peers: $(STAMP)
	$(BIN)/python -m pip install --quiet 'mujoco[sysid]>=4.0,<5'
	$(BIN)/python benchmarks/peers.py

bench-campaign: $(STAMP)
	$(BIN)/python benchmarks/campaign.py

bench-diagnose: $(STAMP)
	$(BIN)/python benchmarks/diagnose_battery.py --per-effect 5

# The discrepancy battery by visibility (README "Discrepancy battery"): cases in battery_out/,
# the detection curve in docs/figures/detection.png.
battery: $(STAMP)
	$(BIN)/python benchmarks/battery.py --jobs 2 --out battery_out

# Regenerate docs/validation.md, every section (hours on 2 cores); one section:
# `.venv/bin/python benchmarks/validate.py --sections speed` (`--list` shows them).
validate: $(STAMP)
	$(BIN)/python benchmarks/validate.py $(if $(SECTIONS),--sections $(SECTIONS))

clean:
	rm -rf $(VENV) demo_out battery_out build *.egg-info
