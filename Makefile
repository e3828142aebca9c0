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

.PHONY: test unit notebooks reproduce verify bench system-deps browser clean

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

# Paper scale: writes figures/ and data/results/ (executed copies in build/executed), two
# notebooks at a time (NB_JOBS) with MAVAC_JOBS trial worker(s) each (05 and 12 two, see below) on
# the machine's 2 cores. Results do not depend
# on the schedule: each trial takes its seed from its argument. Every notebook's wall and CPU
# time goes to data/results/reproduce_times.csv, the commit and settings that made each result
# file to data/results/provenance.json (mavac/verify.py). ONLY=05 runs one notebook.
reproduce: system-deps $(STAMP)
	@start=$$(date +%s); \
	$(MAKE) --no-print-directory -j$(NB_JOBS) at-scale OUT=. EXECUTED=build/executed \
	  && $(PY) -m mavac.verify finish --out . --executed build/executed --started $$start

# Runs the paper-scale notebooks into VERIFY_OUT, from an empty cache unless VERIFY_CACHE says
# otherwise, then compares every CSV, JSON and .npz they wrote with the committed one; exits
# non-zero on any difference (docs/reproduce.md). ONLY=05 runs and checks one notebook.
verify: system-deps $(STAMP)
	rm -rf $(VERIFY_OUT)
	@start=$$(date +%s); \
	MAVAC_CACHE=$(VERIFY_CACHE) $(MAKE) --no-print-directory -j$(NB_JOBS) at-scale OUT=$(VERIFY_OUT) \
	    EXECUTED=$(VERIFY_OUT)/executed \
	  && $(PY) -m mavac.verify finish --out $(VERIFY_OUT) --executed $(VERIFY_OUT)/executed --started $$start
	$(PY) -m mavac.verify --fresh $(VERIFY_OUT) --committed . $(if $(ONLY),--only $(ONLY))

NB_NUM := $(foreach n,$(NB),$(firstword $(subst _, ,$(notdir $(n)))))
RUNS := $(addprefix run-,$(NB_NUM))
.PHONY: at-scale $(RUNS)
NB_JOBS ?= 2
MAVAC_JOBS ?= 1
OUT ?= .
EXECUTED ?= build/executed
VERIFY_OUT ?= build/verify
VERIFY_CACHE ?= $(abspath $(VERIFY_OUT))/cache
ifneq ($(ONLY),)
  ifeq ($(filter $(ONLY),$(NB_NUM)),)
    $(error ONLY must be a notebook number ($(NB_NUM)), got '$(ONLY)')
  endif
endif

at-scale: $(if $(ONLY),run-$(ONLY),$(RUNS))

$(RUNS): run-%:
	MAVAC_FAST=0 MAVAC_JOBS=$(MAVAC_JOBS) $(PY) -m mavac.verify run $* --out $(OUT) --executed $(EXECUTED)

# Two lanes, side by side: A = 00 01 02 03 04 05, B = 06 07 08 09 10 11 12. Notebook 05 (the
# online trials) is the longest single notebook, so lane B runs everything else beside it.
# Notebooks sharing an on-disk cache (build/cache) keep their order, so the first computes an
# entry and the next reads it (never two computing it at once): 01-05 the machines'
# reachability maps and offline plans; 06 -> 07 -> 08 the Kabir baseline reach sweeps; 12 the
# maps of 01-04, the baselines of 06-08 and 05's online plans (its online parts run on them).
# 12 runs last, alone once 05 and 11 are done: the paper notebooks (00-11) then finish as they
# did without it, and 12's trials get both cores. 00, 09, 10 and 11 use no disk cache: their
# place in a lane only balances the two lanes.
ifeq ($(ONLY),)
run-01: run-00
run-02: run-01
run-03: run-02
run-04: run-03
run-05: run-04
run-07: run-06
run-08: run-07
run-09: run-08
run-10: run-09
run-11: run-10
run-12: run-05 run-11
endif
# Notebooks 05 and 12 run their trials on two workers: beside the other lane they share the
# cores, and once it is done they have both (trials take their seeds from their arguments: same
# rows).
run-05 run-12: MAVAC_JOBS = 2

bench: system-deps $(STAMP)
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

clean:
	rm -rf build .pytest_cache
