# All set-up happens here: `make demo` and `make test` work on a fresh machine.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench system-deps clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev]'
	touch $(STAMP)

# graphviz renders the state-machine diagrams (mrcomm fsm); without it the diagram
# falls back to Mermaid text and the SVG test is skipped with its reason.
system-deps:
	@command -v dot >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    (DEBIAN_FRONTEND=noninteractive apt-get install -y -qq graphviz >/dev/null 2>&1 || \
	     (apt-get update -qq >/dev/null 2>&1 && \
	      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq graphviz >/dev/null 2>&1)) || \
	    echo "note: could not install graphviz; diagram rendering tests will be skipped"; \
	  else echo "note: graphviz (dot) not installed; diagram rendering tests will be skipped"; fi; }

demo: $(STAMP) system-deps
	$(BIN)/mrcomm run data/scenarios/s1.yaml --network wlan --spl 0 --behaviour nb --seed 1 --plot demo-s1.png

test: $(STAMP) system-deps
	MPLBACKEND=Agg $(BIN)/pytest -q -n 2

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks scripts
	$(BIN)/mypy

bench: $(STAMP)
	$(BIN)/python benchmarks/run_benchmarks.py

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache
