"""Issue #5 benchmarks: ERA on 10 outputs x 20,000 samples, calibration of two cameras with
50 targets, and the whole TAMU grid campaign of examples/tamu_grid_identification.yaml.
Plain script: `python benchmarks/bench_identify.py` prints a markdown table."""

from __future__ import annotations

import time

import numpy as np

from flexsat.cases import tamu_grid
from flexsat.identify import (
    Channel,
    calibrate,
    era,
    impulse_hammer,
    markov_parameters,
    simulate_centroids,
    simulate_test,
)
from flexsat.identify.photogrammetry import Camera, look_at


def best_of(fn, repeat=3):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def era_case():
    grid = tamu_grid().modal_model(6, damping=0.01)
    sensors = [Channel("displacement", n, "z") for n in (1, 2, 3, 4, 5, 6, 8, 10, 12, 14)]
    meas = simulate_test(
        grid, impulse_hammer(1, "z", 10.0), sensors, 400.0, 50.0, noise=0.01, seed=0
    )  # 20,000 samples
    markov = markov_parameters(meas)
    t, real = best_of(lambda: era(markov, dt=meas.dt, order=12))
    err = np.abs(np.sort(real.frequencies)[:6] / (grid.frequencies_hz[:6]) - 1).max()
    return meas.outputs.shape, t, err


def calibration_case(n_targets=50):
    px, f = 1e-5, 0.004
    cams = [
        Camera(position=p, angles=look_at(p, aim), f=f)
        for p, aim in (([-1.3, 0.2, 2.0], [0.0, 0.15, 0.0]), ([1.3, -0.2, 2.0], [0.0, -0.15, 0.0]))
    ]
    rng = np.random.default_rng(1)
    pts = np.column_stack(
        [
            rng.uniform(-0.35, 0.35, n_targets),
            rng.uniform(-0.3, 0.3, n_targets),
            rng.uniform(-0.4, 0.4, n_targets),
        ]
    )
    obs = simulate_centroids(cams, pts, px, 0.1, quantize=False, seed=0)
    guess = pts + rng.normal(0, 3e-4, pts.shape)
    init = [
        c.with_vector(
            c.vector()
            + np.r_[rng.normal(0, 0.02, 3), rng.normal(0, 0.01, 3), np.zeros(c.vector().size - 6)]
        )
        for c in cams
    ]
    t, res = best_of(
        lambda: calibrate(
            obs, init, guess, datum=None, scale=None, sigma=0.1 * px, target_sigma=3e-4
        ),
        repeat=2,
    )
    # camera position error in units of its own estimated standard deviation
    z = max(
        np.abs(np.subtract(a.position, b.position)).max()
        / max(res.std(f"cam{j}.{c}") for c in ("xc", "yc", "zc"))
        for j, (a, b) in enumerate(zip(res.cameras, cams))
    )
    return t, z, res.result.status, res.sigma0_squared


def campaign_case():
    from pathlib import Path

    from flexsat.scenarios import load_scenario, run_scenario

    spec = load_scenario(
        Path(__file__).resolve().parents[1] / "examples" / "tamu_grid_identification.yaml"
    )
    t, result = best_of(lambda: run_scenario(spec), repeat=2)
    return t, result.campaign.scalings["clamp verticals"]["updated"]


if __name__ == "__main__":
    shape, t_era, err = era_case()
    t_cal, z, status, s0 = calibration_case()
    t_campaign, clamp = campaign_case()
    print("| benchmark | size | time (s) | accuracy |")
    print("|---|---|---|---|")
    print(
        f"| ERA (order 12) | {shape[0]} outputs x {shape[1]} samples | {t_era:.3f} | "
        f"max frequency error {100 * err:.4f} % |"
    )
    print(
        f"| calibration, 2 cameras x 9 parameters | 50 targets, 0.1 px | {t_cal:.3f} | "
        f"camera position error {z:.2f} sigma, s0^2 = {s0:.2f}, solver status {status} |"
    )
    print(
        f"| TAMU grid campaign (examples/tamu_grid_identification.yaml) | hammer 20 s, video "
        f"900 fields x 20 targets, wheels 60,000 samples | {t_campaign:.2f} | clamp stiffness "
        f"on the truth after the update {clamp:.5f} |"
    )
