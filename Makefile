# cadsim — every target sets itself up; nothing needs to be installed or exported by hand.
SHELL := /bin/bash
.SHELLFLAGS := -o pipefail -c
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
EXTRAS := test,highway,dask
# Off-screen GL for pyrender: EGL (Mesa llvmpipe) and OSMesa; OpenMP for LightGBM (the learned
# matchers). Installed when missing and we may.
GL_PKGS := libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6 libgomp1
export SDL_VIDEODRIVER := dummy
export MPLBACKEND := Agg

.PHONY: all venv sysdeps browser test bench lint format reproduce report clean distclean

all: test

# The venv is rebuilt only when pyproject.toml changes: a second `make test` installs nothing.
$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip 2>&1 | { grep -v '^WARNING: Location' || true; }
	$(PY) -m pip install --quiet -e '.[$(EXTRAS)]' 2>&1 | { grep -vE '^WARNING: Location|BuildBackendWarning|^ *$$' || true; }
	@touch $(STAMP)

venv: sysdeps $(STAMP)

# Installs the Mesa GL libraries if one is missing (needs root + apt). Without them the renderer
# falls back to whichever backend loads, and fails with a message naming the missing library.
sysdeps:
	@missing=""; for p in $(GL_PKGS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    echo "installing system GL libraries:$$missing"; \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null) \
	      || echo "warning: apt-get install$$missing failed; rendering falls back to the backend that loads"; \
	  else \
	    echo "warning: missing system packages:$$missing (install with: sudo apt-get install -y$$missing)"; \
	  fi; \
	fi

# Chromium renders the results report (results/index.html) in tests/test_report_site.py, which is
# skipped without it. Installed when missing and we may (root + apt), as sysdeps does.
BROWSER_PKGS := chromium
browser:
	@if ! dpkg -s $(BROWSER_PKGS) >/dev/null 2>&1 && ! command -v chromium >/dev/null \
	    && ! command -v chromium-browser >/dev/null; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    echo "installing $(BROWSER_PKGS) (the report's browser test)"; \
	    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $(BROWSER_PKGS) >/dev/null) \
	      || echo "warning: apt-get install $(BROWSER_PKGS) failed; the report's browser test is skipped"; \
	  else \
	    echo "warning: missing system package: $(BROWSER_PKGS) (install with: sudo apt-get install -y $(BROWSER_PKGS)); the report's browser test is skipped"; \
	  fi; \
	fi

# The tests that touch numerics run a second time with numpy's AVX-512 code paths off, so that both
# dispatch levels are exercised on every machine that has them (DESIGN §10; docs/reproducibility.md).
NUMERIC_TESTS := tests/test_matchers_*.py tests/test_jit_kernels.py tests/test_metrics.py \
	tests/test_calibration.py tests/test_tuning.py tests/test_thinning.py tests/test_sweep_regime.py \
	tests/test_paired_differences.py tests/test_depth_noise.py tests/test_detection.py \
	tests/test_localisation.py tests/test_attribute_noise.py tests/test_camera.py \
	tests/test_validation_synthetic.py tests/test_validation_metrics.py

test: venv browser
	$(PY) -m pytest -q --durations=15
	@features="$$($(PY) tests/cpu_dispatch.py --avx512-features)"; \
	if [ -n "$$features" ]; then \
	  echo "numeric tests again with NPY_DISABLE_CPU_FEATURES=\"$$features\""; \
	  NPY_DISABLE_CPU_FEATURES="$$features" $(PY) -m pytest -q $(NUMERIC_TESTS); \
	else \
	  echo "no AVX-512 on this CPU: numpy has one dispatch level here (tests/test_cpu_independence.py injects last-bit faults instead)"; \
	fi

bench: venv
	$(PY) -m eval.bench

lint: venv
	$(PY) -m ruff check cadsim matchers eval tests examples
	$(PY) -m ruff format --check cadsim matchers eval tests examples

format: venv
	$(PY) -m ruff format cadsim matchers eval tests examples
	$(PY) -m ruff check --fix cadsim matchers eval tests examples

# SCALE=k multiplies every split size (pairs, sequences, snapshots of every study) by k:
# `make reproduce SCALE=2`; unset, the default sizes.
# One BLAS/OpenMP thread in the parent too: it scores, fits and fuses while the worker processes
# (one thread each) use every core; a multi-threaded eigh there only fights them (docs/multi-agent.md).
ONE_THREAD := OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1

reproduce: venv
	$(ONE_THREAD) $(PY) -m eval.reproduce $(if $(SCALE),--scale $(SCALE))

# The report (results/README.md, results/index.html) and the README's results section, written
# again from the files in results/: nothing is recomputed.
report: venv
	$(PY) -m eval.readme_results

clean:
	rm -rf .pytest_cache build *.egg-info

distclean: clean
	rm -rf $(VENV)
