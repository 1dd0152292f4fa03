"""A 40-point Pareto front of the hub-boom co-design on 2 cores (issue 23 benchmark: <= 2 min).

A plain script, never collected as a test: ``python benchmarks/bench_pareto.py``.

The front: :class:`flexsat.design.reference_problems.HubBoomCodesign` (its defaults: a 0.4 kg m²
hub, four 1.2 m aluminium tube booms with 0.2 kg tip masses, 6 FE frames per boom, 3 elastic
modes, f₁ >= 6 Hz), structural mass against the LQ slew cost by ε-constraint
(:func:`flexsat.design.pareto.run_front`), ``--points`` levels × ``--starts`` starts, SLSQP,
each case one ``optimize_design`` with its KKT check. Measured:

1. the whole ``run_front`` on a fresh local cluster of ``--workers`` single-threaded worker
   processes (cluster start-up, the two anchor optimisations and the zarr store included):
   wall time and the client's CPU time;
2. the same cases computed serially in this process (``FrontCases.run_chunk`` on the whole
   table): CPU and wall time, so that compute / (workers × wall) is the parallel efficiency;
3. the front: points kept, the largest KKT residual, mass and LQ-cost range.

The machine is shared: the CPU times are the honest numbers, wall times are best of ``--repeat``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from flexsat.design.pareto import (  # noqa: E402
    FrontCases,
    FrontSetup,
    front_levels,
    front_table,
    run_front,
)
from flexsat.design.reference_problems import HubBoomCodesign  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=40)
    ap.add_argument("--starts", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--chunk-size", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    setup = FrontSetup(HubBoomCodesign(), "lq_cost", "mass")
    n = args.points * args.starts
    print(f"front: {args.points} levels x {args.starts} starts = {n} optimisations")

    walls, cpus = [], []
    front = None
    for _ in range(args.repeat):
        folder = Path(tempfile.mkdtemp(prefix="bench-pareto-"))
        try:
            c0, w0 = time.process_time(), time.perf_counter()
            run_front(
                setup,
                folder / "front.zarr",
                points=args.points,
                starts=args.starts,
                chunk_size=args.chunk_size,
                workers=args.workers,
            )
            walls.append(time.perf_counter() - w0)
            cpus.append(time.process_time() - c0)
            front = front_table(folder / "front.zarr")
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    print(
        f"run_front on {args.workers} workers: wall {min(walls):.1f} s (best of {args.repeat}),"
        f" client CPU {cpus[int(np.argmin(walls))]:.1f} s"
    )

    levels = front_levels(setup, args.points)
    table = {
        "level": np.repeat(levels, args.starts),
        "start": np.tile(np.arange(args.starts, dtype=float), args.points),
    }
    c0, w0 = time.process_time(), time.perf_counter()
    out = FrontCases(setup).run_chunk(None, table, 0, 0)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    print(
        f"serial compute in-process: CPU {cpu:.1f} s, wall {wall:.1f} s "
        f"({1e3 * cpu / n:.0f} ms CPU per optimisation, "
        f"{out['metric_evaluations'].mean():.1f} evaluations on average)"
    )
    print(f"parallel efficiency: {cpu / (args.workers * min(walls)):.0%}")
    assert front is not None
    print(
        f"front: {front['primary'].size} points, max KKT residual "
        f"{front['kkt_residual'].max():.1e}, mass {front['secondary'].min():.4f}-"
        f"{front['secondary'].max():.4f} kg, LQ cost {front['primary'].min():.4f}-"
        f"{front['primary'].max():.4f}"
    )


if __name__ == "__main__":
    main()
