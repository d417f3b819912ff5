# biped-sim: every target sets up its own environment on a fresh machine (Python 3.11 + pip).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
CONFIG ?= configs/round_foot_walker.yaml
# pytest-xdist processes for the fast tier (auto: one per core) and for the slow tier's parallel-safe tests
TEST_WORKERS ?= auto
SLOW_WORKERS ?= 2
# pytest with bytecode writing allowed whatever the environment says (PYTHONDONTWRITEBYTECODE=1, common in
# containers): pytest then caches each test module's assertion rewrite in __pycache__ instead of redoing it in
# every process (some 2.5 CPU s a process: each xdist worker collects every module), and the test's own
# subprocesses load the package's bytecode rather than compiling it
PYTEST := env -u PYTHONDONTWRITEBYTECODE $(BIN)/python -m pytest

.PHONY: setup setup-bench run test test-older-cpu test-slow validate bench lint format sweep-demo golden docs clean

# installed: the package and its test extras; warmed: also the compiled code of the bundled configs' groups
WARMED := $(VENV)/.warmed

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet --no-compile -e ".[test,dask]"
	@# the packages' bytecode, one process per core (pip's own compile is serial: a third of the install's
	@# time); like pip, a file that does not compile is left to compile at its import
	-$(BIN)/python -m compileall -q -j 0 "$$($(BIN)/python -c 'import sysconfig; print(sysconfig.get_path("purelib"))')" > /dev/null
	touch $(STAMP)

$(WARMED): $(STAMP)
	$(BIN)/biped-sim warmup
	touch $(WARMED)

setup: $(WARMED)           ## create .venv, install the package (editable) with test extras, compile the bundled groups

setup-bench: $(WARMED)     ## also install MuJoCo for the benchmark comparison
	$(BIN)/python -m pip install --quiet -e ".[bench]"

run: $(STAMP)              ## simulate the default walker (compiling only its own group); print its step table
	$(BIN)/biped-sim run $(CONFIG)

test: $(WARMED)            ## the fast test tier (pytest's default: -m 'not slow'; about a minute on 2 cores)
	$(PYTEST) -q -n $(TEST_WORKERS)

# numpy's SIMD dispatch limited to AVX2 (numpy >= 2.4's feature names) and OpenBLAS's kernels to Haswell: the
# arithmetic of an older x86 CPU, for the scipy/BLAS/LAPACK paths (tests must pass on any x86 CPU)
OLDER_CPU := NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR" OPENBLAS_CORETYPE=Haswell

test-older-cpu: $(WARMED)  ## the fast tier as on an older (AVX2) CPU
	$(OLDER_CPU) $(PYTEST) -q -n $(TEST_WORKERS)

# the slow tier in SLOW_WORKERS processes, then its serial tests alone: those that time themselves or kill processes
# on deadlines (marked serial); tests/conftest.py's UnitScheduling hands out the same units as in the fast tier
# (a module, a group of modules sharing a session fixture, or a test of its own), LONGEST_FIRST's costliest first
test-slow: $(WARMED)       ## the slow test tier (-m slow; CI's, where tests/test_validation.py runs biped-sim validate)
	$(PYTEST) -q -n $(SLOW_WORKERS) -m 'slow and not serial'
	$(PYTEST) -q -m 'slow and serial'

validate: $(WARMED)        ## long physics checks: the validation report (results/validation), then the slow test tier
	$(BIN)/biped-sim validate
	$(MAKE) --no-print-directory test-slow

bench: $(WARMED)           ## performance benchmark (writes results/bench/)
	$(BIN)/biped-sim bench

sweep-demo: $(STAMP)       ## the bundled slopes x integrators sweep and its report (results/sweeps/slopes_integrators/)
	$(BIN)/biped-sim sweep configs/sweeps/slopes_integrators.yaml
	$(BIN)/biped-sim report results/sweeps/slopes_integrators

golden: $(WARMED)          ## re-record tests/data/golden_summaries.json (after a change that moves numbers on purpose)
	$(BIN)/python -m tests.record_golden

DOCS_STAMP := $(VENV)/.installed-docs

$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[docs]"
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP) $(WARMED)  ## the documentation site into docs/_build/html (tutorials executed; warnings are errors)
	$(BIN)/python -m sphinx -W --keep-going -b html docs docs/_build/html

lint: $(STAMP)
	$(BIN)/ruff check src tests docs
	$(BIN)/ruff format --check src tests docs
	$(BIN)/lint-imports

format: $(STAMP)
	$(BIN)/ruff format src tests docs
	$(BIN)/ruff check --fix src tests docs

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache docs/_build docs/tutorials docs/api/generated
