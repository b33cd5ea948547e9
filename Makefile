# Two set-up commands for a fresh machine with Python 3.11 and pip: `make demo`, `make test`.
VENV ?= .venv
PY := $(VENV)/bin/python
export OPENBLAS_NUM_THREADS ?= 1

.PHONY: demo test typecheck docs figures bench bench-sim bench-ss bench-batch bench-exec bench-verdicts check-certificates bench-choose lint clean

$(PY):
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip

# The package's bytecode, as a normal `pip install` leaves it: an editable checkout otherwise
# compiles its sources on every start where PYTHONDONTWRITEBYTECODE is set (~0.1 s a command).
BYTECODE = $(PY) -m compileall -q dmp tools planner problems && $(PY) -m compileall -q -l .

demo: $(PY)
	$(PY) -m pip install -q -e ".[all]"
	$(BYTECODE)
	$(VENV)/bin/tooltransfer paper --out out

# pytest, told to require the browser tests where chromium and its driver are installed
PYTEST = TT_REQUIRE_BROWSER=$$([ -x $(CHROMIUM) ] && [ -x $(CHROMEDRIVER) ] && echo 1) $(PY) -m pytest

# The suite on two processes, each test file on one of them (its module fixtures built once), then the
# tests marked `serial` (wall-time bounds, real signals racing the work) alone, as on an idle machine.
test: $(PY)
	$(PY) -m pip install -q -e ".[test]"
	$(BYTECODE)
	$(PY) -m ruff check .
	$(MAKE) --no-print-directory typecheck
	$(MAKE) --no-print-directory browser
	$(PYTEST) -n 2 --dist loadfile -m "not serial"
	$(PYTEST) -m serial

# Debian's chromium and chromedriver for the browser tests of the HTML pages (tests/browser.py):
# installed where this runs as root with apt-get and they are missing (about a minute, once per
# machine); elsewhere those tests skip naming what is missing. Where they are there, `make test`
# sets TT_REQUIRE_BROWSER=1: a browser test that cannot start its browser fails instead of skipping.
CHROMIUM ?= /usr/bin/chromium
CHROMEDRIVER ?= /usr/bin/chromedriver
.PHONY: browser
browser:
	@if [ ! -x $(CHROMIUM) ] || [ ! -x $(CHROMEDRIVER) ]; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing Debian's chromium and chromium-driver for the browser tests"; \
	    (apt-get -o DPkg::Lock::Timeout=300 update -qq && DEBIAN_FRONTEND=noninteractive apt-get \
	      -o DPkg::Lock::Timeout=300 install -y -qq chromium chromium-driver >/dev/null) \
	      || echo "make: chromium could not be installed: the browser tests will skip"; \
	  else echo "make: no $(CHROMIUM) (not root, or no apt-get): the browser tests will skip"; fi; fi

# mypy on the DMP core and the public entry points ([tool.mypy] in pyproject.toml says why the link)
TYPED := -p tooltransfer.dmp -m tooltransfer -m tooltransfer.errors -m tooltransfer.validation \
	-m tooltransfer.problems.task -m tooltransfer.problems.named -m tooltransfer.planner.planning.solve \
	-m tooltransfer.planner.planning.plan -m tooltransfer.planner.execution.closed_loop -m tooltransfer.planner.execution.plant \
	-m tooltransfer.planner.execution.fault_plants -m tooltransfer.planner.execution.guarded_plant \
	-m tooltransfer.planner.execution.export -m tooltransfer.planner.execution.scene -m tooltransfer.planner.planning.ss.nlp -m tooltransfer.planner.planning.ss.knot_rows \
	-m tooltransfer.planner.planning.setting -m tooltransfer.planner.planning.variant_registry \
	-p tooltransfer.planner.planning.verdicts -p tooltransfer.tools.derive -p tooltransfer.planner.apps.choose -m tooltransfer.planner.execution.recording \
	-m tooltransfer.planner.apps.batch.frame -m tooltransfer.planner.apps.batch.units -m tooltransfer.planner.apps.plots.plan_view \
	-m tooltransfer.planner.apps.plots.html_page -m tooltransfer.planner.apps.batch.html_report
typecheck: $(PY)
	@mkdir -p build/mypy && ln -sfn "$(CURDIR)" build/mypy/tooltransfer
	cd build/mypy && MYPYPATH=. $(abspath $(PY)) -m mypy --config-file "$(CURDIR)/pyproject.toml" $(TYPED)

