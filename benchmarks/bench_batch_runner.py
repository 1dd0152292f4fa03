"""Throughput of the sweep / Monte Carlo execution layer (flexsat.design.batch_runner, issue 13).

A plain script, never collected as a test: ``python benchmarks/bench_batch_runner.py``.

The chunk: the TAMU Law II slew (10 modes, 15 s at 75 Hz = 1,125 control steps, linear: no
friction, ideal sensors, no random torque), g1 = 3000 oz-in/rad, g2 = 800 oz-in s/rad, cases
over α ∈ [0.02, 0.25] × u_max ∈ [200, 600] oz-in. Measured:

1. the whole ``run_batch`` in-process against its chunks' compute (one chunk's ``run_chunk``
   time × chunks): the per-chunk overhead (dask scheduling, zarr write, mask) as a fraction;
2. ``run_batch`` on an already running local cluster of 1 and of 2 single-threaded worker
   processes (cluster start-up excluded): scaling efficiency T1 / (2 T2);
3. peak resident memory of the client and of each worker, and the extrapolation to
   1,000,000 cases on 2 workers;
4. compute per chunk (``run_chunk``: build + one batched ``simulate`` + metrics) at 100, 1,000
   and 10,000 cases, in-process, numba on one thread: cases/s and µs per case-step (per core),
   wall and CPU time (the CPU time of this process: the machine is shared), best of
   ``--repeat``, side by side for the full path (every history recorded, the metrics computed
   from them: an extractor that does not declare ``reads_metrics_only``) and the metrics-only
   path (``simulate(metrics_only=True)``, what a sweep without histories runs);
5. the same with hub inertia and tip mass dispersed (a stacked plant of one model per case);
6. with ``--full N``: N cases for real on 2 local workers (wall time, cases/s, peak memory of
   the client and of each worker).

Targets (issue 13): ≈ 0.1 µs per case-step per core, ≥ 80 % scaling, ≤ 5 % overhead,
≤ 2 GB peak for 1,000,000 cases (≤ 3 min wall time).
"""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # per-core numbers; workers inherit it

import argparse  # noqa: E402
import resource  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from flexsat.cases import tamu  # noqa: E402
from flexsat.design.batch_runner import (  # noqa: E402
    HubManeuverBuilder,
    maneuver_metrics,
    open_results,
    run_batch,
    run_chunk,
)
from flexsat.units import to_si  # noqa: E402

STEPS = 1125  # 15 s at 75 Hz


def builder() -> HubManeuverBuilder:
    case = tamu(n_modes=10)
    return HubManeuverBuilder(
        case.params,
        10,
        case.sim_config(duration=15.0, friction=False, noise=False),
        case.angle,
        case.reference_inertia,
        u_max=case.max_torque,
        g1=to_si("3000 ozf*in/rad", "N*m/rad"),
        g2=to_si("800 ozf*in*s/rad", "N*m*s/rad"),
    )


class TimedBuilder:
    """The builder, noting when the chunk's work starts (per worker process: one thread)."""

    def __init__(self, builder):
        self.builder, self.parameter_names = builder, builder.parameter_names

    def describe(self):
        return self.builder.describe()

    def __call__(self, parameters, seeds):
        # the process environment: the one place the builder and the extractor (pickled by
        # value, each with its own copy of this module's globals) both see
        os.environ["BENCH_CHUNK_STARTED"] = repr(time.perf_counter())
        return self.builder(parameters, seeds)


def timed_metrics(result):
    """The maneuver metrics and ``chunk_compute_s``: the chunk's build + simulate + metrics
    wall time spread over its cases (their sum over the store is the total compute)."""
    out = maneuver_metrics(result)
    n = result.dataset.sizes["case"]
    out["chunk_compute_s"] = np.full(
        n, (time.perf_counter() - float(os.environ["BENCH_CHUNK_STARTED"])) / n
    )
    return out


