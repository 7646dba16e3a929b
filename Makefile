# mechviz: `make run` serves the viewer, `make test` runs every test (`make test-fast`: those not
# marked slow or browser, for the edit-test loop), `make bench` charts speed against accuracy
# (into a temporary folder), `make docs` builds the site into build/docs. `make screenshots`,
# `make bench-docs`, `make readme-gif` and `make atlas-docs` refresh the pictures and tables
# committed under docs/ (`bench-docs` also the speed page's figures); nothing else writes there.
# Each target creates .venv and installs the project (editable) on first use.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin

.PHONY: run test test-fast docs bench bench-docs screenshots readme-gif atlas-docs lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e '.[test]'
	touch $@ $(VENV)/.installed

run: $(VENV)/.installed
	$(BIN)/mechviz view

test: lint
	$(BIN)/python -m pytest

test-fast: lint
	$(BIN)/python -m pytest -q -m "not slow and not browser"

# The manual: the Sphinx site built from docs/ (pages, the API reference from the docstrings,
# the command-line and demo-file references from the code, the example notebooks executed, the
# gallery of every built-in demo recorded), warnings as errors, into build/docs (ignored by git).
DOCS_OUT ?= build/docs
docs: $(VENV)/.installed-test
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs $(DOCS_OUT)
	@echo "the site: $(DOCS_OUT)/index.html"

# The code as the formatter writes it, and the linter's rules (pyproject.toml): `ruff format .`
# rewrites what this refuses.
lint: $(VENV)/.installed-test
	$(BIN)/ruff format --check .
	$(BIN)/ruff check .

bench: $(VENV)/.installed-test
	$(BIN)/mechviz bench

# The benchmark's figures on the site: the peers installed, the full run (30-60 minutes) written
# to docs/bench, then docs/bench/tables.md and the blocks of docs/speed.md rendered from its
# results.json. The page's blocks are checked first, so a bad page fails before the run.
# The bench exits with status 1 when it misses a target and writes its figures all the same;
# what counts is that it wrote a new results.json.
bench-docs: $(VENV)/.installed-test
	$(BIN)/python -m mechviz.bench.docs --check docs/speed.md
	$(BIN)/python -m pip install -q -e '.[peers]'
	stamp=$$(mktemp) && trap 'rm -f "$$stamp"' EXIT && \
	{ $(BIN)/mechviz bench --peers --out docs/bench; \
	  [ docs/bench/results.json -nt "$$stamp" ] || { echo "bench-docs: the run wrote no results"; exit 1; }; }
	$(BIN)/python -m mechviz.bench.docs docs/bench docs/speed.md

screenshots: $(VENV)/.installed-test
	MECHVIZ_WRITE_DOCS=1 MECHVIZ_ALL_DEMOS=1 $(BIN)/python -m pytest -q \
		tests/test_viewer_browser.py tests/test_recording_browser.py tests/test_pictures_browser.py

# The GIF on the site's "Videos, stills and notebooks" page: the radial-kick demo filmed in headless Chromium.
README_GIF := docs/img/radial-kick.gif
readme-gif: $(VENV)/.installed-test
	tmp=$$(mktemp -d) && trap 'rm -rf "$$tmp"' EXIT && \
	$(BIN)/mechviz record radial-kick --out "$$tmp" --duration 8 --fps 10 --video gif --size 640x360 && \
	cp "$$tmp/radial-kick.gif" $(README_GIF).partial && mv $(README_GIF).partial $(README_GIF)

# The atlas maps on the site: the hoop's chaos map (128 x 128 starts, 60 s each) at rest and over
# (theta1, theta1'), its stability and accuracy maps for every fixed-step method, on a
# LocalCluster of this machine's cores; and the viewer's maps of the default hoop.
ATLAS_IMG := docs/img/atlas
atlas-docs: $(VENV)/.installed-test
	$(BIN)/python -m pip install -q -e '.[atlas]'
	tmp=$$(mktemp -d) && trap 'rm -rf "$$tmp"' EXIT && \
	$(BIN)/mechviz atlas chaos --out "$$tmp/chaos" --no-progress && \
	$(BIN)/mechviz atlas chaos --section theta1 --out "$$tmp/chaos-hoop" --no-progress && \
	$(BIN)/mechviz atlas stability --out "$$tmp/stability" --no-progress && \
	$(BIN)/mechviz atlas accuracy --out "$$tmp/accuracy" --no-progress && \
	mkdir -p $(ATLAS_IMG) && \
	for m in chaos stability accuracy; do \
	  cp "$$tmp/$$m/$$m.png" $(ATLAS_IMG)/$$m.png.partial && mv $(ATLAS_IMG)/$$m.png.partial $(ATLAS_IMG)/$$m.png; \
	done && \
	cp "$$tmp/chaos-hoop/chaos.png" $(ATLAS_IMG)/chaos-hoop.png.partial && \
	mv $(ATLAS_IMG)/chaos-hoop.png.partial $(ATLAS_IMG)/chaos-hoop.png
	$(BIN)/python -m mechviz.viz.model.atlas_map

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache
