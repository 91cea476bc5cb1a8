# cadsim — every target sets itself up; nothing needs to be installed or exported by hand.
SHELL := /bin/bash
.SHELLFLAGS := -o pipefail -c
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
EXTRAS := test,highway,dask
# Off-screen GL for pyrender: EGL (Mesa llvmpipe) and OSMesa. Installed when missing and we may.
GL_PKGS := libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6
export SDL_VIDEODRIVER := dummy
export MPLBACKEND := Agg

.PHONY: all venv sysdeps test bench lint format reproduce clean distclean

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

test: venv
	$(PY) -m pytest -q

bench: venv
	$(PY) -m eval.bench

lint: venv
	$(PY) -m ruff check cadsim matchers eval tests
	$(PY) -m ruff format --check cadsim matchers eval tests

format: venv
	$(PY) -m ruff format cadsim matchers eval tests
	$(PY) -m ruff check --fix cadsim matchers eval tests

reproduce: venv
	$(PY) -m eval.reproduce

clean:
	rm -rf .pytest_cache build *.egg-info

distclean: clean
	rm -rf $(VENV)
