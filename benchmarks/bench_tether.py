"""Wall time per simulated orbit of the tethered-subsatellite retrieval (issue 14).

A plain script, never collected as a test: ``python benchmarks/bench_tether.py``.

Controller 2 (K = 1, 0, 3, 2; λr = 0.01) from λ = 1, θ = φ = 5°, two orbits, the paper's scales
(Vadali & Kim; Junkins, Pollock & Rahman 1990 Att. 12):

1. continuous feedback (:func:`flexsat.dynamics.tether.integrate`, DOP853 at rtol 1e-10,
   2,000 output samples an orbit) for 1 case and for 100 cases in one vectorised call;
2. the simulation core (:func:`flexsat.sim.simulate`, Python loop: the law is nonlinear, RK4 of
   the plant with the commands held) at 1,000 and 2,000 control samples an orbit, 1 case and
   100 cases (K4 dispersed over [1, 4]).

Each timing is the best of ``--repeat`` runs (the machine is shared).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from flexsat.control.tether_laws import CoupledTetherLaw
from flexsat.dynamics.tether import TetheredSubsatellite, TetherScales, integrate
from flexsat.sim.config import SimConfig
from flexsat.sim.engine import simulate

ORBITS = 2.0
X0 = np.array([1.0, np.radians(5), np.radians(5), 0.0, 0.0, 0.0])


def best(f, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    scales = TetherScales(mass="22.7 kg", length="20 km", altitude="220 km")
    tau = np.linspace(0, 2 * np.pi * ORBITS, int(2000 * ORBITS) + 1)
    print(f"{'path':<48}{'cases':>6}{'s/orbit':>10}{'ms/case-orbit':>15}")
    for n in (1, 100):
        law = CoupledTetherLaw(1.0, 0.0, 3.0, np.linspace(1.0, 4.0, n) if n > 1 else 2.0, 0.01)
        t = best(lambda: integrate(law.nondimensional, np.tile(X0, (n, 1)), tau), args.repeat)
        print(
            f"{'continuous (DOP853, rtol 1e-10)':<48}{n:>6}{t / ORBITS:>10.3f}"
            f"{1e3 * t / ORBITS / n:>15.2f}"
        )
    plant = TetheredSubsatellite(scales)
    x0 = scales.state_to_si(X0)
    for samples in (1000, 2000):
        cfg = SimConfig(
            duration=ORBITS * scales.period, control_rate=samples / scales.period, substeps=1
        )
        for n in (1, 100):
            law = CoupledTetherLaw(
                1.0, 0.0, 3.0, np.linspace(1.0, 4.0, n) if n > 1 else 2.0, 0.01, scales=scales
            )
            t = best(lambda: simulate(plant, law, cfg, n_cases=n, initial_state=x0), args.repeat)
            print(
                f"{f'simulation core, {samples} samples/orbit':<48}{n:>6}{t / ORBITS:>10.3f}"
                f"{1e3 * t / ORBITS / n:>15.2f}"
            )


if __name__ == "__main__":
    main()
