# rotorcheck: every target creates and uses its own virtual environment in .venv
# (one BLAS thread per process: the engine solves many small systems, where BLAS threads only contend,
# above all beside pytest's two workers on two cores)
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: venv demo test lint samples golden bench clean fleet-demo

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	MPLBACKEND=Agg OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/python -m tools.demo

# PYTHONDONTWRITEBYTECODE emptied (unset, for Python): the suite starts ~25 Python processes that import rotorcheck
# (tests/test_sigkill.py alone 15, the Dask workers, the claims tests) and two xdist workers; without bytecode
# caches each compiles the package again (0.5-0.7 s), as bench/detect_speed.py notes. __pycache__ is ignored by git
test: $(STAMP)
	$(BIN)/ruff check rotorcheck tests bench tools
	$(BIN)/python -m mypy rotorcheck
	PYTHONDONTWRITEBYTECODE= MPLBACKEND=Agg OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(BIN)/python -m pytest -q -n 2 --dist loadgroup

lint: $(STAMP)
	$(BIN)/ruff check rotorcheck tests bench tools
	$(BIN)/python -m mypy rotorcheck

samples: $(STAMP)
	$(BIN)/python -m tools.samples data_samples

golden: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m tools.golden --write

bench: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m bench

# issue 12: build the wheel, install it into a fresh venv in a temporary folder (dependencies from .venv through
# a .pth file: no network) and run the sample commands there, outside the checkout (tests/test_install.py too)
.PHONY: wheel-check
wheel-check: $(STAMP)
	@set -e; tmp=$$(mktemp -d); trap 'rm -rf "$$tmp"' EXIT; mkdir "$$tmp/src" "$$tmp/run"; \
	for f in pyproject.toml README.md MANIFEST.in setup.py setup.cfg rotorcheck configs data_samples; do \
	  if [ -e "$$f" ]; then cp -a "$$f" "$$tmp/src/"; fi; done; \
	find "$$tmp/src" -name __pycache__ -prune -exec rm -rf {} +; \
	export PIP_DISABLE_PIP_VERSION_CHECK=1 MPLBACKEND=Agg; unset PYTHONPATH ROTORCHECK_CONFIGS ROTORCHECK_SAMPLES; \
	$(BIN)/python -m pip wheel --quiet --no-deps --no-build-isolation --no-index -w "$$tmp/dist" "$$tmp/src"; \
	$(BIN)/python -m venv --without-pip "$$tmp/venv"; \
	$(BIN)/python -m pip --python "$$tmp/venv/bin/python" install --quiet --no-deps --no-index "$$tmp"/dist/*.whl; \
	purelib=$$("$$tmp/venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])'); \
	$(BIN)/python -c 'import site; print(*site.getsitepackages(), sep="\n")' > "$$purelib/_rotorcheck_deps.pth"; \
	cd "$$tmp/run"; R="$$tmp/venv/bin/rotorcheck"; \
	"$$tmp/venv/bin/python" -c 'import sys, rotorcheck as r; print("imported", r.__file__); \
	  sys.exit(0 if r.__file__.startswith(sys.prefix) else "not the installed wheel")'; \
	"$$R" --version; S=$$("$$R" --samples-dir); echo "bundled samples: $$S"; \
	"$$R" fit-noise --demo; \
	"$$R" validate "$$S/crack_rig/healthy_1000rpm.h5" --no-plots; \
	rc=0; "$$R" detect "$$S/crack_rig/breathing_crack_1000rpm.h5" --no-plots || rc=$$?; \
	if [ $$rc -ne 1 ]; then echo "wheel-check: detect exited $$rc, expected 1 (damage)"; exit 1; fi; \
	echo "wheel-check: ok"

# issue 15: a simulated fleet (20 machines x 10 sweeps: two growing cracks, one benign bearing drift) in
# $(FLEET_DEMO)/fleet (kept: the previous demo there is replaced), then `rotorcheck fleet` on it (local processes),
# printing the alert list, the trends against the simulator's truth (tools/fleet_trends.py) and where index.html is
FLEET_DEMO ?= rotorcheck-out/fleet-demo
fleet-demo: $(STAMP)
	@set -e; test -n "$(FLEET_DEMO)"; dir="$(FLEET_DEMO)/fleet"; rm -rf "$$dir"; mkdir -p "$$dir"; \
	export MPLBACKEND=Agg OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1; \
	$(BIN)/python -m tools.fleet_sim "$$dir" --machines 20 --sweeps 10 --seed 0; \
	rc=0; $(BIN)/python -m rotorcheck fleet "$$dir" --limit 3000 || rc=$$?; \
	if [ $$rc -gt 1 ]; then echo "fleet-demo: rotorcheck fleet exited $$rc"; exit $$rc; fi; \
	echo "--- alert list ($$dir/results/alerts.txt; exit $$rc: 1 = a machine in alarm)"; \
	cat "$$dir/results/alerts.txt"; echo "---"; \
	$(BIN)/python -m tools.fleet_trends "$$dir"; \
	echo "--- the fleet's report: $$(cd "$$dir/results" && pwd)/index.html (open it in a browser)"

clean:
	rm -rf $(VENV) rotorcheck-out .pytest_cache