timed_metrics.reads_metrics_only = True  # it reads result.metrics only (as maneuver_metrics)


def full_path_metrics(result):
    """:func:`maneuver_metrics` without ``reads_metrics_only``: the chunk records every history
    and computes the metrics from them (the path before the metrics-only one)."""
    return maneuver_metrics(result)


def compute_s(store) -> float:
    return float(open_results(store)["metric_chunk_compute_s"].sum())


def table(n: int) -> dict[str, np.ndarray]:
    """n cases on a near-square (α, u_max) grid."""
    rng = np.random.default_rng(0)
    return {
        "alpha": rng.uniform(0.02, 0.25, n),
        "u_max": rng.uniform(to_si("200 ozf*in", "N*m"), to_si("600 ozf*in", "N*m"), n),
    }


def max_rss_mb() -> float:
    """Peak resident memory of this process, MB (VmHWM: reset by exec, so a spawned worker's
    own peak, not its parent's)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=20_000, help="cases of the whole runs")
    parser.add_argument("--chunk", type=int, default=2_000, help="chunk of the whole runs")
    parser.add_argument("--sizes", default="100,1000,10000", help="chunk sizes of part 4")
    parser.add_argument("--dispersed", type=int, default=200, help="cases of part 5")
    parser.add_argument("--repeat", type=int, default=3, help="best of, in part 4")
    parser.add_argument("--full", type=int, default=0, help="cases of part 6 (0: skipped)")
    parser.add_argument("--skip-runs", action="store_true", help="parts 4 and 5 only")
    args = parser.parse_args()
    b = builder()
    run_chunk(b, maneuver_metrics, table(10), 0, 0)  # numba cache load, base plant built

    n, chunk = args.cases, args.chunk
    p = table(n)
    tb = TimedBuilder(b)
    tmp = Path(tempfile.mkdtemp(prefix="bench_batch_"))
    try:
        if args.skip_runs:
            raise _Skip
        print(f"1. run_batch in-process, {n} cases in chunks of {chunk}")
        t0 = time.perf_counter()
        run_batch(tb, p, tmp / "inproc.zarr", chunk_size=chunk, extract=timed_metrics)
        wall = time.perf_counter() - t0
        compute = compute_s(tmp / "inproc.zarr")
        print(
            f"   wall {wall:.2f} s, compute {compute:.2f} s (sum of the chunks' own times): "
            f"overhead {(wall - compute) / compute:+.1%} (in-process client start-up included)"
        )

        from distributed import Client, LocalCluster

        walls, computes = {}, {}
        worker_rss = {}
        for workers in (1, 2):
            with (
                LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
                ) as cluster,
                Client(cluster) as client,
            ):
                client.run(run_chunk, b, maneuver_metrics, table(10), 0, 0)  # warm workers
                t0 = time.perf_counter()
                run_batch(
                    tb,
                    p,
                    tmp / f"w{workers}.zarr",
                    chunk_size=chunk,
                    scheduler=cluster.scheduler_address,
                    extract=timed_metrics,
                )
                walls[workers] = time.perf_counter() - t0
                computes[workers] = compute_s(tmp / f"w{workers}.zarr")
                worker_rss[workers] = max(client.run(max_rss_mb).values())
        eff = walls[1] / (2 * walls[2])
        over = {w: (walls[w] - computes[w] / w) / (computes[w] / w) for w in walls}
        print(
            f"2. local cluster: 1 worker {walls[1]:.2f} s, 2 workers {walls[2]:.2f} s: "
            f"scaling efficiency {eff:.0%}; overhead (wall against compute / workers) "
            f"{over[1]:+.1%} on 1 worker, {over[2]:+.1%} on 2; compute per case "
            f"{computes[1] / n * 1e3:.3f} ms on 1 worker, {computes[2] / n * 1e3:.3f} ms on 2"
        )
        rate2 = n / walls[2]
        print(
            f"3. peak RSS: client {max_rss_mb():.0f} MB (after the in-process run), worker "
            f"{max(worker_rss.values()):.0f} MB (chunks of {chunk}); load average "
            f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
        )
        print(
            f"   1,000,000 cases on 2 workers: {1e6 / rate2:.0f} s "
            f"({1e6 / rate2 / 60:.1f} min) at {rate2:.0f} cases/s; memory does not grow "
            f"with the case count (≤ 4 chunks in flight)"
        )
    except _Skip:
        pass
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(f"4. compute per chunk, in-process, 1 thread, best of {args.repeat} (wall; CPU)")
    for n in [int(v) for v in args.sizes.split(",") if v]:
        p = table(n)
        best = {}
        for _ in range(args.repeat):
            for name, extract in (("full", full_path_metrics), ("metrics-only", maneuver_metrics)):
                c0, t0 = time.process_time(), time.perf_counter()
                run_chunk(b, extract, p, 0, 0)
                wall, cpu = time.perf_counter() - t0, time.process_time() - c0
                w0, u0 = best.get(name, (np.inf, np.inf))
                best[name] = (min(w0, wall), min(u0, cpu))
        for name, (wall, cpu) in best.items():
            print(
                f"   {n:>6} cases, {name:>12}: {wall:7.2f} s  {n / wall:8.0f} cases/s  "
                f"{wall / (n * STEPS) * 1e6:.3f} µs/case-step wall, "
                f"{cpu / (n * STEPS) * 1e6:.3f} CPU"
            )
        ratio = best["full"][1] / best["metrics-only"][1]
        print(
            f"   {n:>6} cases: metrics-only {ratio:.1f}× faster (CPU); peak RSS so far "
            f"{max_rss_mb():.0f} MB"
        )

    n = args.dispersed
    if not n:
        main_full(args, b)
        return
    p = table(n)
    p["hub_inertia"] = np.linspace(0.9, 1.1, n) * b.params.hub_inertia
    p["tip_mass"] = np.linspace(0.9, 1.1, n) * b.params.tip_mass
    t0 = time.perf_counter()
    run_chunk(b, maneuver_metrics, p, 0, 0)
    dt = time.perf_counter() - t0
    print(
        f"5. dispersed plant (hub inertia and tip mass per case), {n} cases: {dt:.2f} s, "
        f"{dt / n * 1e3:.2f} ms/case, {dt / (n * STEPS) * 1e6:.2f} µs/case-step (one "
        f"HubAppendage built per case)"
    )
    main_full(args, b)


def main_full(args, b) -> None:
    """Part 6 (``--full``)."""
    if args.full:
        from distributed import Client, LocalCluster

        n = args.full
        tmp = Path(tempfile.mkdtemp(prefix="bench_batch_full_"))
        try:
            with (
                LocalCluster(
                    n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
                ) as cluster,
                Client(cluster) as client,
            ):
                client.run(run_chunk, b, maneuver_metrics, table(10), 0, 0)  # warm workers
                t0 = time.perf_counter()
                run_batch(
                    b,
                    table(n),
                    tmp / "full.zarr",
                    chunk_size=args.chunk,
                    scheduler=cluster.scheduler_address,
                )
                wall = time.perf_counter() - t0
                rss = client.run(max_rss_mb)
            done = int(open_results(tmp / "full.zarr")["done"].values.sum())
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        print(
            f"6. {n} cases on 2 workers (chunks of {args.chunk}): {wall:.1f} s "
            f"({wall / 60:.2f} min), {n / wall:.0f} cases/s, {done} done; peak RSS client "
            f"{max_rss_mb():.0f} MB, workers {', '.join(f'{v:.0f}' for v in rss.values())} MB; "
            f"load average {os.getloadavg()[0]:.1f}"
        )


class _Skip(Exception):
    """Skip parts 1-3 (``--skip-runs``)."""


if __name__ == "__main__":
    main()
