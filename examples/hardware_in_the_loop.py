"""The laboratories' hardware in the loop: the TAMU maneuvers with their amplifier, anti-alias
filter and one-step-ahead command, and the NPS PD slews with the cable-spring torque.

Run: ``python examples/hardware_in_the_loop.py`` (docs/tamu.md and docs/nps.md show its output).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from flexsat.cases.nps import nps
from flexsat.cases.tamu import tamu
from flexsat.maneuvers.torque_shapes import PseudoSquare, Sinusoidal
from flexsat.sim.channels import ChannelDisturbance
from flexsat.sim.config import SimConfig
from flexsat.sim.disturbances import CableSpring
from flexsat.sim.engine import simulate
from flexsat.units import to_si


def _metrics(run, band_deg: float) -> tuple[float, float]:
    return float(run["settling_time_s"][0]), float(run["overshoot_deg"][0])


def tamu_rows() -> None:
    """Law I and Law II (the default scenario's settings) ideal and with the TAMU hardware
    preset, each piece alone, settling to 0.5° and 1°, overshoot."""
    case = tamu()
    g = lambda v: to_si(f"{v} ozf*in/rad", "N*m/rad")  # noqa: E731
    gd = lambda v: to_si(f"{v} ozf*in*s/rad", "N*m*s/rad")  # noqa: E731
    laws = {
        "Law I, g1 = 600, g2 = 800": case.law_i(g(600), gd(800)),
        "Law I, g1 = 600, g2 = 0": case.law_i(g(600), 0.0),
        "Law II, α = 0.2, g1 = 3000, g2 = 800": case.law_ii(g(3000), gd(800), alpha=0.2),
    }
    hw = case.hardware()
    variants = {
        "ideal": None,
        "hardware (all)": hw,
        "delay only": replace(hw, actuators={}, filters={}),
        "amplifier + filter, no delay": replace(hw, delay=0.0),
        "hardware, 500 Hz current loop": case.hardware(amplifier_bandwidth=500.0),
    }
    print("| run | hardware | settling 0.5° (s) | settling 1° (s) | overshoot (°) |")
    print("|---|---|---|---|---|")
    for name, law in laws.items():
        for label, h in variants.items():
            cfg = case.sim_config(15.0, hardware=h)
            a = simulate(case.model(), law, cfg).dataset
            b = simulate(case.model(), law, replace(cfg, settling_band=np.radians(1.0))).dataset
            ts05, os_ = _metrics(a, 0.5)
            ts1, _ = _metrics(b, 1.0)
            fmt = lambda v: "not settled" if not np.isfinite(v) else f"{v:.2f}"  # noqa: E731
            print(f"| {name} | {label} | {fmt(ts05)} | {fmt(ts1)} | {os_:.2f} |")


def nps_rows() -> None:
    """The three PD slews of examples/nps_pd_slews.yaml (60°, 20 Hz, gyro 1e-4 rad/s), with
    and without a 1 mN m cable torque, 120 s: settling, overshoot, final error."""
    case = nps()
    angle, inertia = case.slew_angle, case.design_inertia
    shapes = {
        "PD step": None,
        "PD + pseudo-square": PseudoSquare(angle, inertia, duration=10.0, rise_time=1.0),
        "PD + sinusoid": Sinusoidal(angle, inertia, duration=10.0),
    }
    print("| run | cable T_D | settling 0.5° (s) | overshoot (°) | error at 120 s (°) |")
    print("|---|---|---|---|---|")
    from flexsat.sim.sensors import Sensors

    for name, shape in shapes.items():
        for td in (0.0, 1e-3):
            dist = (
                {"torque": ChannelDisturbance(force=CableSpring(td), force_output="theta")}
                if td
                else {}
            )
            cfg = SimConfig(
                120.0,
                20.0,
                sensors=Sensors(rate="gyro", gyro_noise=1e-4),
                channel_disturbances=dist,
            )
            law = case.pd_gains(target=angle, reference=shape)
            run = simulate(case.model(), law, cfg).dataset
            ts, os_ = _metrics(run, 0.5)
            err = np.degrees(run["theta"].values[0, -200:].mean() - angle)
            print(f"| {name} | {td * 1e3:g} mN m | {ts:.1f} | {os_:.2f} | {err:.4f} |")


if __name__ == "__main__":
    tamu_rows()
    print()
    nps_rows()
