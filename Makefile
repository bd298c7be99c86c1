# bt-manip developer commands. Each target creates .venv on first use.
#
# `make demo` installs only what bt-manip needs to run; `make test`, `lint` and `bench` add every
# optional extra of pyproject.toml (test tools, benchmark peers...). Each install leaves a stamp
# in the venv, so `make test` after `make demo` installs just the rest, and a change to
# pyproject.toml installs again.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
RUNTIME_STAMP := $(VENV)/.installed-runtime
EXTRAS_STAMP := $(VENV)/.installed-extras
# every extra of [project.optional-dependencies], comma-separated (dev,bench,...)
EXTRAS := $(shell sed -n '/^\[project\.optional-dependencies\]/,/^\[/s/^\([A-Za-z0-9_-]*\) *= *\[.*/\1/p' pyproject.toml | paste -sd, -)

.PHONY: demo test lint bench dist clean

$(RUNTIME_STAMP): pyproject.toml
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	@echo "installing bt-manip and its dependencies into $(VENV) (log: $(VENV)/install.log)"
	@{ $(BIN)/python -m pip install --upgrade pip && \
	   $(BIN)/python -m pip install -e .; } > $(VENV)/install.log 2>&1 \
	   || { tail -n 30 $(VENV)/install.log; exit 1; }
	@touch $(RUNTIME_STAMP)

$(EXTRAS_STAMP): $(RUNTIME_STAMP)
	@echo "installing the extras $(EXTRAS) into $(VENV) (log: $(VENV)/install-extras.log)"
	@$(BIN)/python -m pip install -e '.[$(EXTRAS)]' > $(VENV)/install-extras.log 2>&1 \
	   || { tail -n 30 $(VENV)/install-extras.log; exit 1; }
	@touch $(EXTRAS_STAMP)

## demo: set up and run the main job (Scenario A, headless): summary, report, replay page
demo: $(RUNTIME_STAMP)
	@mkdir -p out
	$(BIN)/bt-manip run trees/husky_carry_wall.xml --world worlds/tb3_house.yaml --seed 0 \
		--report out/husky_report.json --record out/husky_replay.html
	@echo "run report: out/husky_report.json; replay page (open in a browser): out/husky_replay.html"

## test: run the whole test suite on two processes
test: $(EXTRAS_STAMP)
	$(BIN)/python -m pytest -n 2 -q

## lint: ruff, and mypy over bt_manip/ (settings in pyproject.toml)
lint: $(EXTRAS_STAMP)
	$(BIN)/ruff check .
	$(BIN)/mypy

## dist: the sdist and the wheel in dist/ (the wheel carries trees/, worlds/, robots/)
dist: $(EXTRAS_STAMP)
	rm -rf dist
	$(BIN)/python -m build --outdir dist .

bench: $(EXTRAS_STAMP)
	$(BIN)/python benchmarks/astar.py
	$(BIN)/python benchmarks/ik.py
	$(BIN)/python benchmarks/bt_tick.py

clean:
	rm -rf $(VENV) out build dist *.egg-info
