"""ERA's accuracy against measurement noise (flexsat.design.era_noise): on the TAMU grid's
first six modes (1 % damping), a hammer test at node 1 read by the 20 free nodes, the damping
error grows with the noise level."""

from __future__ import annotations

import numpy as np

from flexsat.cases.tamu_grid import tamu_grid
from flexsat.design.era_noise import noise_damping_sweep
from flexsat.identify import Channel
from flexsat.identify.excitation import impulse_hammer

NODES = range(1, 21)  # the 20 free nodes (21-25 are clamped)
DURATION, RATE = 40.0, 50.0


def test_the_damping_error_grows_with_the_noise():
    grid = tamu_grid().modal_model(6, damping=0.01)
    sensors = [Channel.at("displacement", n, "z") for n in NODES]
    sweep = noise_damping_sweep(
        grid, [0.001, 0.01, 0.05], sensors, impulse_hammer(1, "z", 10.0), DURATION, RATE, seeds=(0,)
    )
    mean = sweep["damping_error"].mean(axis=1)
    assert sweep["damping_error"].shape == (3, 6)
    assert sweep["frequency_error"].shape == (3, 6)
    assert np.all(np.diff(mean) > 0)