# The suite on the floors of pyproject.toml: uv's lowest-direct resolution (every direct dependency
# at the lowest version its specifier admits, the others at their newest) in a separate venv,
# $(LOWEST); pip goes in too for the wheel-building tests. About as long as `make test`.
LOWEST ?= .venv-lowest
.PHONY: test-lowest
test-lowest: $(PY)
	$(PY) -m pip install -q "uv>=0.8"
	$(PY) -m uv venv -q --clear --no-python-downloads --python python3 $(LOWEST)
	$(PY) -m uv pip install -q --python $(LOWEST)/bin/python --resolution lowest-direct -e ".[test]"
	$(PY) -m uv pip install -q --python $(LOWEST)/bin/python pip
	$(LOWEST)/bin/python -m pytest

# API documentation and the design document (mkdocs + mkdocstrings), offline, warnings are errors;
# `make test` builds it too (tests/test_docs.py). Open out/docs/index.html.
docs: $(PY)
	$(PY) -m pip install -q -e ".[all,docs]"
	$(PY) -m mkdocs build --strict --site-dir out/docs

# The README's two figures, committed in docs/images: the paper's transfer task solved with every
# variant pair, and its qp/opt plan executed open and closed loop on the simulated Omni (Fig. 12).
# Deterministic (the same bytes on the same versions of the dependencies); about 10 s.
figures: $(PY)
	$(PY) -m pip install -q -e ".[all]"
	$(PY) -m tooltransfer.planner.apps.plots.paper_figures docs/images

# A release from files into dist/: the sdist, the wheel built from it, both checked by twine
# (tests/test_packaging_wheel.py does the same on a copy and installs the wheel into a fresh venv).
.PHONY: release
release: $(PY)
	$(PY) -m pip install -q -e ".[test]"
	rm -rf dist
	$(PY) -m build --no-isolation -o dist .
	$(PY) -m twine check --strict dist/*

# The Dockerfile built without a Docker engine, then a batch on its workers (docs/cluster.md; root,
# network and debootstrap; tests/image/dockerfile_without_engine.py)
.PHONY: image-check
image-check: $(PY)
	$(PY) -m pip install -q -e ".[all]"
	$(PY) tests/image/dockerfile_without_engine.py

bench: $(PY)
	$(PY) -m pip install -q -e ".[bench]"
	$(PY) benchmarks/bench_dmp.py
	$(PY) benchmarks/bench_sim.py
	$(PY) benchmarks/bench_oe.py
	$(PY) benchmarks/bench_solve.py

bench-sim: $(PY)
	$(PY) -m pip install -q -e ".[all]"
	$(PY) benchmarks/bench_sim.py

bench-ss: $(PY)
	$(PY) -m pip install -q -e ".[all]"
	$(PY) benchmarks/bench_ss.py

# 1,000 generated tasks x 4 variants on 2 cores, process pool and Dask LocalCluster (several minutes)
bench-batch: $(PY)
	$(PY) -m pip install -q -e ".[all]"
	$(PY) benchmarks/bench_batch.py

# 60 generated tasks + 2 paper tasks planned and executed open and closed loop on 2 cores (about 25 s)
bench-exec: $(PY)
	$(PY) -m pip install -q -e ".[all]"
	$(PY) benchmarks/bench_execution.py

# 60 + 200 generated tasks planned on 2 cores: solved / certified infeasible / unknown, the planning times, and the
# solved plans executed open and closed loop on the simulated Omni
bench-verdicts: $(PY)
	$(PY) -m pip install -q -e ".[all]"
	$(PY) benchmarks/bench_verdicts.py --execute --json out/verdicts.json

# every certificate of the last `make bench-verdicts` against the test suite's own lattice search
check-certificates: $(PY)
	$(PY) benchmarks/check_certificates.py out/verdicts.json

# 100 generated tasks, each given to `tooltransfer choose` over the library's tools (long: see benchmarks/README.md)
bench-choose: $(PY)
	$(PY) -m pip install -q -e ".[all]"
	$(PY) benchmarks/bench_choose.py

lint: $(PY)
	$(PY) -m ruff check .

clean:
	rm -rf $(VENV) out build *.egg-info .pytest_cache .ruff_cache
