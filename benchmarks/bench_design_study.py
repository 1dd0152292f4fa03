"""The flagship design study end to end (issue 22): ``examples/eps_design_study.yaml``.

A plain script, never collected as a test: ``python benchmarks/bench_design_study.py``.

The whole file as ``flexsat run`` runs it, from an empty stage cache: the EPS finite-element
modal solve (30 modes), the 12 kept modes, the H2 force placement, the optimal slew and its
frequency-shaped scheduled perturbation feedback (11 Riccati designs), the nominal run, then
the 10,000 dispersed cases (12.5 s at 50 Hz, 625 control steps each, sensor noise and a random
torque) in chunks of 250 on a local dask cluster of ``--workers`` processes, their zarr store
and the statistics. Then the same file again with only the dispersions' seed changed (every
other stage read from the cache: the Monte Carlo alone).

Measured: wall time, the CPU time of this process and of the worker processes (``os.times``:
the children's times once the cluster has stopped), each stage's own time (the report's
records) and the machine's load average before and after (the machine may be shared: the
CPU time is the number that does not depend on the other jobs). ``--chunk-profile`` also times
one chunk in this process, split into its parts: the cases' truths (``setup``), the compiled
batch (``simulate``) and the metrics.

Target (issue 22): the study end to end on 2 cores in at most 2 min, aiming at 1 min.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import yaml  # noqa: E402

HERE = Path(__file__).resolve()
EXAMPLE = HERE.parents[1] / "examples" / "eps_design_study.yaml"


def _document(cache: Path, cases: int, chunk: int, workers: int | None, seed: int) -> str:
    data = yaml.safe_load(EXAMPLE.read_text(encoding="utf-8"))
    data["cache"] = str(cache)
    d = data["dispersions"]
    d["cases"], d["seed"] = cases, seed
    d["execution"] = {"chunk_size": chunk, **({"workers": workers} if workers else {})}
    return yaml.safe_dump(data, sort_keys=False)


def _timed_run(text: str) -> dict:
    from flexsat.scenarios import load_scenario, run_scenario

    load0 = os.getloadavg()[0]
    t0, c0, k0 = time.perf_counter(), time.process_time(), os.times()
    result = run_scenario(load_scenario(text))
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    k1 = os.times()
    children = (k1.children_user - k0.children_user) + (k1.children_system - k0.children_system)
    d = result.dispersions
    return {
        "wall_s": wall,
        "cpu_this_process_s": cpu,
        "cpu_workers_s": children,
        "load_before": load0,
        "load_after": os.getloadavg()[0],
        "stages": {r.stage.label: [r.cached, round(r.seconds, 2)] for r in result.records},
        "chunks_run": d.chunks_run,
        "probabilities": {
            r["requirement"]: [r["probability"], r["low"], r["high"]]
            for r in d.summary["requirements"]
        },
    }


def _chunk_profile(cache: Path, cases: int) -> dict:
    """One chunk of ``cases`` in this process, by parts (the stages read from ``cache``)."""
    import numpy as np

    from flexsat.scenarios import load_scenario, run_scenario
    from flexsat.scenarios.batch_cases import document_seeds
    from flexsat.scenarios.design_dispersions import case_builder, sample_table
    from flexsat.scenarios.design_flight import fly_cases
    from flexsat.scenarios.design_study import stage_plan

    scenario = load_scenario(_document(cache, cases, cases, None, 11))
    data = yaml.safe_load(scenario.yaml_text)
    data.pop("dispersions")
    nominal = run_scenario(load_scenario(yaml.safe_dump(data)))
    build = case_builder(
        scenario, stage_plan(scenario)["dispersions"], nominal.placement, nominal.laws
    )
    table = sample_table(scenario.dispersions, {p.path: p.unit for p in build.cases.parameters})
    values = [{p: float(table.values[p][k]) for p in build.parameter_names} for k in range(cases)]
    seeds = document_seeds(11, np.arange(cases))
    build.fly(values[:8], seeds[:8], 0)  # compiled, the nominal spacecraft built
    out: dict[str, float] = {}
    t0, c0 = time.perf_counter(), time.process_time()
    setups = [build.setup(v, int(s), k) for k, (v, s) in enumerate(zip(values, seeds))]
    out["setup_cpu_ms_per_case"] = 1e3 * (time.process_time() - c0) / cases
    controllers = build.controllers(setups[0].plant, setups[0].config.dt)
    c1 = time.process_time()
    fly_cases(build, setups, seeds, controllers)
    out["fly_cpu_ms_per_case"] = 1e3 * (time.process_time() - c1) / cases
    out["chunk_wall_s"] = time.perf_counter() - t0
    out["chunk_cpu_ms_per_case"] = 1e3 * (time.process_time() - c0) / cases
    c2 = time.process_time()
    build.check(table.values)
    out["check_cpu_ms_per_case"] = 1e3 * (time.process_time() - c2) / cases
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--chunk", type=int, default=250)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--chunk-profile", type=int, default=250, help="cases; 0: skip")
    parser.add_argument("--out", type=Path, default=None, help="JSON of the numbers")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-design-study-") as folder:
        cache = Path(folder) / "cache"
        report: dict = {"cases": args.cases, "chunk": args.chunk, "workers": args.workers}
        text = _document(cache, args.cases, args.chunk, args.workers, 3)
        report["cold"] = _timed_run(text)  # every stage computed
        print(json.dumps(report["cold"], indent=1), flush=True)
        text = _document(cache, args.cases, args.chunk, args.workers, 4)
        report["dispersions_only"] = _timed_run(text)  # the other stages from the cache
        print(json.dumps(report["dispersions_only"], indent=1), flush=True)
        if args.chunk_profile:
            report["chunk"] = _chunk_profile(cache, args.chunk_profile)
            print(json.dumps(report["chunk"], indent=1), flush=True)
    if args.out is not None:
        args.out.write_text(json.dumps(report, indent=1), encoding="utf-8")


if __name__ == "__main__":
    main()
