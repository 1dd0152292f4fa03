"""Compiled three-axis batches (issue 22 deliverable 4): the lane kernel of
``flexsat.sim.kernels_attitude`` against the Python loop of ``flexsat.sim.engine`` on the same
runs, side by side in one run, each the best of N calls of ``simulate`` (end to end: set-up,
loop, outputs, result dataset).

(a) Rigid three-axis batch: ``RigidSpacecraft`` (the conformance suite's inertia), MRP PD law
    with a per-case gain, 1,000 cases, 20 s at 10 Hz (RKMK4, 1 substep). µs per case-step =
    wall time / (cases × control steps). Target <= 0.2 µs.
(b) EPS with 45 elastic modes (97 states, exp_rk4 with the engine's substeps), the example's
    MRP PD law (examples/eps_flexible_slew.yaml), a batch of 100: a shared plant
    (``n_cases=100``) and a dispersed one (``stack_plants`` of 100 ``with_parameters`` cases:
    inertia ±5 %, frequencies ±10 %, log-normal damping σ = 0.3). Target <= 2 µs per
    case-step (the issue's "today": 13 µs on the Python loop).
(c) The 200-case three-axis Monte Carlo: the example's EPS slew (10 modes, 60 s at 20 Hz,
    saturation 2,000 N m) dispersed as in (b), as one ``stack_plants`` batch on the compiled
    path (plants built, modal forms and propagators included) against the Python loop over
    the cases one by one (the way it was run: each case its own ``simulate``), the latter
    timed on ``--loop-cases`` cases and scaled to 200.

Run with ``python benchmarks/bench_attitude.py [--repeat N]``; numbers go to
docs/performance.md by hand.

``--against TREE`` (a source tree of another version, e.g. ``git archive <commit> src | tar -x
-C /tmp/base``): the compiled rows (a) and (b) of this tree and of TREE side by side instead,
each in its own interpreter, alternating (TREE, this, TREE, ...) ``--runs`` processes each, each
process the best of ``--repeat`` calls; end to end and the kernel calls alone (the three-axis
kernels of ``flexsat.sim.compiled_attitude`` wrapped by a timer), wall and process CPU time,
min / median over the processes.

The compiled rows include the same runs with ``metrics_only=True`` (the channel metrics
accumulated in the loop, no history; a tree without that path for three-axis runs returns the
full result) and with ``SimConfig(substeps=1)`` (one integrator step per control period: its
error against 32 substeps is below the round-off bound, docs/performance.md).

``--step``: the flexible plant's integrator step alone (``kernels_attitude.modal_steps``, EPS
45 modes, 4 substeps, one group of 8 lanes, 200 control steps, best of 5, process CPU time per
lane and substep), with the propagators shared by the lanes and with each lane's own copy (a
dispersed plant's layout); the two give the same numbers bit for bit.

NUMBA_NUM_THREADS as set (2 on the benchmark machine: a batch of at least 16 cases runs its
groups of 8 on both cores).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from flexsat.cases.eps import eps  # noqa: E402
from flexsat.control.attitude_laws import MRPLaw  # noqa: E402
from flexsat.dynamics.dispersion import stack_plants  # noqa: E402
from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft  # noqa: E402
from flexsat.sim import SimConfig, simulate  # noqa: E402
from flexsat.sim.channels import ChannelActuator  # noqa: E402

J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
TARGET = [
    np.cos(0.15),
    np.sin(0.15) / np.sqrt(3),
    np.sin(0.15) / np.sqrt(3),
    np.sin(0.15) / np.sqrt(3),
]
EPS_GAINS = dict(K=7200.0, P=[5400.0, 32400.0, 32800.0])  # examples/eps_flexible_slew.yaml


def timed(fn, repeat: int):
    """(best wall time, the process CPU time of that call (every thread), last result): on a
    shared machine the CPU time is what the run costs, the wall time what it took."""
    best, out = (np.inf, np.inf), None
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        best = min(best, (time.perf_counter() - w0, time.process_time() - c0))
    return best[0], best[1], out


def _per_step(seconds: float, cases: int, config: SimConfig) -> float:
    return 1e6 * seconds / (cases * config.n_steps)


def _row(label: str, compiled, python, cases: int, config: SimConfig) -> None:
    """compiled, python: (wall, CPU) s."""
    (cw, cc), (pw, pc) = compiled, python

    def us(t):
        return _per_step(t, cases, config)

    print(
        f"  {label:36} µs/case-step, wall (CPU): compiled {us(cw):7.3f} ({us(cc):7.3f})   "
        f"python {us(pw):8.3f} ({us(pc):8.3f})   ratio {pw / cw:5.1f}x ({pc / cc:5.1f}x)"
    )


def bench_rigid(repeat: int) -> None:
    n = 1000
    config = SimConfig(duration=20.0, control_rate=10.0)
    law = MRPLaw(K=np.linspace(8.0, 14.0, n), P=[50.0, 60.0, 70.0], beta_target=TARGET)
    p = RigidSpacecraft(J)
    *c, r = timed(lambda: simulate(p, law, config, n_cases=n), repeat)
    assert r.dataset.attrs["engine"] == "compiled"
    *py, _ = timed(lambda: simulate(p, law, config, n_cases=n, compiled=False), 1)
    print(f"(a) rigid three-axis batch, {n} cases, {config.n_steps} steps, best of {repeat}")
    _row("RigidSpacecraft, MRP PD (per-case K)", c, py, n, config)


def _dispersed(base, n: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    w = np.sqrt(base.stiffness)
    return [
        base.with_parameters(
            inertia=base.inertia * (1 + 0.05 * rng.uniform(-1, 1)),
            frequencies=w * (1 + 0.1 * rng.uniform(-1, 1, w.size)),
            damping=0.005 * np.exp(0.3 * rng.standard_normal(w.size)),
        )
        for _ in range(n)
    ]


def bench_eps45(repeat: int) -> None:
    n = 100
    config = SimConfig(duration=10.0, control_rate=20.0)
    law = MRPLaw(**EPS_GAINS, beta_target=TARGET)
    base = eps().plant(n_modes=45)
    print(f"(b) EPS, 45 modes ({base.nx} states), batch of {n}, {config.n_steps} steps")
    *c, r = timed(lambda: simulate(base, law, config, n_cases=n), repeat)
    assert r.dataset.attrs["engine"] == "compiled"
    *py, _ = timed(lambda: simulate(base, law, config, n_cases=n, compiled=False), 1)
    _row(f"shared plant (substeps {r.dataset.attrs['substeps']})", c, py, n, config)
    t0 = time.perf_counter()
    batch = stack_plants(_dispersed(base, n))
    build = time.perf_counter() - t0
    *c, r = timed(lambda: simulate(batch, law, config), repeat)
    assert r.dataset.attrs["engine"] == "compiled"
    *py, _ = timed(lambda: simulate(batch, law, config, compiled=False), 1)
    _row("dispersed plant (stack_plants)", c, py, n, config)
    print(f"  building the {n} dispersed plants: {build:.3f} s")


def bench_monte_carlo(loop_cases: int) -> None:
    n = 200
    config = SimConfig(
        duration=60.0,
        control_rate=20.0,
        channel_actuators={"torque": ChannelActuator(saturation=2000.0)},
    )
    law = MRPLaw(**EPS_GAINS, beta_target=TARGET)
    base = eps().plant(n_modes=10)

    def batch():
        plants = _dispersed(base, n)
        return plants, simulate(stack_plants(plants), law, config)

    bw, bc, (plants, r) = timed(batch, 1)
    assert r.dataset.attrs["engine"] == "compiled"

    def loop():
        for p in plants[:loop_cases]:
            simulate(p, law, config, n_cases=1, compiled=False)

    lw, lc, _ = timed(loop, 1)
    scale = n / loop_cases
    print(
        f"(c) Monte Carlo, {n} cases of the EPS slew (10 modes, {config.n_steps} steps), "
        f"wall (CPU) s\n"
        f"  one compiled batch (plants, modal forms, run, outputs) {bw:8.2f} ({bc:8.2f})\n"
        f"  Python loop, case by case ({loop_cases} timed, × {scale:g}) "
        f"{lw * scale:8.1f} ({lc * scale:8.1f})   ratio {lw * scale / bw:6.1f}x "
        f"({lc * scale / bc:6.1f}x)"
    )


def _kernel_clock() -> list[float]:
    """[wall, CPU] s spent in the three-axis kernels from now on: the kernels as
    ``flexsat.sim.compiled_attitude`` calls them, wrapped by a timer."""
    from flexsat.sim import compiled_attitude

    spent = [0.0, 0.0]

    def clocked(kernel):
        def call(*args):
            w0, c0 = time.perf_counter(), time.process_time()
            kernel(*args)
            spent[0] += time.perf_counter() - w0
            spent[1] += time.process_time() - c0

        return call

    compiled_attitude.attitude_loop = clocked(compiled_attitude.attitude_loop)
    compiled_attitude.attitude_loop_parallel = clocked(compiled_attitude.attitude_loop_parallel)
    return spent


def compiled_rows(repeat: int) -> dict[str, list[float]]:
    """µs per case-step of the compiled rows (a), (b): label -> [wall, CPU, kernel wall,
    kernel CPU] of the best call (least wall time) of ``repeat``."""
    spent = _kernel_clock()
    base = eps().plant(n_modes=45)
    eps_config = SimConfig(duration=10.0, control_rate=20.0)
    eps_law = MRPLaw(**EPS_GAINS, beta_target=TARGET)
    rigid_config = SimConfig(duration=20.0, control_rate=10.0)
    rigid_law = MRPLaw(K=np.linspace(8.0, 14.0, 1000), P=[50.0, 60.0, 70.0], beta_target=TARGET)
    batch = stack_plants(_dispersed(base, 100))
    rigid1 = SimConfig(duration=20.0, control_rate=10.0, substeps=1)
    eps1 = SimConfig(duration=10.0, control_rate=20.0, substeps=1)
    runs = {
        "(a) rigid, 1,000 cases, MRP PD": (
            lambda: simulate(RigidSpacecraft(J), rigid_law, rigid_config, n_cases=1000),
            1000,
            rigid_config,
        ),
        "(a) same, metrics only": (
            lambda: simulate(
                RigidSpacecraft(J), rigid_law, rigid_config, n_cases=1000, metrics_only=True
            ),
            1000,
            rigid_config,
        ),
        "(a) same, metrics only, 1 substep": (
            lambda: simulate(
                RigidSpacecraft(J), rigid_law, rigid1, n_cases=1000, metrics_only=True
            ),
            1000,
            rigid1,
        ),
        "(b) EPS 45 modes, 100 cases of one plant": (
            lambda: simulate(base, eps_law, eps_config, n_cases=100),
            100,
            eps_config,
        ),
        "(b) same, metrics only": (
            lambda: simulate(base, eps_law, eps_config, n_cases=100, metrics_only=True),
            100,
            eps_config,
        ),
        "(b) same, metrics only, 1 substep": (
            lambda: simulate(base, eps_law, eps1, n_cases=100, metrics_only=True),
            100,
            eps1,
        ),
        "(b) EPS 45 modes, 100 dispersed plants": (
            lambda: simulate(batch, eps_law, eps_config),
            100,
            eps_config,
        ),
        "(b) dispersed, metrics only, 1 substep": (
            lambda: simulate(batch, eps_law, eps1, metrics_only=True),
            100,
            eps1,
        ),
    }
    rows = {}
    for label, (fn, cases, config) in runs.items():
        fn()  # compiled, warm
        best = None
        for _ in range(repeat):
            spent[:] = [0.0, 0.0]
            w0, c0 = time.perf_counter(), time.process_time()
            r = fn()
            t = [time.perf_counter() - w0, time.process_time() - c0, *spent]
            assert r.dataset.attrs["engine"] == "compiled"
            if best is None or t[0] < best[0]:
                best = t
        rows[label] = [_per_step(v, cases, config) for v in best]
    return rows


def against(tree: str, runs: int, repeat: int) -> None:
    """The compiled rows of this tree and of ``tree`` side by side (module docstring)."""
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src")
    trees = {"against": os.path.join(tree, "src"), "this": here}
    got: dict[str, list] = {k: [] for k in trees}
    for _ in range(runs):
        for name, src in trees.items():
            env = dict(os.environ, PYTHONPATH=src)
            out = subprocess.run(
                [sys.executable, __file__, "--child", "--repeat", str(repeat)],
                env=env,
                check=True,
                capture_output=True,
                text=True,
            ).stdout
            got[name].append(json.loads(out.splitlines()[-1]))
    print(f"compiled rows, µs per case-step, min / median over {runs} processes (best of {repeat})")
    print(f"  against: {tree}; load average {os.getloadavg()[0]:.1f}")
    parts = ("end to end, wall", "end to end, CPU", "kernel alone, wall", "kernel alone, CPU")
    for label in got["this"][0]:
        for i, part in enumerate(parts):
            a = np.array([r[label][i] for r in got["against"]])
            b = np.array([r[label][i] for r in got["this"]])
            print(
                f"  {label:42} {part:19} against {a.min():7.3f} / {np.median(a):7.3f}   "
                f"this {b.min():7.3f} / {np.median(b):7.3f}   ratio {a.min() / b.min():5.2f}x"
            )


def bench_step() -> None:
    """The flexible step alone, shared against per-lane propagators (module docstring)."""
    from numba import njit

    from flexsat.sim.kernel_phases import row_entry, rows_shape
    from flexsat.sim.kernels_attitude import LANES, modal_steps
    from flexsat.sim.spacecraft_modal import modal_propagators, spacecraft_modal_form

    W, substeps, steps = LANES, 4, 200
    p = eps().plant(n_modes=45)
    modes = spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping)
    _, B = p.linear_part()
    Ti = modes.T_inv
    E2, E, Q1u, P1u, F = modal_propagators(
        modes.blocks, Ti @ B, Ti @ p.force_matrix, 0.05, substeps
    )
    R = np.ascontiguousarray(modes.T[1:7])
    n, m = R.shape[1], B.shape[1]

    def lanes(a):
        return np.ascontiguousarray(np.repeat(a[..., None], W, -1))

    R_lanes = np.zeros(rows_shape(6, n, W))
    for s in range(6):
        for i in range(n):
            a, b = row_entry(s, i, n, W)
            R_lanes[a, b, :] = R[s, i]

    @njit
    def run(k, z, w, E2, E, Q1u, P1u, F, R, J, work, g, acc, lanes):
        # lanes a run-time argument, as the kernel's group has it (kernels_attitude._group)
        for _ in range(k):
            modal_steps(z, w, E2, E, Q1u, P1u, F, R, J, substeps, work, g, acc, lanes)

    z0 = lanes(Ti @ p.state_from(rate=[0.01, 0.0, -0.01]))
    w = np.zeros((m, W))
    w[0] = 1.0
    layouts = {
        "per-lane copies": (lanes(E2), lanes(E), lanes(F), R_lanes),
        "shared": (E2, E, F, R),
    }
    ends = {}
    print(f"flexible step alone, EPS 45 modes ({n} states), {substeps} substeps, {W} lanes")
    for name, (e2, e, f, r) in layouts.items():
        arrays = (e2, e, lanes(Q1u), lanes(P1u), f, r, lanes(p.inertia))
        scratch = (np.empty((9, n, W)), np.empty((7, W)), np.empty((8, W)))
        run(1, z0.copy(), w, *arrays, *scratch, W)  # compiled
        best = np.inf
        for _ in range(5):
            z = z0.copy()
            c0 = time.process_time()
            run(steps, z, w, *arrays, *scratch, W)
            best = min(best, time.process_time() - c0)
        ends[name] = z
        print(f"  {name:16} {1e6 * best / (steps * substeps * W):6.3f} µs CPU per lane-substep")
    print(f"  bit for bit the same: {np.array_equal(*ends.values())}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--loop-cases", type=int, default=10)
    ap.add_argument("--against", help="source tree of the version to compare with")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--step", action="store_true", help="the flexible step alone")
    args = ap.parse_args()
    if args.step:
        bench_step()
        return
    if args.child:
        print(json.dumps(compiled_rows(args.repeat)))
        return
    if args.against:
        against(args.against, args.runs, args.repeat)
        return
    simulate(RigidSpacecraft(J), MRPLaw(K=1.0, P=1.0), SimConfig(duration=0.2, control_rate=10.0))
    bench_rigid(args.repeat)
    bench_eps45(args.repeat)
    bench_monte_carlo(args.loop_cases)


if __name__ == "__main__":
    main()
