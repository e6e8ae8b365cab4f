# TreeSketch: the two commands are `make demo` and `make test`.
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
OUT ?= out

.PHONY: setup demo test test-fast lint bench reports clean

$(STAMP): pyproject.toml scripts/setup.sh
	bash scripts/setup.sh

setup: $(STAMP)

## Run the main job: the bundled example sketch -> TSN -> refinement -> 3D tree.
demo: $(STAMP)
	mkdir -p $(OUT)
	$(VENV)/bin/treesketch predict examples/sketch_maple.png --budget 40 \
		--out $(OUT)/demo_tree.glb --params $(OUT)/demo_tree.json \
		--preset $(OUT)/demo_tree_sapling.py --compare $(OUT)/demo_compare.png

## Run the whole test suite (slow end-to-end tests included).
test: $(STAMP)
	$(PY) -m pytest -q

## Only the fast tests.
test-fast: $(STAMP)
	$(PY) -m pytest -q -m "not slow"

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

bench: $(STAMP)
	$(PY) benchmarks/bench_grow.py
	$(PY) benchmarks/bench_render.py
	$(PY) benchmarks/bench_tsn.py

clean:
	rm -rf $(OUT) .pytest_cache
