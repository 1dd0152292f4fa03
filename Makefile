VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test test-numerics docs bench clean

$(PY):
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip

# the example plug-in (tests/plugin_package) is part of the test environment: tests/test_example_plugin.py
# runs its plant, law, case and check through the command line
$(STAMP): $(PY) pyproject.toml tests/plugin_package/pyproject.toml
	$(PY) -m pip install -q -e '.[dev]'
	$(PY) -m pip install -q -e tests/plugin_package
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/flexsat run -o out

# one BLAS thread per pytest worker: two workers on two cores, no oversubscription; worksteal:
# an idle worker takes queued tests from the other, so a long test near the end does not leave
# one core idle
test: $(STAMP)
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 $(PY) -m pytest -n 2 --dist worksteal -q

# the tests whose tolerances sit near round-off, again on another BLAS kernel (OpenBLAS picks
# one per CPU: SkylakeX on AVX-512, Haswell on AVX2); a tolerance below the problem's noise
# floor passes on one kernel and fails on another
NUMERICS_CORETYPE ?= Sandybridge
test-numerics: $(STAMP)
	OPENBLAS_CORETYPE=$(NUMERICS_CORETYPE) OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \
		$(PY) -m pytest -n 2 --dist worksteal -q -m numerics

# static checks, the same for developers and CI (.ci/run): ruff lint and format on the Python
# sources, mypy on src/flexsat (configuration in pyproject.toml, [tool.ruff] and [tool.mypy])
.PHONY: lint
lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks
	$(VENV)/bin/ruff format --check src tests benchmarks
	$(VENV)/bin/mypy

# the documentation site (mkdocs.yml: the guides in docs/ and an API reference from the
# docstrings), built strictly: a broken link or a docstring section it cannot parse fails
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --quiet

bench: $(STAMP)
	$(PY) benchmarks/bench_tamu.py
	$(PY) benchmarks/bench_modal.py
	$(PY) benchmarks/bench_lqr.py
	$(PY) benchmarks/bench_identify.py
	$(PY) benchmarks/bench_cli.py

clean:
	rm -rf $(VENV) out .pytest_cache
