# frf_ident — quick start: `make demo`, `make test` (no ROS needed; a virtualenv is bootstrapped).
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
OUT    ?= out
# an empty OUT would make `make demo` run `rm -rf /demo`
ifeq ($(strip $(OUT)),)
$(error OUT is empty: set it to an output directory, e.g. OUT=out)
endif

# Every DDS participant we start stays on loopback (docs/CONTRACT.md §2). With ROS 2 sourced
# (.ci/run does it when ../shared/ros2 exists) the ROS tests run on rmw_cyclonedds_cpp.
export ROS_AUTOMATIC_DISCOVERY_RANGE := LOCALHOST
export RMW_IMPLEMENTATION := rmw_cyclonedds_cpp
export CYCLONEDDS_URI := file://$(CURDIR)/config/cyclonedds-localhost.xml
export NUMBA_CACHE_DIR := $(CURDIR)/$(VENV)/numba_cache
export MPLBACKEND := Agg

.PHONY: demo test bench venv clean

$(STAMP): setup.py
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

venv: $(STAMP)

# the demo's output is regenerated (the same simulated run), so an earlier one is replaced
# instead of refused (frf-ident demo never writes over an existing bag)
demo: $(STAMP)
	rm -rf $(OUT)/demo
	$(PY) -m frf_ident demo --out $(OUT)/demo

# one pytest-xdist worker per core; a module's shared fixtures keep its tests on one worker
# (xdist_group marks)
# one BLAS thread per worker: two xdist workers on two cores, each with a multi-threaded
# OpenBLAS, oversubscribe the cores (the rational fit took 10.4 s instead of 0.7 s that way)
test: export OPENBLAS_NUM_THREADS := 1
test: $(STAMP)
	$(PY) -m pytest -q -ra --durations=15 -n auto --dist loadgroup test

bench: $(STAMP)
	$(PY) -m benchmarks --markdown

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info .pytest_cache
