# bt-manip developer commands. Each target creates .venv on first use.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	@echo "installing bt-manip and its dependencies into $(VENV) (log: $(VENV)/install.log)"
	@{ $(BIN)/python -m pip install --upgrade pip && \
	   $(BIN)/python -m pip install -e '.[dev,bench]'; } > $(VENV)/install.log 2>&1 \
	   || { tail -n 30 $(VENV)/install.log; exit 1; }
	@touch $(STAMP)

## demo: set up and run the main job (Scenario A, headless): summary, report, replay page
demo: $(STAMP)
	@mkdir -p out
	$(BIN)/bt-manip run trees/husky_carry_wall.xml --world worlds/tb3_house.yaml --seed 0 \
		--report out/husky_report.json --record out/husky_replay.html
	@echo "run report: out/husky_report.json; replay page (open in a browser): out/husky_replay.html"

## test: run the whole test suite on two processes
test: $(STAMP)
	$(BIN)/python -m pytest -n 2 -q

lint: $(STAMP)
	$(BIN)/ruff check .

bench: $(STAMP)
	$(BIN)/python benchmarks/astar.py
	$(BIN)/python benchmarks/ik.py
	$(BIN)/python benchmarks/bt_tick.py

clean:
	rm -rf $(VENV) out build *.egg-info
