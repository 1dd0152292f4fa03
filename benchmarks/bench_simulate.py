"""End-to-end benchmarks of issue #10 through the public ``flexsat.sim.simulate``: what a user
gets, set-up (propagators, the law's linear form), loop, recording, dataset and metrics
included. Side by side in one run, each the best of N calls:

(a) single TAMU maneuver (10 modes per appendage, linear, 15 s at 75 Hz, Law I with root-torque
    feedback g3): simulate() on the compiled loop and on the Python loop (``compiled=False``)
    against python-control's ``forced_response`` on the same discrete closed loop
    (bench_core.python_control_loop); then with the TAMU friction and noise;
(b) batch of 1,000 such maneuvers (g1 dispersed ±20 %, friction and noise): µs per case-step
    on both loops and peak traced memory per case;
(c) 100 modes per appendage, single maneuver, against ``forced_response``;
(d) the EPS-sized flexible three-axis model (``flexsat.cases.eps().plant(n_modes=45)``, MRP PD,
    10 s at 100 Hz, nonlinear: the Python loop with exp_rk4): a single run, and its cost per
    case-step in a batch.

Run with ``python benchmarks/bench_simulate.py [--repeat N] [--eps-cases N]``; a plain script,
never collected as a test. The numbers go to docs/performance.md by hand.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import tracemalloc
from pathlib import Path

# one BLAS thread, as in bench_core (small matrices; OpenBLAS threads spin on a shared machine)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_core import G1, G2, G3, python_control_loop, tamu_problem  # noqa: E402
from bench_tamu import best_of  # noqa: E402
from flexsat.cases import eps  # noqa: E402
from flexsat.cases.tamu import tamu  # noqa: E402
from flexsat.control import MRPLaw  # noqa: E402
from flexsat.dynamics.attitude import dcm_to_quaternion, euler123_to_dcm  # noqa: E402
from flexsat.sim import ChannelActuator, SimConfig, simulate  # noqa: E402

US = 1e6


def tamu_run(n_modes=10, friction=False, noise=False, g1=G1):
    case = tamu(n_modes=n_modes)
    return (
        case.model(),
        case.law_i(g1, G2, G3),
        case.sim_config(15.0, friction=friction, noise=noise),
    )


def per_step(plant, law, cfg, repeat, compiled=None, n_cases=None):
    simulate(plant, law, cfg, compiled=compiled, n_cases=n_cases)  # compile / warm up
    t, _, r = best_of(lambda: simulate(plant, law, cfg, compiled=compiled, n_cases=n_cases), repeat)
    return t / cfg.n_steps, r


def bench_single(repeat):
    plant, law, cfg = tamu_run()
    comp, rc = per_step(plant, law, cfg, repeat)
    py, rp = per_step(plant, law, cfg, max(3, repeat // 5), compiled=False)
    _, info = tamu_problem(10)
    t_pc, _, _ = best_of(python_control_loop(info), max(3, repeat // 5))
    pc = t_pc / cfg.n_steps
    diff = float(np.abs(rc.dataset.theta.values - rp.dataset.theta.values).max())
    plant, law, cfg = tamu_run(friction=True, noise=True)
    comp_f, _ = per_step(plant, law, cfg, repeat)
    py_f, _ = per_step(plant, law, cfg, max(3, repeat // 5), compiled=False)
    return dict(
        compiled=comp,
        python=py,
        pc=pc,
        full=comp_f,
        full_python=py_f,
        diff=diff,
        engine=rc.dataset.attrs["engine"],
    )


def bench_batch(repeat, n_cases=1000):
    g1 = G1 * (1 + 0.2 * np.linspace(-1, 1, n_cases))
    plant, law, cfg = tamu_run(g1=g1)
    steps = cfg.n_steps * n_cases
    linear, _ = per_step(plant, law, cfg, repeat)
    linear_py, _ = per_step(plant, law, cfg, 1, compiled=False)
    plant, law, cfg = tamu_run(friction=True, noise=True, g1=g1)
    comp, _ = per_step(plant, law, cfg, repeat)
    py, _ = per_step(plant, law, cfg, 1, compiled=False)
    mem = {}
    for compiled in (True, False):
        tracemalloc.start()
        simulate(plant, law, cfg, compiled=compiled)
        mem[compiled] = tracemalloc.get_traced_memory()[1] / n_cases
        tracemalloc.stop()
    return dict(
        compiled=comp * cfg.n_steps / steps,
        python=py * cfg.n_steps / steps,
        linear=linear * cfg.n_steps / steps,
        linear_python=linear_py * cfg.n_steps / steps,
        mem=mem[True],
        mem_python=mem[False],
        n=n_cases,
    )


def bench_modes(repeat, n_modes=100):
    plant, law, cfg = tamu_run(n_modes=n_modes)
    comp, _ = per_step(plant, law, cfg, max(2, repeat // 5))
    _, info = tamu_problem(n_modes)
    t_pc, _, _ = best_of(python_control_loop(info), 2)
    return dict(compiled=comp, pc=t_pc / cfg.n_steps, n=plant.nx)


def eps_run(n_cases=1):
    plant = eps().plant(n_modes=45)
    target = dcm_to_quaternion(euler123_to_dcm([0.2, 0.2, 0.2]))
    law = MRPLaw(
        K="7200 N*m", P=["5400 N*m*s/rad", "32400 N*m*s/rad", "32800 N*m*s/rad"], beta_target=target
    )
    cfg = SimConfig(
        duration=10.0,
        control_rate=100.0,
        channel_actuators={"torque": ChannelActuator(saturation="2000 N*m")},
    )
    return plant, law, cfg


def bench_eps(repeat, n_cases):
    plant, law, cfg = eps_run()
    single, r = per_step(plant, law, cfg, max(2, repeat // 5))
    t0 = time.perf_counter()
    simulate(plant, law, cfg, n_cases=n_cases)
    batch = time.perf_counter() - t0
    return dict(
        single=single * cfg.n_steps,
        engine=r.dataset.attrs["engine"],
        integrator=getattr(plant, "integrator", "etd2rk"),
        nx=plant.nx,
        batch=batch / (cfg.n_steps * n_cases),
        n=n_cases,
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--eps-cases", type=int, default=100)
    args = ap.parse_args(argv)
    a = bench_single(args.repeat)
    print(
        f"(a) TAMU 10 modes, Law I, 1125 steps, engine {a['engine']}: simulate() "
        f"{a['compiled'] * US:.2f} µs/step compiled, {a['python'] * US:.1f} Python loop, "
        f"forced_response {a['pc'] * US:.2f} (ratio pc/compiled {a['pc'] / a['compiled']:.2f}"
        f"×; Python loop {a['python'] / a['compiled']:.0f}× slower); compiled − Python θ "
        f"{a['diff']:.1e} rad"
    )
    print(
        f"    with friction + noise: {a['full'] * US:.2f} µs/step compiled, "
        f"{a['full_python'] * US:.1f} Python loop"
    )
    b = bench_batch(max(2, args.repeat // 10))
    print(
        f"(b) {b['n']} cases, linear: {b['linear'] * US:.3f} µs per case-step compiled, "
        f"{b['linear_python'] * US:.3f} Python loop"
    )
    print(
        f"(b) {b['n']} cases, friction + noise: {b['compiled'] * US:.3f} µs per case-step "
        f"compiled, {b['python'] * US:.3f} Python loop; peak memory {b['mem'] / 1e3:.0f} kB "
        f"per case compiled, {b['mem_python'] / 1e3:.0f} kB Python loop"
    )
    c = bench_modes(args.repeat)
    print(
        f"(c) 100 modes per appendage ({c['n']} states): simulate() {c['compiled'] * US:.1f} "
        f"µs/step, forced_response {c['pc'] * US:.1f} (ratio {c['pc'] / c['compiled']:.2f}×)"
    )
    d = bench_eps(args.repeat, args.eps_cases)
    print(
        f"(d) EPS flexible, 45 modes ({d['nx']} states), MRP PD, 10 s at 100 Hz, engine "
        f"{d['engine']} ({d['integrator']}): single run {d['single']:.3f} s; batch of "
        f"{d['n']}: {d['batch'] * US:.2f} µs per case-step"
    )


if __name__ == "__main__":
    main()
