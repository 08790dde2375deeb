# a1_leg_fk developer tasks. GNU make + bash; everything runs from one virtual environment.
#
#   make venv       create/refresh $(VENV): pinned requirements + this package (editable)
#   make demo       the node and a demo joint-state stream, feet for ~10 s, verify, exit
#   make lint       ruff check, ruff format --check and mypy (config: ruff.toml, setup.cfg)
#   make test       the test suite but the long families, in $(TEST_WORKERS) workers (each picks its own
#                   ROS domain)
#   make accept     the long families (tests marked accept): every simulated run, tuned and held out
#   make bench      bench/fk_speed.py, ik_speed.py, force_speed.py, contact_speed.py, node_stages.py,
#                   node_cost.py, node_throughput.py, odometry_throughput.py, bag_speed.py
#   make soak       bench/soak.py
#   make fuzz       bench/fuzz_recordings.py: 4000 damaged recordings through bag, gait and odom;
#                   bench/fuzz_nodes.py: 2000 damaged messages on every input topic of every node
#   make mutate     test/mutations.py: curated bugs in the estimation code, each must fail the fast tests
#   make clean      build outputs and caches (keeps $(VENV));  make distclean: $(VENV) too

SHELL := bash
.SHELLFLAGS := -eu -o pipefail -c
.DEFAULT_GOAL := help
.DELETE_ON_ERROR:

VENV ?= .venv
PYTHON ?= python3
# Bounds against hangs (pytest-timeout), far above the normal run: seconds for one test, and for
# the session (checked between tests, so a run ends by about the sum).
TEST_TIMEOUT ?= 300
TEST_SESSION_TIMEOUT ?= 1200
ACCEPT_SESSION_TIMEOUT ?= 3600
PYTEST_ARGS ?=
# make test's worker processes (pytest-xdist), each given whole modules (--dist loadscope: a
# module's fixtures are built once); TEST_WORKERS=0 runs in this process, serially.
TEST_WORKERS ?= 2

BIN := $(VENV)/bin
# The ROS 2 Jazzy wheels are built for CPython 3.11 only.
PYTHON_NEEDED := 3.11
# The requirements stamp is named after a hash of both requirements files: a changed file gives a
# new name, so the install runs again; unchanged files find their stamp and skip it.
REQUIREMENTS := requirements.txt requirements-test.txt requirements-msgs.txt
REQUIREMENTS_HASH := $(shell cat $(REQUIREMENTS) 2>/dev/null | sha256sum | cut -c1-16)
REQUIREMENTS_STAMP := $(VENV)/.requirements-$(REQUIREMENTS_HASH).stamp
PACKAGE_STAMP := $(VENV)/.a1_leg_fk-editable.stamp
# Two `make test` started together (several people share a tree) must not both install.
VENV_LOCK := $(or $(TMPDIR),/tmp)/a1_leg_fk-venv-$(shell echo '$(abspath $(VENV))' | sha256sum | cut -c1-16).lock

.PHONY: help venv venv-unlocked demo lint test accept bench soak fuzz mutate clean distclean

help:
	@sed -n '3,14p' $(firstword $(MAKEFILE_LIST)) | sed 's/^# \{0,1\}//'

venv:
	@flock '$(VENV_LOCK)' $(MAKE) --no-print-directory venv-unlocked

venv-unlocked: $(PACKAGE_STAMP)
	@:

$(BIN)/python:
	@version=$$($(PYTHON) -c 'import sys; print("%d.%d" % sys.version_info[:2])') || { \
	  echo "make: cannot run PYTHON=$(PYTHON)" >&2; exit 1; }; \
	if [ "$$version" != "$(PYTHON_NEEDED)" ]; then \
	  echo "make: $(PYTHON) is Python $$version; the ROS 2 Jazzy wheels need $(PYTHON_NEEDED)" \
	       "(run: make PYTHON=python$(PYTHON_NEEDED) ...)" >&2; exit 1; fi
	$(PYTHON) -m venv $(VENV)

