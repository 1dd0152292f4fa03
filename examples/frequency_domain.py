"""Margins of the TAMU Law I and of an EPS three-axis LQG, continuous and sampled-data.

Run: ``python examples/frequency_domain.py [figure.png]`` (docs/frequency_domain.md shows its
output). Prints the classical and disk margins of the TAMU hub loop under Law I (the default
scenario's gains) as designed (continuous) and as run at 75 Hz with 0 and 1 sample of
computation delay; then the loop-at-a-time and multiloop disk margins of a 45-mode EPS
AttitudeLQG at 10 Hz, its per-axis classical margins, and its least damped closed-loop poles.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from flexsat.analysis.frequency_domain import build_loop
from flexsat.analysis.frequency_plots import loop_figure
from flexsat.analysis.loop_modes import closed_loop_poles
from flexsat.analysis.margins import disk_margin, disk_margins, loop_margins
from flexsat.cases.eps import eps
from flexsat.cases.tamu import tamu
from flexsat.control import AttitudeLQG
from flexsat.control.state_space_export import continuous_law, discrete_law
from flexsat.dynamics import linearize_attitude
from flexsat.dynamics.linear_model import plant_state_space


def tamu_law_i() -> None:
    case = tamu()
    plant = plant_state_space(case.model())
    law = case.law_i("600 ozf*in/rad", "800 ozf*in*s/rad", 0.0)
    dt = 1 / 75
    print("TAMU Law I (g1 = 600 oz-in/rad, g2 = 800 oz-in-s/rad), loop broken at the torque")
    print(
        f"{'loop':>24} {'PM (deg)':>9} {'ω_c (rad/s)':>11} {'GM':>8} {'DM (ms)':>8} {'disk α':>7}"
    )
    for label, K in (
        ("continuous", continuous_law(law)),
        ("75 Hz, no delay", discrete_law(law, dt)),
        ("75 Hz, 1 sample delay", discrete_law(law, dt, delay=1)),
    ):
        loop = build_loop(plant, K, "torque")
        m, dm = loop_margins(loop), disk_margin(loop)
        print(
            f"{label:>24} {m.phase_margin_deg:9.2f} {m.gain_crossover_rad_s:11.4f} "
            f"{m.gain_margin:8.3g} {1e3 * m.delay_margin_s:8.2f} {dm.alpha:7.3f}"
        )
    loop = build_loop(plant, discrete_law(law, dt, delay=1), "torque")
    if len(sys.argv) > 1:
        loop_figure(loop, frequency_unit="Hz", title="TAMU Law I, 75 Hz, 1 sample").savefig(
            sys.argv[1], dpi=90
        )


def eps_lqg() -> None:
    plant = eps().plant(n_modes=45)
    lin = linearize_attitude(plant)
    n = lin.A.shape[0]
    Q = np.diag([100 / 0.25**2] * 3 + [10.0] * 3 + [1.0] * (n - 6))
    law = AttitudeLQG.design(
        lin, Q, 1e-3 * np.eye(3), np.eye(3), np.diag([1e-6] * 3 + [1e-4] * 3), 0.1
    )
    P = lin.to_statespace("eps")
    start = time.perf_counter()
    loop = build_loop(P, discrete_law(law, 0.1), "input")
    per_axis, multi = disk_margins(loop)
    took = time.perf_counter() - start
    print(f"\nEPS AttitudeLQG, 45 modes, 10 Hz, loop at the plant input ({took:.2f} s)")
    for axis, d in enumerate(per_axis):
        m = loop_margins(build_loop(P, discrete_law(law, 0.1), f"torque[{axis}]"))
        print(
            f"  torque[{axis}]: PM {m.phase_margin_deg:6.2f} deg, GM {m.gain_margin:6.3f}, "
            f"DM {m.delay_margin_s:6.3f} s, disk α {d.alpha:.3f}"
        )
    lo, hi = multi.gain_range
    print(
        f"  multiloop disk margin α >= {multi.alpha:.3f}: gains [{lo:.3f}, {hi:.3f}] and "
        f"±{multi.phase_deg:.1f} deg on all three torques at once"
    )
    least = sorted(
        (p for p in closed_loop_poles(loop) if p.pole.imag > 0 and p.plant_share > 0.5),
        key=lambda p: p.damping_ratio,
    )[:3]
    for p in least:
        print(
            f"  least damped: {p.mode:>10} {p.natural_frequency_rad_s:8.4f} rad/s, "
            f"ζ = {p.damping_ratio:.4f}"
        )


if __name__ == "__main__":
    tamu_law_i()
    eps_lqg()
