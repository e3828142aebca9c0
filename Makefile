# Two commands do all the setup: `make test` and `make reproduce`.
# Any Python >= 3.11; python3.11 (the version constraints.txt is tested on) when present.
PYTHON ?= $(shell command -v python3.11 >/dev/null 2>&1 && echo python3.11 || echo python3)
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# Debian libraries that open3d needs at import time on a fresh machine.
SYSTEM_LIBS := libusb-1.0-0 libgomp1
NB := $(sort $(wildcard notebooks/*.ipynb))
# Open3D reduces ICP sums over OpenMP threads in a run-dependent order; one thread makes
# the same seed give the same CSV, byte for byte (parallelism comes from joblib processes).
export OMP_NUM_THREADS := 1

.PHONY: test unit notebooks reproduce bench system-deps browser clean

test: unit notebooks

system-deps:
	@missing=""; \
	for lib in $(SYSTEM_LIBS); do dpkg -s $$lib >/dev/null 2>&1 || missing="$$missing $$lib"; done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = "0" ]; then \
	    echo "installing system libraries:$$missing"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing; \
	  else \
	    echo "open3d needs system libraries that are missing. Run:"; \
	    echo "  sudo apt-get install -y$$missing"; \
	    exit 1; \
	  fi; \
	fi

# Headless Chromium renders the exported HTML for the screenshot test. It is optional: when it
# cannot be installed (not root, no apt), say why and go on; that one test then skips.
browser:
	@if command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 \
	    || command -v google-chrome >/dev/null 2>&1; then :; \
	elif [ "$$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "installing chromium (headless screenshot test of the HTML viewer)"; \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; } \
	    || echo "chromium could not be installed (apt-get failed); the screenshot test will be skipped"; \
	else \
	  echo "chromium is not installed and cannot be installed here (needs root and apt-get);"; \
	  echo "the screenshot test will be skipped. To run it: sudo apt-get install -y chromium"; \
	fi

# Version ranges live in pyproject.toml; the exact tested set in constraints.txt.
$(STAMP): pyproject.toml constraints.txt | system-deps
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "need Python >= 3.11 on PATH (set PYTHON=...)"; exit 1; }
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' \
	  || { echo "$(PYTHON) is older than Python 3.11; set PYTHON=python3.11 (or newer)"; exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -c constraints.txt -e ".[test,dask]"
	$(PY) -m ipykernel install --sys-prefix --name python3 >/dev/null
	touch $(STAMP)

unit: system-deps browser $(STAMP)
	$(PY) -m pytest -q tests

# Every notebook under nbval in fast mode; fast mode writes under build/, never data/results/.
notebooks: system-deps $(STAMP)
	MAVAC_FAST=1 $(PY) -m pytest -q --nbval-lax --nbval-current-env -p no:cacheprovider $(NB)

# Paper scale: writes figures/ and data/results/. Executed copies go to build/executed.
# Trials run two at a time (MAVAC_JOBS, the machine's 2 cores); results do not depend on it.
reproduce: system-deps $(STAMP)
	mkdir -p build/executed
	for nb in $(NB); do \
	  MAVAC_FAST=0 MAVAC_JOBS=$${MAVAC_JOBS:-2} $(VENV)/bin/jupyter nbconvert --to notebook --execute \
	    --ExecutePreprocessor.timeout=-1 --output-dir build/executed "$$nb" || exit 1; \
	done

bench: system-deps $(STAMP)
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

clean:
	rm -rf build .pytest_cache
