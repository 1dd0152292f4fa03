"""Claim of the recording: a TAMU maneuver (10 modes per appendage, 15 s at 75 Hz, friction and
noise on) costs at most 150 kB per case in a batch (issue 10; 326 kB before the rewrite)."""

import tracemalloc

import numpy as np

from flexsat.sim import simulate
from flexsat.sim.engine import check_resources
from flexsat.units import to_si


def test_a_batch_maneuver_fits_in_150_kB_per_case(tamu_case):
    """Peak traced memory of a 200-case Law II batch, per case: the 13 recorded histories of
    1,126 samples (117 kB), the law's reference table (37 kB, two of its rows are the recorded
    references) and the loop's 32-sample buffer of states; measured 147 kB. The estimate of
    check_resources counts the recorded histories and the buffer."""
    model, n = tamu_case.model(), 200
    law = tamu_case.law_ii(to_si("3000 ozf*in/rad", "N*m/rad"),
                           to_si("800 ozf*in*s/rad", "N*m*s/rad"),
                           alpha=np.linspace(0.05, 0.2, n))
    cfg = tamu_case.sim_config(15.0)
    simulate(model, law, cfg)  # imports and caches outside the measurement
    tracemalloc.start()
    try:
        simulate(model, law, cfg)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak / n <= 150e3
    assert check_resources(model, cfg, n) == 4
