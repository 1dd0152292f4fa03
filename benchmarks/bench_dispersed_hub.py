"""A dispersed hub + appendage plant in a batch, end to end (issue 22).

A plain script, never collected as a test: ``python benchmarks/bench_dispersed_hub.py``.

The chunk of a Monte Carlo over the plant: the TAMU Law II slew (10 modes, 15 s at 75 Hz =
1,125 control steps, linear: no friction, ideal sensors) with the hub inertia, the appendages'
bending stiffness EI and the tip mass drawn per case (uniform ±10 %), run as a sweep runs it:
``run_chunk(HubManeuverBuilder, maneuver_metrics, table)`` — the builder's plant for the
chunk (one model per case), then one batched ``simulate(metrics_only=True)``, then the
metrics. Every repeat draws a new table, so no case's frequency equation is a cache hit.

Measured per case, at 100 and 1,000 cases: the whole chunk (wall and process CPU time), and
its two parts, the plant build (``builder(table, seeds)``) and the simulation
(``simulate(...)``), best of ``--repeat`` in each process. Two source trees side by side:
the baseline (``--baseline``, default ``/tmp/hubfast-main``, main's sources before issue 22:
``git archive 54f384e src | tar -x -C /tmp/hubfast-main``) and this one, each run in its own
interpreter (``PYTHONPATH``), alternating, ``--runs`` processes each; the table gives the
minimum and the median over the processes and the ratio baseline / this tree.

Target (issue 22): ≤ 1 ms per case end to end (the issue measured 15 ms).
"""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # per-core numbers
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve()
TREE = HERE.parents[1]
STEPS = 1125  # 15 s at 75 Hz


def _builder():
    from flexsat.cases import tamu
    from flexsat.design.batch_runner import HubManeuverBuilder
    from flexsat.units import to_si

    case = tamu(n_modes=10)
    return case.params, HubManeuverBuilder(
        case.params,
        10,
        case.sim_config(duration=15.0, friction=False, noise=False),
        case.angle,
        case.reference_inertia,
        u_max=case.max_torque,
        g1=to_si("3000 ozf*in/rad", "N*m/rad"),
        g2=to_si("800 ozf*in*s/rad", "N*m*s/rad"),
    )


def _table(params, n: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        "hub_inertia": params.hub_inertia * rng.uniform(0.9, 1.1, n),
        "EI": params.EI * rng.uniform(0.9, 1.1, n),
        "tip_mass": params.tip_mass * rng.uniform(0.9, 1.1, n),
    }


def child(sizes: list[int], repeat: int, seed: int) -> dict:
    """Timings of this interpreter's flexsat (one process of the comparison)."""
    import flexsat
    from flexsat.design.batch_runner import maneuver_metrics, run_chunk
    from flexsat.sim import simulate

    params, b = _builder()
    run_chunk(b, maneuver_metrics, _table(params, 3, seed), 0, 0)  # numba cache, base plant
    out: dict = {"tree": str(Path(flexsat.__file__).parents[2])}
    for n in sizes:
        best = {k: np.inf for k in ("chunk_wall", "chunk_cpu", "build", "simulate")}
        for r in range(repeat):
            table = _table(params, n, seed + 1000 * (r + 1) + n)
            w0, c0 = time.perf_counter(), time.process_time()
            run_chunk(b, maneuver_metrics, table, 0, 0)
            best["chunk_wall"] = min(best["chunk_wall"], time.perf_counter() - w0)
            best["chunk_cpu"] = min(best["chunk_cpu"], time.process_time() - c0)
            table = _table(params, n, seed + 1000 * (r + 1) + n + 1)
            seeds = np.arange(n)
            t0 = time.perf_counter()
            plant, law, config, x0 = b(table, seeds)
            t1 = time.perf_counter()
            simulate(plant, law, config, n_cases=n, seeds=seeds, metrics_only=True)
            t2 = time.perf_counter()
            best["build"] = min(best["build"], t1 - t0)
            best["simulate"] = min(best["simulate"], t2 - t1)
        out[str(n)] = {k: v / n * 1e3 for k, v in best.items()}  # ms per case
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="100,1000", help="cases per chunk")
    parser.add_argument("--repeat", type=int, default=3, help="best of, in each process")
    parser.add_argument("--runs", type=int, default=3, help="processes per tree, alternating")
    parser.add_argument("--baseline", default="/tmp/hubfast-main", help="baseline source tree")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--seed", type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args()
    sizes = [int(v) for v in args.sizes.split(",") if v]
    if args.child:
        print(json.dumps(child(sizes, args.repeat, args.seed)))
        return
    trees = {"baseline": Path(args.baseline), "this tree": TREE}
    results: dict[str, list[dict]] = {name: [] for name in trees}
    for run in range(args.runs):
        for name, tree in trees.items():
            env = {**os.environ, "PYTHONPATH": str(tree / "src")}
            cmd = [sys.executable, str(HERE), "--child", "--sizes", args.sizes]
            cmd += ["--repeat", str(args.repeat), "--seed", str(run)]
            done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
            results[name].append(json.loads(done.stdout.strip().splitlines()[-1]))
            print(
                f"run {run + 1}/{args.runs} {name} ({results[name][-1]['tree']}) done", flush=True
            )
    print(f"\nms per case, min / median over {args.runs} processes (each a best of {args.repeat});")
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs\n")
    print("| chunk | part | baseline | this tree | ratio baseline / this (min) |")
    print("|---|---|---|---|---|")
    parts = {
        "chunk_wall": "end to end, wall",
        "chunk_cpu": "end to end, CPU",
        "build": "plant build",
        "simulate": "simulate (metrics only)",
    }
    for n in sizes:
        for key, label in parts.items():
            cells = []
            for name in trees:
                v = np.array([r[str(n)][key] for r in results[name]])
                cells.append((v.min(), np.median(v)))
            ratio = cells[0][0] / cells[1][0]
            print(
                f"| {n} | {label} | {cells[0][0]:.3f} / {cells[0][1]:.3f} | "
                f"{cells[1][0]:.3f} / {cells[1][1]:.3f} | {ratio:.1f}× |"
            )
    n = sizes[-1]
    best = min(r[str(n)]["chunk_wall"] for r in results["this tree"])
    print(f"\n{n} cases: {best * 1e3 / STEPS:.3f} µs per case-step end to end (this tree)")


if __name__ == "__main__":
    main()
