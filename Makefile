# TreeSketch: the two commands are `make demo` and `make test`.
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
OUT ?= out

.PHONY: setup demo test test-fast lint bench reports notebooks clean blender-test blender-addon

$(STAMP): pyproject.toml scripts/setup.sh
	bash scripts/setup.sh

setup: $(STAMP)

## Run the main job: the bundled example sketch -> TSN -> refinement -> 3D tree.
demo: $(STAMP)
	mkdir -p $(OUT)
	$(VENV)/bin/treesketch predict examples/sketch_maple.png --budget 40 \
		--out $(OUT)/demo_tree.glb --params $(OUT)/demo_tree.json \
		--preset $(OUT)/demo_tree_sapling.py --compare $(OUT)/demo_compare.png

## Run the whole test suite (slow end-to-end tests included) on two workers, each test
## module on one of them (tests/conftest.py says why).
XDIST := -n 2 --dist loadfile
test: $(STAMP)
	$(PY) -m pytest -q $(XDIST)

## Only the fast tests.
test-fast: $(STAMP)
	$(PY) -m pytest -q $(XDIST) -m "not slow"

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

bench: $(STAMP)
	$(PY) benchmarks/bench_grow.py
	$(PY) benchmarks/bench_render.py
	$(PY) benchmarks/bench_tsn.py

## The paper's tables for the shipped network into reports/ (treesketch eval paper: builds
## its own seeded test data under out/paper_cache; full sizes, estimated 20-25 min on two
## cores). `make reports REPORT_ARGS=--quick` is the few-minute check.
REPORT_ARGS ?=
reports: $(STAMP)
	$(PY) -m treesketch.cli eval paper $(REPORT_ARGS)

## Re-execute notebooks/*.ipynb and store them with their (small) outputs.
notebooks: $(STAMP)
	$(PY) scripts/run_notebooks.py

## The Blender add-on as an installable zip: $(OUT)/treesketch_addon.zip.
blender-addon: $(STAMP)
	$(PY) scripts/blender_addon_zip.py $(OUT)/treesketch_addon.zip

## Our GLB in Blender's glTF importer and the add-on end to end, headless (about a minute
## once Blender is there). Installs Debian's blender and python3-numpy when missing (root).
blender-test: $(STAMP)
	@if ! command -v blender >/dev/null 2>&1 || ! dpkg -s python3-numpy >/dev/null 2>&1; then \
		if [ "$$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then \
			echo "blender-test: installing Debian packages blender python3-numpy"; \
			apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq blender python3-numpy; \
		else \
			echo "blender-test: needs Debian's blender and python3-numpy (run as root to install)" >&2; exit 2; \
		fi; \
	fi
	bash scripts/blender_test.sh

clean:
	rm -rf $(OUT) .pytest_cache
