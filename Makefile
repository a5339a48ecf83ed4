# All set-up happens here: `make demo` and `make test` work on a fresh machine.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

ROS_VENV := $(VENV)-ros2
ROS_STAMP := $(ROS_VENV)/.attempted

.PHONY: demo test lint bench ns3-validation system-deps clean ros2 docs-tables reproduce

$(STAMP): pyproject.toml examples/mrcomm-repeat/pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev]'
	$(BIN)/pip install --quiet -e examples/mrcomm-repeat  # the example plugin, tested by make test
	touch $(STAMP)

# System packages some features need: graphviz renders the state-machine diagrams
# (mrcomm fsm; without it: Mermaid text), chromium renders the HTML report in the browser
# test and, driven by chromium-driver, runs the operator console's browser test,
# nftables and iproute2 build the network-namespace tests of live mode (certificates
# are made in Python, by the cryptography package), cmake and the C/C++ compilers build
# nav2_msgs' NavigateToPose for the ROS 2 tests. Installed as root with apt-get when
# missing; otherwise the tests that need them are skipped with their reason.
SYSTEM_PACKAGES := graphviz:dot chromium:chromium chromium-driver:chromedriver nftables:nft iproute2:ip cmake:cmake gcc:gcc g++:g++
system-deps:
	@for entry in $(SYSTEM_PACKAGES); do \
	  pkg=$${entry%%:*}; cmd=$${entry##*:}; \
	  command -v $$cmd >/dev/null 2>&1 && continue; \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing $$pkg (apt-get)"; \
	    (DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$pkg >/dev/null 2>&1 || \
	     (apt-get update -qq >/dev/null 2>&1 && \
	      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$pkg >/dev/null 2>&1)) || \
	    echo "note: could not install $$pkg; the tests that need it will be skipped"; \
	  else echo "note: $$pkg not installed; the tests that need it will be skipped"; fi; \
	done

# The main job on the embedded defaults: one mission with its figure, then a small real
# study (12 missions) swept into DuckDB, its statistics, and its HTML report.
demo: $(STAMP) system-deps
	$(BIN)/mrcomm run data/scenarios/s1.yaml --network ah --threshold slt --behaviour lf --spl 25 --seed 1 --plot demo-s1.png
	$(BIN)/mrcomm sweep data/experiments/demo.yaml --db demo.duckdb --jobs 2
	$(BIN)/mrcomm analyze --db demo.duckdb --metric execution_phase_time --metric total_movement_time --metric near_collisions
	$(BIN)/mrcomm report --db demo.duckdb --out demo-report
	@echo "demo: figure demo-s1.png, results demo.duckdb, report demo-report/report.html"

# The ROS 2 extra in an environment of its own (its wheels re-execute every Python of
# their environment with LD_LIBRARY_PATH set): rclpy and the messages from PyPI, and
# nav2_msgs' NavigateToPose built from ros2/nav2_msgs. Where it cannot be built, the
# reason is in $(ROS_VENV)/.skipped and the ROS 2 tests are skipped with it.
ros2: $(ROS_STAMP)

$(ROS_STAMP): pyproject.toml scripts/ros2_env.sh ros2/nav2_msgs/CMakeLists.txt ros2/nav2_msgs/package.xml ros2/nav2_msgs/action/NavigateToPose.action | system-deps
	PYTHON=$(PYTHON) sh scripts/ros2_env.sh $(ROS_VENV)
	touch $@

# The two environments are built side by side (mostly downloads and unpacking: about a
# minute saved on a fresh machine). Live-mode tests run processes against a wall clock:
# they run after the others, so that the simulation tests do not starve them of CPU on a
# 2-core machine, two test files at a time (each mostly waits on the clock: one at a time
# they kept half a core busy), except those over the kernel's network (namespaces,
# emulated links: marked `alone`), which run last, one at a time (beside another file,
# a mission under 30 % kernel loss once overran its time). The ROS 2 tests (in
# tests/ros2 the core environment runs only those that need no ROS) last.
test: system-deps
	$(MAKE) --no-print-directory -j2 $(STAMP) $(ROS_STAMP)
	MPLBACKEND=Agg $(BIN)/pytest -q -n 2 --durations=20 --ignore=tests/live tests examples/mrcomm-repeat/tests
	MPLBACKEND=Agg $(BIN)/pytest -q -n 2 --durations=10 --dist loadfile -m "not alone" tests/live
	MPLBACKEND=Agg $(BIN)/pytest -q -m alone tests/live
	@if [ -f $(ROS_VENV)/.installed ]; then \
	  MPLBACKEND=Agg MRCOMM_ROS2_ENV=1 $(ROS_VENV)/bin/pytest -q tests/ros2; \
	else echo "ROS 2 tests skipped: $$(cat $(ROS_VENV)/.skipped)"; \
	  if [ "$$MRCOMM_REQUIRE_ALL" = 1 ]; then echo "MRCOMM_REQUIRE_ALL=1: failing"; exit 1; fi; fi

# Every results table of the docs (RESULTS, SCENARIOS, BENCHMARKS' speed summary),
# written from its experiment between the page's "generated" markers, with the commit
# the runs were made on (scripts/docs_tables.py). The sweeps are kept in results/docs
# (resumable; delete one to rerun it on new code). About an hour on 2 cores.
docs-tables: $(STAMP)
	$(BIN)/python scripts/docs_tables.py

# The reproduction of the original study (docs/REPRODUCTION.md): 2 x 720 runs, about
# 8 minutes on 2 cores; resumable (the sweeps are kept in results/docs/).
reproduce: $(STAMP)
	$(BIN)/python scripts/docs_tables.py --only reproduction-summary --only reproduction-table

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks scripts examples
	$(BIN)/mypy

bench: $(STAMP)
	$(BIN)/python benchmarks/run_benchmarks.py

# The radio model against ns-3 (BENCHMARKS.md, issue 17 §4). ns-3's Python bindings (the
# pip package ns3 with cppyy, ~500 MB) go into the venv for this target only: not a dependency.
ns3-validation: $(STAMP)
	$(BIN)/pip install --quiet 'ns3==3.44.*'
	MPLBACKEND=Agg $(BIN)/python benchmarks/ns3_validation.py --packets 10000 --out benchmarks/results --figure docs/figures/ns3_validation.png
	MPLBACKEND=Agg $(BIN)/python benchmarks/ns3_contention.py --seconds 10 --seeds 1 2 3 4 5 6 7 8 9 10 --out benchmarks/results --figure docs/figures/ns3_contention.png

clean:
	rm -rf $(VENV) $(ROS_VENV) .pytest_cache .mypy_cache .ruff_cache
