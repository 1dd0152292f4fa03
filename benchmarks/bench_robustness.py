"""Robustness and reduction benchmark (issue 24): the TAMU loop over ±10 % on 10 modes.

Times (wall and CPU, best of N) for the TAMU hub with its 10 flexible modes under Control Law I
(g1 = 600 oz-in/rad, g2 = 800 oz-in-s/rad, continuous):

* ``certify``: the guaranteed answer over ±10 % on every mode's frequency and damping ratio —
  stability and a bound of sup ‖S‖∞ (flexsat.analysis.robustness, zero exclusion with support
  functions, branch-and-bound on frequency), including building the modal loop;
* ``stability_margin``: the largest certified uniform ±k·(10 %, 10 %) ... k <= 0.99 (bisection);
* the dense sweep it is checked against: eigenvalues of the batch of closed loops and |S| on a
  grid, for N members;
* balanced truncation and the modal truncations of the 22-state plant to 4 modes, with their
  H∞ errors and Glover's bound.

Target (issue 24): the robustness analysis <= 10 s. Prints a markdown table; never collected
by pytest.

    .venv/bin/python benchmarks/bench_robustness.py [--members 2000] [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import time

from flexsat.analysis.reduction import compare_reductions
from flexsat.analysis.robustness import (
    ParameterBox,
    certify,
    modal_loop,
    stability_margin,
    sweep,
)
from flexsat.cases.tamu import tamu
from flexsat.control.state_space_export import continuous_law
from flexsat.dynamics.linear_model import plant_state_space


def timed(fn, repeats):
    best_w = best_c = float("inf")
    out = None
    for _ in range(repeats):
        w, c = time.perf_counter(), time.process_time()
        out = fn()
        best_w = min(best_w, time.perf_counter() - w)
        best_c = min(best_c, time.process_time() - c)
    return out, best_w, best_c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--members", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    case = tamu()
    P = plant_state_space(case.model())
    K = continuous_law(case.law_i("600 ozf*in/rad", "800 ozf*in*s/rad", 0.0))

    def analysis():
        loop = modal_loop(P, K)
        return loop, certify(loop, ParameterBox.uniform(loop, 0.1, 0.1))

    (loop, cert), w1, c1 = timed(analysis, args.repeats)
    box = ParameterBox.uniform(loop, 0.1, 0.1)
    margin, w2, c2 = timed(lambda: stability_margin(loop, box, k_max=0.99), args.repeats)
    sw, w3, c3 = timed(lambda: sweep(loop, box, n_members=args.members), 1)
    print(f"OMP/BLAS threads: {os.environ.get('OPENBLAS_NUM_THREADS', 'default')}")
    print("| step | result | wall (s) | CPU (s) |")
    print("|---|---|---|---|")
    print(
        f"| certify ±10 % on 10 modes | stable={cert.stable}, sup‖S‖∞ <= "
        f"{cert.sensitivity_bound:.4f} ({cert.n_intervals} intervals) | {w1:.3f} | {c1:.3f} |"
    )
    print(
        f"| certified stability margin | k = {margin:.3f} of (±10 %, ±10 %) | {w2:.3f} | {c2:.3f} |"
    )
    print(
        f"| dense sweep, {sw.n_members} members | all stable={sw.all_stable}, max Re λ = "
        f"{sw.max_real_pole:.4f}, max |S| = {sw.sensitivity_peak:.4f} | {w3:.3f} | {c3:.3f} |"
    )
    print(f"| bound / sweep | {cert.sensitivity_bound / sw.sensitivity_peak:.4f} | | |")
    table, w4, c4 = timed(lambda: compare_reductions(P, 4), 1)
    for name, (model, err) in table.items():
        print(
            f"| reduce 22 → {model.system.nstates} states: {name} | H∞ error {err:.4g}, "
            f"bound {model.error_bound:.4g} | | |"
        )
    print(f"| all reductions and their H∞ errors | | {w4:.3f} | {c4:.3f} |")


if __name__ == "__main__":
    main()
