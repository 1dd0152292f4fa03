"""A 40-point Pareto front of a co-design on 2 cores (issue 23 benchmark: <= 2 min).

A plain script, never collected as a test: ``python benchmarks/bench_pareto.py
[--problem hub_boom|tamu]``.

The fronts:

* ``hub_boom``: :class:`flexsat.design.reference_problems.HubBoomCodesign` (its defaults: a
  0.4 kg m² hub, four 1.2 m aluminium tube booms with 0.2 kg tip masses, 6 FE frames per boom,
  3 elastic modes, f₁ >= 6 Hz), structural mass against the LQ slew cost;
* ``tamu``: the TAMU co-design of examples/tamu_codesign_mass_front.yaml
  (:class:`flexsat.cases.tamu_codesign.TamuCodesign` with the published tip mass: appendage
  thickness, Law II's gains and α), the mass of one appendage against the smoothed settling
  time of the published 40° slew (each problem evaluation one batched 15 s simulation of the
  2n + 1 = 9 designs of a central-difference gradient);

by ε-constraint (:func:`flexsat.design.pareto.run_front`), ``--points`` levels × ``--starts``
starts, SLSQP, each case one ``optimize_design`` with its KKT check. Measured:

1. the whole ``run_front`` on a fresh local cluster of ``--workers`` single-threaded worker
   processes (cluster start-up, the two anchor optimisations and the zarr store included):
   wall time, the client's CPU time and the worker processes' CPU time (``getrusage`` of the
   children, reaped when the cluster closes);
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
import resource  # noqa: E402
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

TAMU_FRONT = Path(__file__).parents[1] / "examples" / "tamu_codesign_mass_front.yaml"


def tamu_setup() -> FrontSetup:
    """The front of examples/tamu_codesign_mass_front.yaml, as its ``design`` scenario runs it."""
    from flexsat.scenarios.design_problem import ConfiguredProblem
    from flexsat.scenarios.documents import load_scenario

    scenario = load_scenario(TAMU_FRONT)
    assert scenario.pareto is not None
    return FrontSetup(
        ConfiguredProblem.from_scenario(scenario),
        scenario.objective,
        scenario.pareto.secondary,
        tol=scenario.optimizer.tol,
        max_iterations=scenario.optimizer.max_iterations,
    )


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--problem", choices=("hub_boom", "tamu"), default="hub_boom")
    ap.add_argument("--points", type=int, default=40)
    ap.add_argument("--starts", type=int, default=None, help="default: 3 hub_boom, 1 tamu")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--chunk-size", type=int, default=None, help="default: 10 hub_boom, 5 tamu")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--serial", action=argparse.BooleanOptionalAction, default=None)
    args = ap.parse_args()
    tamu = args.problem == "tamu"
    args.starts = args.starts or (1 if tamu else 3)
    args.chunk_size = args.chunk_size or (5 if tamu else 10)
    serial = (not tamu) if args.serial is None else args.serial
    setup = tamu_setup() if tamu else FrontSetup(HubBoomCodesign(), "lq_cost", "mass")
    print(f"load average at start: {os.getloadavg()}")
    n = args.points * args.starts
    print(f"front: {args.points} levels x {args.starts} starts = {n} optimisations")

    walls, cpus, workers_cpu = [], [], []
    front = None
    for _ in range(args.repeat):
        folder = Path(tempfile.mkdtemp(prefix="bench-pareto-"))
        try:
            k0 = children_cpu()
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
            workers_cpu.append(children_cpu() - k0)
            front = front_table(folder / "front.zarr")
            every_case(folder / "front.zarr")
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    best = int(np.argmin(walls))
    print(
        f"run_front on {args.workers} workers: wall {min(walls):.1f} s (best of {args.repeat}),"
        f" client CPU {cpus[best]:.1f} s, worker processes' CPU {workers_cpu[best]:.1f} s"
    )
    print(f"load average at the end: {os.getloadavg()}")
    assert front is not None
    report(front, tamu)
    if not serial:
        return

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


def every_case(store: Path) -> None:
    """Each case's KKT residual, optimiser verdict and ε-activity (front_table keeps the
    successful ones within 1e-6, then the nondominated)."""
    from flexsat.design.batch_runner import open_results

    ds = open_results(store).load()
    kkt, ok = ds["metric_kkt_residual"].values, ds["metric_success"].values > 0
    active = ds["metric_epsilon_active"].values > 0
    within = int((kkt <= 1e-6).sum())
    print(
        f"cases: {kkt.size}, optimiser success {int(ok.sum())}, KKT <= 1e-6 {within}"
        f", both {int((ok & (kkt <= 1e-6)).sum())}, epsilon active {int(active.sum())}; "
        f"KKT residuals: {' '.join(f'{v:.0e}' for v in kkt)}"
    )


def report(front: dict[str, np.ndarray], tamu: bool) -> None:
    """The front's points: each with its KKT residual (and, for the TAMU front, its design)."""
    if tamu:
        print("appendage mass (kg) | soft settling (s) | KKT residual | s | lambda_eps (s/kg)")
        for k in range(front["primary"].size):
            print(
                f"{front['secondary'][k]:.4f} | {front['primary'][k]:.4f} | "
                f"{front['kkt_residual'][k]:.1e} | {front['x_thickness_ratio'][k]:.4f} | "
                f"{front['epsilon_multiplier'][k]:.3f}"
            )
        print(
            f"front: {front['primary'].size} points, max KKT residual "
            f"{front['kkt_residual'].max():.1e}, appendage mass {front['secondary'].min():.4f}-"
            f"{front['secondary'].max():.4f} kg, soft settling {front['primary'].min():.4f}-"
            f"{front['primary'].max():.4f} s"
        )
        return
    print(
        f"front: {front['primary'].size} points, max KKT residual "
        f"{front['kkt_residual'].max():.1e}, mass {front['secondary'].min():.4f}-"
        f"{front['secondary'].max():.4f} kg, LQ cost {front['primary'].min():.4f}-"
        f"{front['primary'].max():.4f}"
    )


if __name__ == "__main__":
    main()
