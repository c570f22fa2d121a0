# armguard — the two commands: `make run` and `make test`.
SHELL  := bash
.SHELLFLAGS := -o pipefail -c
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
HASH   := $(shell cat pyproject.toml | cksum | cut -d' ' -f1)
STAMP_RUN  := $(VENV)/.installed-run-$(HASH)
STAMP_TEST := $(VENV)/.installed-test-$(HASH)
PIP_QUIET  := 2>&1 | { grep -v "^WARNING: Location" || true; }

.PHONY: run test bench install browser clean clean-cache smoke-wheel

# Installing: uv (a resolver and installer that runs the same install in ~8 s instead of pip's
# ~40 s: most of `make run`'s first minute) when it can be had, else pip; both install what
# pyproject.toml asks for.  `make ... INSTALLER=pip` forces pip.
INSTALLER ?= uv
UV     := $(VENV)/bin/uv
# The venv is made without pip (its ensurepip took ~5 s of a fresh `make run`): uv is installed into
# it by the system's pip (`pip --python`, pip >= 22.3); pip is put in the venv only where that or uv
# fails, for the pip install.
define install
	test -x $(PY) || $(PYTHON) -m venv --without-pip $(VENV)
	if [ "$(INSTALLER)" = uv ] && { test -x $(UV) || $(PYTHON) -m pip --python $(PY) install -q uv $(PIP_QUIET) \
	     || { $(PY) -m ensurepip >/dev/null && $(PY) -m pip install -q uv $(PIP_QUIET); }; } && test -x $(UV); then \
	  $(UV) pip install -q --python $(PY) $(1) \
	    || { $(PY) -m ensurepip >/dev/null && $(PY) -m pip install -q --no-compile $(1) $(PIP_QUIET); }; \
	else $(PY) -m ensurepip >/dev/null && $(PY) -m pip install -q --no-compile $(1) $(PIP_QUIET); fi
endef

# run: armguard and what running needs (no test extras: no mujoco, pybullet, playwright)
$(STAMP_RUN): pyproject.toml
	$(call install,-e .)
	rm -f $(VENV)/.installed-run-* && touch $(STAMP_RUN)

# test: everything, test extras included (implies the run install)
$(STAMP_TEST): pyproject.toml
	$(call install,-e ".[test]")
	rm -f $(VENV)/.installed-test-* $(VENV)/.installed-run-* && touch $(STAMP_TEST) $(STAMP_RUN)

install: $(STAMP_TEST)

## run: set up .venv (run dependencies only) and run the main job on the built-in scenes
run: $(STAMP_RUN)
	$(VENV)/bin/armguard demo

## browser: Debian's chromium for the end-to-end console test (needs root or sudo)
browser:
	@if [ ! -x /usr/bin/chromium ]; then \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && apt-get install -y -qq chromium >/dev/null; \
	  elif command -v sudo >/dev/null; then sudo apt-get update -qq && sudo apt-get install -y -qq chromium >/dev/null; \
	  else echo "chromium missing and no root: the browser test will be skipped (fails under CI)"; fi; fi

## test: set up .venv with test extras, check the layers (import-linter's contracts in
## pyproject.toml, docs/architecture.md), run every test, then the installed-wheel smoke check
test: $(STAMP_TEST) browser
	$(VENV)/bin/lint-imports
	$(PY) -m pytest -n 2 --dist loadfile -q
	$(PY) tools/smoke_wheel.py

## smoke-wheel: build the sdist and wheel, install the wheel in a fresh venv in a temp folder, run
## `armguard check ranger` and load_model("hermes") from another folder (tools/smoke_wheel.py;
## it reuses the checkout's compiled kernels, so after the tests it compiles nothing)
smoke-wheel: $(STAMP_TEST)
	$(PY) tools/smoke_wheel.py

## bench: run the benchmarks and rewrite docs/performance.md
bench: $(STAMP_TEST)
	$(PY) -m bench

## clean-cache: drop numba's on-disk kernel cache (cache=True only notices edits to a kernel's
## own file, not to the kernels it calls: run this after editing geometry kernels)
clean-cache:
	find src plugins -name "*.nbi" -o -name "*.nbc" | xargs rm -f

clean: clean-cache
	rm -rf $(VENV) build *.egg-info out
