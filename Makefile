# Two entry points for a fresh machine: `make demo` (main job) and `make test`.
# Both create .venv and install the CPU build of torch before anything else
# pulls a (multi-GB) CUDA build.
VENV ?= .venv
PY := $(VENV)/bin/python
TORCH_CPU := torch==2.13.0

.PHONY: setup demo test lint bench clean

setup: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -c "import torch" 2>/dev/null || $(PY) -m pip install --quiet $(TORCH_CPU)
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $@

# Main job: distil the privileged oracle of MarkerTrack-v0 (the constant tuned per UWB
# condition) into a sensor-only tuner by DAgger (agents/distill.py), then compare it with
# the paper filter, the CMA-ES constant and the oracle on 200 development episodes.
# --overwrite: the demo re-creates its run, so a second `make demo` replaces the first.
DEMO_ENV ?= pednav/MarkerTrack-v0
demo: setup
	$(VENV)/bin/pednav distill $(DEMO_ENV) --run-dir runs/demo --overwrite
	$(VENV)/bin/pednav evaluate $(DEMO_ENV) --policy paper tuned oracle runs/demo \
		--episodes 200 --seed 5000

test: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/python -m pytest -q

lint: setup
	$(VENV)/bin/ruff check . && $(VENV)/bin/ruff format --check .

clean:
	rm -rf $(VENV) build *.egg-info
