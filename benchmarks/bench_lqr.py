"""LQR benchmark: continuous Riccati solves for lightly damped modal models of 50-400 states.

Model (n states = n/2 modes): one rigid-body mode and n/2 − 1 elastic modes at frequencies
geometrically spaced over 0.1 … 100 rad/s, modal damping ζ = 0.005, two inputs with random
(seeded) modal participation, Q = I, R = I:

    A = [[0, I], [−diag(ω²), −diag(2ζω)]],   B = [0; Φᵀb]

Solvers timed (wall time, best of N):

* scipy: ``scipy.linalg.solve_continuous_are(A, B, Q, R)`` (balanced) and K = R⁻¹BᵀS;
* python-control: ``control.lqr`` (its 'scipy' method; with slycot installed the 'slycot'
  method, SLICOT SB02MD, is timed too — it is not installed here, which the table states);
* flexsat: ``flexsat.control.lqr`` (scipy's solver plus the input checks — symmetry and
  definiteness of the weights, PBH stabilizability/detectability — and the residual).

Residuals: ρ_c = ‖AᵀS + SA − SBR⁻¹BᵀS + Q‖_F / (2‖AᵀS‖_F + ‖SBR⁻¹BᵀS‖_F + ‖Q‖_F) (the
relative residual flexsat reports) and the same norm relative to ‖Q‖_F. Prints a markdown
table; a plain script, never collected by pytest.

    .venv/bin/python benchmarks/bench_lqr.py [--sizes 50,100,200,400] [--repeats 3]
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import time

import numpy as np
import scipy
import scipy.linalg

import control
from flexsat.control import lqr
from flexsat.control.lqr import care_residual


def modal_model(n_states: int, zeta: float = 0.005, n_inputs: int = 2, seed: int = 0):
    m = n_states // 2
    w = np.concatenate([[0.0], np.geomspace(0.1, 100.0, m - 1)])
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.diag(w**2), -np.diag(2 * zeta * w)]])
    B = np.vstack(
        [np.zeros((m, n_inputs)), np.random.default_rng(seed).standard_normal((m, n_inputs))]
    )
    return A, B, np.eye(n_states), np.eye(n_inputs)


def best_of(repeats: int, fn):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def solvers(has_slycot: bool):
    def scipy_solve(A, B, Q, R):
        S = scipy.linalg.solve_continuous_are(A, B, Q, R)
        return S

    def control_solve(method):
        return lambda A, B, Q, R: control.lqr(A, B, Q, R, method=method)[1]

    def flexsat_solve(A, B, Q, R):
        return lqr(A, B, Q, R).solution

    out = [
        ("scipy solve_continuous_are", scipy_solve),
        ("python-control lqr (scipy)", control_solve("scipy")),
    ]
    if has_slycot:
        out.append(("python-control lqr (slycot)", control_solve("slycot")))
    out.append(("flexsat lqr", flexsat_solve))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="50,100,200,400")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    has_slycot = importlib.util.find_spec("slycot") is not None

    print(
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"python-control {control.__version__}, slycot "
        f"{'installed' if has_slycot else 'NOT installed (slycot rows omitted)'}"
    )
    print(
        f"Model: rigid mode + elastic modes 0.1-100 rad/s, zeta = 0.005, 2 inputs, Q = I, R = I; "
        f"best of {args.repeats}\n"
    )
    print("| states | solver | time (s) | rel. residual ρ_c | residual / ‖Q‖ |")
    print("|---:|---|---:|---:|---:|")
    for n in sizes:
        A, B, Q, R = modal_model(n)
        named = solvers(has_slycot)
        best = {name: np.inf for name, _ in named}
        result = {}
        for _ in range(args.repeats):  # interleaved, so that load on a shared machine hits all
            for name, fn in named:
                t, result[name] = best_of(1, lambda fn=fn: fn(A, B, Q, R))
                best[name] = min(best[name], t)
        for name, _ in named:
            rel, rel_q, _ = care_residual(A, B, Q, R, result[name])
            print(f"| {n} | {name} | {best[name]:.3f} | {rel:.1e} | {rel_q:.1e} |", flush=True)


if __name__ == "__main__":
    main()
