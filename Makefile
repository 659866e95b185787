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

# Main job: train a PPO tuner on FootZupt-v0 (about 3 min on 2 cores), then compare it
# with the paper, tuned-fixed and innovation-adaptive policies on 100 held-out episodes.
DEMO_STEPS ?= 400000
demo: setup
	$(VENV)/bin/pednav train pednav/FootZupt-v0 --algo ppo --timesteps $(DEMO_STEPS) --run-dir runs/demo
	$(VENV)/bin/pednav evaluate pednav/FootZupt-v0 --policy paper tuned adaptive runs/demo \
		--episodes 100 --seed 5000

test: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/python -m pytest -q

lint: setup
	$(VENV)/bin/ruff check . && $(VENV)/bin/ruff format --check .

clean:
	rm -rf $(VENV) build *.egg-info
