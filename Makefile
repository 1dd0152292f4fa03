VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean

$(PY):
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip

$(STAMP): $(PY) pyproject.toml
	$(PY) -m pip install -q -e '.[dev]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/flexsat run -o out

# one BLAS thread per pytest worker: two workers on two cores, no oversubscription
test: $(STAMP)
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 $(PY) -m pytest -n 2 -q

bench: $(STAMP)
	$(PY) benchmarks/bench_tamu.py
	$(PY) benchmarks/bench_modal.py
	$(PY) benchmarks/bench_lqr.py
	$(PY) benchmarks/bench_identify.py
	$(PY) benchmarks/bench_cli.py

clean:
	rm -rf $(VENV) out .pytest_cache
