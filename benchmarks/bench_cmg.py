"""CMG benchmark (issue 14): steering kernels, gimbal runs and the space station per simulated
orbit.

Timed (wall time, best of N):

* the steering kernel ``flexsat.dynamics.cmg.steering_rates`` (pseudo-inverse, Eq. 7) for one
  gimbal set and for 1,000 sets in one call (µs per set);
* a V3 run (``integrate_gimbals`` from σ = 0 under the unit +x demand to the singular stop,
  DOP853 at rtol 1e-10);
* the space station (§8.4, V9) per simulated orbit (5,712 s): the LQR attitude loop
  (``simulate_attitude``, one orbit) and the CMG loop (``cmg_loop`` from [45, −45, 45, −45]°,
  pseudo-inverse, one orbit);
* the rigid spacecraft with a CMG pyramid (``CmgSpacecraft``) through ``flexsat.sim.simulate``:
  the station's roll and pitch inertia (yaw: I1 + I2, as Table 2's violates the triangle
  inequality) and rotors, a rate-damping law at 1 Hz (RKMK4, 2 substeps), one orbit,
  1 case and 100 cases.

Prints a markdown table; a plain script, never collected by pytest.

    .venv/bin/python benchmarks/bench_cmg.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from flexsat.cases import space_station_cmg as st
from flexsat.control.base import Controller
from flexsat.dynamics import cmg
from flexsat.dynamics.cmg_actuator import CmgSpacecraft
from flexsat.sim import SimConfig, simulate


def best_of(repeats, fn):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


class RateDamping(Controller):
    reads = ("rate",)
    writes = ("torque",)

    def __init__(self, k):
        self.k = k

    def __call__(self, t, y, state):
        return -self.k * y["rate"], state


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    r = args.repeats
    rng = np.random.default_rng(0)
    rows = []

    sigma1, torque1 = rng.uniform(-np.pi, np.pi, 4), rng.normal(size=3)
    n_calls = 1000
    t, _ = best_of(r, lambda: [cmg.steering_rates(sigma1, torque1) for _ in range(n_calls)])
    rows.append(("steering_rates, 1 set per call", f"{1e6 * t / n_calls:.1f} µs per set"))
    sig, tq = rng.uniform(-np.pi, np.pi, (1000, 4)), rng.normal(size=(1000, 3))
    t, _ = best_of(r, lambda: cmg.steering_rates(sig, tq))
    rows.append(("steering_rates, 1,000 sets in one call", f"{1e6 * t / 1000:.2f} µs per set"))

    t, run = best_of(r, lambda: cmg.integrate_gimbals(np.zeros(4), [-1.0, 0.0, 0.0], 5.0))
    rows.append((f"V3 run to the singular stop (t = {run.t[-1]:.4f} s)", f"{1e3 * t:.0f} ms"))

    design = st.design()
    period = design.data.period
    t, att = best_of(r, lambda: st.simulate_attitude(design, period, "aero_substitute"))
    rows.append(("station attitude loop (LQR, AERO1 substitute)", f"{t:.2f} s per orbit"))
    alt = np.deg2rad([45.0, -45.0, 45.0, -45.0])
    t, _ = best_of(r, lambda: st.cmg_loop(att, alt))
    rows.append(
        ("station CMG loop, pseudo-inverse from [45, −45, 45, −45]°", f"{t:.2f} s per orbit")
    )

    # Table 2's moments violate the triangle inequality (5.28 + 10.80 < 58.57 slug ft²: no mass
    # distribution has them, the products of inertia being neglected), which CmgSpacecraft
    # refuses; the flat-plate limit I3 = I1 + I2 stands in for the timing
    i1, i2, _ = design.data.inertia
    inertia = np.diag([i1, i2, i1 + i2])
    plant = CmgSpacecraft(
        inertia, design.data.rotor_momentum, steering="sr", alpha=1e-3, gimbal_rate_limit="1 deg/s"
    )
    x0 = plant.state_from(rate=[1e-4, -2e-4, 1e-4], gimbal_angles=alt)
    cfg = SimConfig(duration=period, control_rate=1.0, substeps=2)
    law = RateDamping(1.0e4)
    for n in (1, 100):
        t, _ = best_of(
            r, lambda n=n: simulate(plant, law, cfg, n_cases=n, initial_state=np.tile(x0, (n, 1)))
        )
        rows.append(
            (
                f"CmgSpacecraft in simulate(), 1 Hz, {n} case(s)",
                f"{t:.2f} s per orbit ({1e6 * t / (period * n * 2):.0f} µs per "
                f"RKMK4 step per case)",
            )
        )

    cpu = platform.processor() or platform.machine()
    print(
        f"machine: {platform.node()}, {cpu}, {os.cpu_count()} cores, Python "
        f"{platform.python_version()}, numpy {np.__version__}; best of {r}\n"
    )
    print("| what | time |\n|---|---|")
    for what, value in rows:
        print(f"| {what} | {value} |")


if __name__ == "__main__":
    main()