# pip >= 25.3 builds every install through PEP 517/660, so console scripts always land in
# $(BIN) and setup.cfg's [develop]/[install] script dirs (meant for colcon) never apply to pip.
$(REQUIREMENTS_STAMP): | $(BIN)/python
	$(BIN)/python -m pip install --quiet --upgrade 'pip>=25.3'
	$(BIN)/python -m pip install --quiet -r requirements-test.txt
	rm -f $(VENV)/.requirements-*.stamp
	touch $@

# Editable: the tests and the console scripts in $(BIN) run the working tree, so edits (and new
# modules) need no reinstall; only a change to the package metadata does. --no-build-isolation
# builds with the pinned setuptools in the venv instead of whatever the index has that day.
$(PACKAGE_STAMP): setup.py setup.cfg package.xml $(REQUIREMENTS_STAMP)
	$(BIN)/python -m pip install --quiet --no-deps --no-build-isolation --editable .
	@for script in foot_fk_node foot_ik_node joint_state_demo leg_odometry_node a1-leg-fk; do \
	  [ -x $(BIN)/$$script ] || { echo "make: $(BIN)/$$script was not installed" >&2; exit 1; }; \
	done
	touch $@

# A domain of its own unless the caller chose one, so two demos (or a demo and the tests) on one
# machine do not see each other's topics.
demo: venv
	@if [ -z "$${ROS_DOMAIN_ID:-}" ]; then \
	  export ROS_DOMAIN_ID=$$(( (RANDOM + $$$$) % 101 + 1 )); \
	  echo "make demo: ROS_DOMAIN_ID=$$ROS_DOMAIN_ID"; fi; \
	export ROS_AUTOMATIC_DISCOVERY_RANGE=$${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}; \
	exec $(BIN)/a1-leg-fk demo

# Every tool runs, so one run lists all findings; the target fails if any of them found one.
lint: venv
	@status=0; \
	$(BIN)/ruff check . || status=1; \
	$(BIN)/ruff format --check . || status=1; \
	$(BIN)/mypy || status=1; \
	exit $$status

# The long families (marked accept) run in `make accept`, so that .ci/run stays within its budget.
test: venv
	$(BIN)/python -m pytest -q -p no:cacheprovider --timeout=$(TEST_TIMEOUT) \
	  --session-timeout=$(TEST_SESSION_TIMEOUT) -n $(TEST_WORKERS) --dist loadscope \
	  -m 'not accept' $(PYTEST_ARGS) test

accept: venv
	$(BIN)/python -m pytest -q -p no:cacheprovider --timeout=$(TEST_TIMEOUT) \
	  --session-timeout=$(ACCEPT_SESSION_TIMEOUT) -m accept $(PYTEST_ARGS) test

BENCH_SCRIPTS := bench/fk_speed.py bench/ik_speed.py bench/force_speed.py bench/contact_speed.py \
  bench/node_stages.py bench/node_cost.py bench/node_throughput.py bench/odometry_throughput.py \
  bench/bag_speed.py

bench: venv
	@for script in $(BENCH_SCRIPTS); do echo "== $$script"; $(BIN)/python $$script; done

soak: venv
	$(BIN)/python bench/soak.py

# FUZZ_ARGS: e.g. --copies 1 --first-seed SEED to rerun a failure the run printed;
# FUZZ_NODES_ARGS: e.g. --node foot_fk_node --seed SEED.
FUZZ_ARGS ?=
FUZZ_NODES_ARGS ?=
fuzz: venv
	$(BIN)/python bench/fuzz_recordings.py $(FUZZ_ARGS)
	$(BIN)/python bench/fuzz_nodes.py $(FUZZ_NODES_ARGS)

# MUTATE_ARGS: e.g. --jobs 1, or --only 'NAME' to rerun one mutation the table printed.
MUTATE_ARGS ?=
mutate: venv
	$(BIN)/python test/mutations.py $(MUTATE_ARGS)

clean:
	rm -rf build install log dist .pytest_cache .hypothesis .coverage .coverage.* htmlcov \
	  bench/out bench/results ./*.egg-info
	find . -path ./$(VENV) -prune -o -name __pycache__ -type d -prune -exec rm -rf {} +

distclean: clean
	@[ -n "$(VENV)" ] && [ "$(VENV)" != "/" ] || { echo "make: refusing VENV='$(VENV)'" >&2; exit 1; }
	rm -rf $(VENV)
