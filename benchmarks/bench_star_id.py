"""Issue 14 benchmark: lost-in-space star identifications per second (two fields of view) with
the k-vector pair index against the brute-force scan, side by side in one run.

Same frames for both matchers: seeded random attitudes of the synthetic sky (5,000 stars to
m = 6.5), two 12° cameras 90° apart (4096 px), 0.1-pixel centroid noise, 2 false stars and 20 %
missing stars per frame. Timed: `StarTracker.identify` (pair look-ups, voting, triplet check,
q-method and residual check), not the frame simulation. Plain script:
`python benchmarks/bench_star_id.py [n_attitudes]` prints a markdown table."""

from __future__ import annotations

import os
import platform
import sys
import time

import numpy as np

from flexsat.attitude.star_camera import StarCamera
from flexsat.attitude.star_catalog import synthetic_sky
from flexsat.attitude.star_tracker import StarTracker, random_attitudes, score


def main(n: int = 200) -> None:
    sky = synthetic_sky(6.5, seed=0)
    cams = (StarCamera(), StarCamera(mounting=(0.0, np.pi / 2, 0.0)))
    t0 = time.perf_counter()
    trackers = {
        "k-vector": StarTracker(cams, sky, index="kvector"),
        "brute force": StarTracker(cams, sky, index="brute"),
    }
    build = time.perf_counter() - t0
    rng = np.random.default_rng(7)
    frames = [trackers["k-vector"].observe(C, rng, 2, 0.2) for C in random_attitudes(n, 7)]
    rows = {}
    for name, tr in trackers.items():
        best = np.inf
        for _ in range(3 if name == "k-vector" else 1):
            t0 = time.perf_counter()
            idents = [tr.identify(f) for f in frames]
            best = min(best, time.perf_counter() - t0)
        correct = sum(score(i, f)[0] for i, f in zip(idents, frames))
        rows[name] = (best, correct)
    load = os.getloadavg()
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python "
        f"{sys.version.split()[0]}, NumPy {np.__version__}; load {load[0]:.2f}; "
        f"{len(sky)} stars, {len(trackers['k-vector'].index)} pairs; both indexes built in "
        f"{build:.2f} s"
    )
    print("\n| matcher | attitudes | correct | time (s) | identifications / s | ms each |")
    print("|---|---|---|---|---|---|")
    for name, (t, c) in rows.items():
        print(f"| {name} | {n} | {c} | {t:.3f} | {n / t:.1f} | {1e3 * t / n:.2f} |")
    ratio = rows["brute force"][0] / rows["k-vector"][0]
    print(f"\nk-vector speed-up over brute force: {ratio:.1f}×")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 200)
