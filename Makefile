# sonartrack — two commands: `make demo` and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
OUT    ?= results

.PHONY: demo test lint bench docs install install-test install-docs stonesoup-suite browser clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# Stamps so that a second `make` does not reinstall; they depend on pyproject.toml.
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $(VENV)/.installed $@

$(VENV)/.installed-docs: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[docs]"
	touch $(VENV)/.installed $@

install: $(VENV)/.installed
install-test: $(VENV)/.installed-test
install-docs: $(VENV)/.installed-docs

# Stone Soup's own tests (its sdist has them, its wheel not), for tests/stonesoup/test_stonesoup_suite.py,
# which runs them with our components swapped in. Downloaded here, at install time, for the installed
# Stone Soup version; the tests never use the network (without this folder they skip, saying why).
STONESOUP_SUITE := $(VENV)/stonesoup-suite
$(STONESOUP_SUITE)/VERSION: $(VENV)/.installed-test tests/stonesoup/fetch_stonesoup_suite.py
	$(BIN)/python tests/stonesoup/fetch_stonesoup_suite.py $(STONESOUP_SUITE)

stonesoup-suite: $(STONESOUP_SUITE)/VERSION

demo: install
	$(BIN)/sonartrack reproduce all --quick --out $(OUT)
	@echo "Report: $(abspath $(OUT))/report.html"

test: install-test stonesoup-suite browser lint docs
	$(BIN)/python -m pytest -q -n 2

# Debian's headless Chromium (and its driver) for the console's browser test (tests/console/test_browser.py),
# installed with apt-get only where missing; the test drives the browser over the DevTools protocol.
browser:
	@if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then \
		command -v apt-get >/dev/null || { echo "make browser: no apt-get here; install chromium yourself" >&2; exit 1; }; \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq chromium chromium-driver; \
	fi

# The site in docs/_build/html: API reference, pages, tutorials executed (warnings are errors). Incremental: a
# failed build drops its saved state, so the next one reads every page again and cannot pass on stale pages.
docs: install-docs
	NUMBA_CACHE_DIR=$(CURDIR)/.numba-cache $(BIN)/python -m sphinx -W --keep-going -j 2 -q -b html \
		-d docs/_build/doctrees docs docs/_build/html || { rm -rf docs/_build/doctrees; exit 1; }
	@echo "Docs: $(abspath docs/_build/html)/index.html"

lint: install-test
	$(BIN)/ruff check src tests benchmarks examples docs

bench: install-test
	$(BIN)/python benchmarks/run_all.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache docs/_build docs/api docs/auto_tutorials docs/sg_execution_times.rst
