# The two commands a newcomer runs first: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test

.PHONY: demo test test-all lint bench clean docs

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# The demo's headline commands (report, explore, lut -o *.exr, verify --certified) need these extras.
$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e '.[explore,exr,certified]'
	touch $@

$(TEST_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[test,bench]'
	touch $@

demo: $(STAMP)
	$(BIN)/brdfnorm report -o report

# The quick tier (a few minutes): every module and command checked once; the long sweeps are marked `slow`.
test: $(TEST_STAMP)
	$(BIN)/python -m pytest -q -n auto -m "not slow"

# Everything, the slow sweeps included (what .ci/run runs).
test-all: $(TEST_STAMP)
	$(BIN)/python -m pytest -q -n auto

lint: $(TEST_STAMP)
	$(BIN)/ruff check src tests benchmarks

bench: $(TEST_STAMP)
	$(BIN)/python benchmarks/run.py

DOCS_STAMP := $(VENV)/.installed-docs

$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[docs]'
	touch $@

# The documentation site from docs/ into site/; strict: a broken link or a docstring that fails to render fails.
docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --site-dir site

clean:
	rm -rf $(VENV) report build site src/*.egg-info
