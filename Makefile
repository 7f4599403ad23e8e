# The two commands of the README. Both create .venv if needed and install the project.
PY ?= $(shell command -v python3.11 2>/dev/null || command -v python3 2>/dev/null)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test

.PHONY: run test check check-ray lint clean chromium peers notebook

$(BIN)/python:
	@$(PY) -c 'import sys; assert sys.version_info[:2] == (3, 11)' 2>/dev/null \
		|| { echo "need Python 3.11 on PATH (python3.11 or python3)"; exit 1; }
	$(PY) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/pip install -q -e .
	@touch $@

# The cluster extra (Ray) too: the sweep's Ray test runs a local 2-CPU instance.
$(TEST_STAMP): $(STAMP)
	$(BIN)/pip install -q -e '.[test,cluster]'
	@touch $@

# numba compiles the control tick's kernels (controller/compiled.py) at their first call and keeps
# them in __pycache__: two short walks compile them once (about 30 s of CPU) rather than every
# test or worker process that happens to start first (a live robot would stall meanwhile); the
# free waist of redundancy is a kernel of its own (the IK's step with no waist rate); a changed
# kernel module compiles again.
KERNELS := $(VENV)/.kernels
$(KERNELS): $(STAMP) $(wildcard controller/*.py) pelvic_walk/core/world.py
	$(BIN)/pelvic-walk simulate --method mpc --step-length 0.2 --steps 1 > /dev/null
	$(BIN)/pelvic-walk simulate --method redundancy --step-length 0.2 --steps 1 > /dev/null
	@touch $@

run: $(STAMP) $(KERNELS)
	$(BIN)/pelvic-walk serve --host 127.0.0.1 --port 8000

# Debian's chromium for the browser test: installed if missing and we are root.
chromium:
	@if [ ! -x /usr/bin/chromium ]; then \
		if [ "$$(id -u)" = "0" ]; then \
			(apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null) \
			|| echo "warning: could not install chromium; the browser test will be skipped"; \
		else echo "warning: /usr/bin/chromium missing and not root; the browser test will be skipped"; fi; \
	fi

# Two processes (pytest-xdist), one test file each, the browser files together (one Chromium
# at a time, tests/conftest.py): many tests wait on real-time walks and servers, so two
# share this 2-core machine's time well.
test: $(TEST_STAMP) $(KERNELS) chromium
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup

# The quick inner loop: unit, API and headless tests; no browser, no study, no wheel build,
# no load test, no mypy (tests/conftest.py marks them). make test still runs everything.
check: $(TEST_STAMP) $(KERNELS)
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup -m "not browser and not slow"

# The Ray set alone (live sessions on Ray: serve --ray on a local instance, the pool's tests on
# Ray actors, a two-node cluster losing a node; about a minute). make test runs it too.
check-ray: $(TEST_STAMP) $(KERNELS)
	$(BIN)/python -m pytest -q -m ray

# Style, types and structure: ruff's rules and formatting everywhere (the notebooks' code
# cells too), mypy on app, controller and pelvic_walk, the import contracts between the
# layers (pyproject.toml [tool.importlinter]).
lint: $(TEST_STAMP)
	$(BIN)/ruff check app controller models tests pelvic_walk notebooks examples
	$(BIN)/ruff format --check app controller models tests pelvic_walk notebooks examples
	$(BIN)/mypy
	$(BIN)/lint-imports

# The course (notebooks/, docs/PYTHON.md): the notebook extra (JupyterLab, its kernel, pandas)
# in .venv, then JupyterLab on notebooks/ (Ctrl-C stops it; as root, as on CI machines, it needs
# --allow-root). The notebooks are stored without outputs; tests/test_notebooks.py runs each
# one top to bottom in `make test`.
NB_STAMP := $(VENV)/.installed-notebook
$(NB_STAMP): $(STAMP)
	$(BIN)/pip install -q -e '.[notebook]'
	@touch $@

notebook: $(NB_STAMP) $(KERNELS)
	$(BIN)/jupyter lab --notebook-dir=notebooks $$([ "$$(id -u)" = 0 ] && echo --allow-root)

# A peer for `pelvic-walk bench`: placo in a venv of its own (it pins an older Pinocchio than
# ours, so it cannot share .venv); the bench finds it there and runs placo's walk loop on our
# robot beside our tick.
PEERS := .venv-peers
peers: $(PEERS)/bin/python
$(PEERS)/bin/python:
	$(PY) -m venv $(PEERS)
	$(PEERS)/bin/pip install -q --upgrade pip
	$(PEERS)/bin/pip install -q 'placo>=0.10,<0.11'

clean:
	rm -rf $(VENV) $(PEERS) .pytest_cache
