# Set-up on a fresh Debian machine, as root (see README):
#   make demo   installs everything (system packages too) and runs the demo
#   make test   installs what the tests need and runs them
# Both are idempotent.

VENV ?= .venv
APT_PKGS := python3 python3-venv python3-pip libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri libosmesa6
# Headless MuJoCo rendering through Mesa's EGL software device; MUJOCO_GL=osmesa also works.
export MUJOCO_GL ?= egl
# pip's wheel cache would hold a second copy of every dependency (about 1 GB): not kept
export PIP_NO_CACHE_DIR := 1

.PHONY: demo test system clean

system:
	@if ! dpkg -s $(APT_PKGS) >/dev/null 2>&1; then \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
	  apt-get install -y -qq --no-install-recommends $(APT_PKGS); fi

$(VENV)/bin/python: | system
	python3 -m venv $(VENV)
	$(VENV)/bin/python -m pip install -q --upgrade pip

$(VENV)/.runtime: pyproject.toml | $(VENV)/bin/python
	$(VENV)/bin/python -m pip install -q -e .
	touch $@

$(VENV)/.test: pyproject.toml $(VENV)/.runtime
	$(VENV)/bin/python -m pip install -q -e '.[test]'
	touch $@

demo: $(VENV)/.runtime
	$(VENV)/bin/handsynth demo --out demo_out

# One BLAS/OpenMP thread per test worker: the workers already fill the cores, and threaded
# linear algebra competing with them made the suite about a fifth slower (354 s against 287 s,
# 2,425 tests on 2 cores, 2026-11-27).
test: $(VENV)/.test
	OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 \
	  $(VENV)/bin/python -m pytest -q -n auto --maxprocesses 4

clean:
	rm -rf $(VENV) demo_out
