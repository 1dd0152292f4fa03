"""Propagator set-up: the minimal block exponential against the former 3n × 3n one (issue #10).

TAMU case, Control Law II (g1 = 3000 oz-in/rad, g2 = 800 oz-in s/rad), linear setting
(``case.sim_config(15.0, friction=False, noise=False)``: 15 s at 75 Hz), 10 and 100 modes per
appendage. Timed side by side in one run, best (median) of the repeats:

* build: ``ExponentialStepper.build`` as it is now (expm of the (n+1) × (n+1) block
  [[A, B_u], [0, 0]]; n + 3 with the friction column) against the former construction, expm of
  the 3n × 3n Van Loan block [[A, I, 0], [0, 0, I], [0, 0, 0]] and the products with B_u, B_f
  (``phi_products`` with B = I, the same matrix the stepper exponentiated before);
* simulate: the whole ``simulate`` call with each stepper (the engine's stepper class swapped
  for the run), and the largest difference of the hub-angle histories.

A plain script, never collected by pytest:

    PYTHONPATH=src .venv/bin/python benchmarks/bench_expm.py [--repeat 5]
"""

from __future__ import annotations

import argparse
from contextlib import contextmanager

import numpy as np

from bench_tamu import best_of  # the same timing helper as the TAMU benchmark
from flexsat.cases.tamu import tamu
from flexsat.sim import engine
from flexsat.sim.integrators import ExponentialStepper, phi_products
from flexsat.units import to_si

G1 = to_si("3000 ozf*in/rad", "N*m/rad")
G2 = to_si("800 ozf*in*s/rad", "N*m*s/rad")


class FullBlockStepper(ExponentialStepper):
    """The former set-up: φ1, φ2 in full from the 3n × 3n block, then the products."""

    @classmethod
    def build(cls, A, Bu, Bf, dt: float, substeps: int = 1) -> ExponentialStepper:
        n = A.shape[0]
        E, P1, P2 = phi_products(np.asarray(A, float), dt / substeps, np.eye(n), n)
        P1u = (P1 @ np.asarray(Bu, float).reshape(n, -1)).T.copy()  # (m, n), the stepper's form
        if Bf is None:
            return cls(E.T.copy(), P1u, None, None, substeps)
        return cls(E.T.copy(), P1u, (P1 @ Bf).T.copy(), (P2 @ Bf).T.copy(), substeps)


@contextmanager
def engine_stepper(cls):
    saved = engine.ExponentialStepper
    engine.ExponentialStepper = cls
    try:
        yield
    finally:
        engine.ExponentialStepper = saved


def fmt(best_median) -> str:
    best, median = best_median
    return f"{best * 1e3:.3g} ms ({median * 1e3:.3g})"


def compare(n_modes: int, repeat: int) -> list[str]:
    """Table rows of one TAMU model: the two builds, then the two whole runs."""
    case = tamu(n_modes=n_modes)
    model = case.model()
    A, Bu, Bf = model.state_space
    cfg = case.sim_config(15.0, friction=False, noise=False)
    law = case.law_ii(G1, G2)
    label = f"{n_modes} ({model.nx})"
    rows = []
    for what, bf in (("build, linear", None), ("build, friction column", Bf[:, :1])):
        old = best_of(lambda bf=bf: FullBlockStepper.build(A, Bu, bf, cfg.dt), repeat)
        new = best_of(lambda bf=bf: ExponentialStepper.build(A, Bu, bf, cfg.dt), repeat)
        rows.append(
            f"| {label} | {what} | {fmt(old[:2])} | {fmt(new[:2])} | {old[0] / new[0]:.1f}× |"
        )
    engine.simulate(model, law, cfg)  # warm-up (imports, caches)
    with engine_stepper(FullBlockStepper):
        old = best_of(lambda: engine.simulate(model, law, cfg), repeat)
    new = best_of(lambda: engine.simulate(model, law, cfg), repeat)
    th_old = old[2].dataset.theta.values
    diff = np.abs(new[2].dataset.theta.values - th_old).max() / np.abs(th_old).max()
    rows.append(
        f"| {label} | whole `simulate` (linear, 15 s at 75 Hz; hub angle differs by "
        f"{diff:.1e} relative) | {fmt(old[:2])} | {fmt(new[:2])} "
        f"| {old[0] / new[0]:.2f}× |"
    )
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    print(
        "| modes per appendage (states) | set-up | former 3n × 3n: best (median) "
        "| minimal block: best (median) | former / minimal |"
    )
    print("|---|---|---|---|---|")
    for n_modes in (10, 100):
        print("\n".join(compare(n_modes, args.repeat)))


if __name__ == "__main__":
    main()
