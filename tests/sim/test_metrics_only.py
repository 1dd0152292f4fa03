"""``simulate(metrics_only=True)`` (issue 13, the sweep's fast path; flexsat.sim.compiled.
run_reduced): the single-axis maneuver metrics accumulated in the compiled loop, with no time
history, are the metrics of the full compiled run on the same propagation bit for bit; a case
run alone equals the same case in a batch bit for bit (the path does not depend on the batch
size); and they equal the general dense path (the Python loop's dense exponential) to the
round-off the modal change of coordinates allows.

The runs: the TAMU Law II slew of seed 000 Att. 3 §V (the conftest case), 15 s at 75 Hz, with
the bearing friction, the encoder quantisation and the random torque of the case's hardware
settings (every case its own noise seed) and a spread of (α, u_max).
"""

import numpy as np
import pytest

from flexsat.sim import simulate
from flexsat.sim.compiled import modal_form
from flexsat.units import to_si

EPS = np.finfo(float).eps
G1, G2 = to_si("3000 ozf*in/rad", "N*m/rad"), to_si("800 ozf*in*s/rad", "N*m*s/rad")
N = 24
ALPHA = np.linspace(0.02, 0.25, N)
U_MAX = to_si("1 ozf*in", "N*m") * np.linspace(200.0, 600.0, N)[::-1]
SEEDS = 1000 + np.arange(N)


@pytest.fixture(scope="module")
def runs(tamu_case):
    cfg = tamu_case.sim_config(duration=15.0)
    law = tamu_case.law_ii(G1, G2, alpha=ALPHA, u_max=U_MAX)
    plant = tamu_case.model()
    lean = simulate(plant, law, cfg, n_cases=N, seeds=SEEDS, metrics_only=True)
    full = simulate(plant, law, cfg, n_cases=N, seeds=SEEDS)
    return plant, cfg, lean, full


def test_metrics_only_keeps_no_history_and_equals_the_full_run_bit_for_bit(runs):
    """24 cases × 1,125 samples take the modal path in both runs (flexsat.sim.compiled.
    MODAL_STEPS); the reduced loop performs the full loop's operations in the same order, so
    every metric is the same float (NaN where NaN)."""
    _, _, lean, full = runs
    assert lean.dataset.attrs["histories"] == "none"
    assert lean.dataset.attrs["propagation"] == full.dataset.attrs["propagation"] == "modal"
    assert not [v for v in lean.dataset.data_vars if "time" in lean.dataset[v].dims]
    assert sorted(lean.metrics) == sorted(full.metrics)
    for name, value in full.metrics.items():
        assert np.array_equal(lean.metrics[name], value, equal_nan=True), name
    assert np.isfinite(lean.metrics["settling_time_s"]).sum() >= N // 2  # most settle


def test_a_case_alone_equals_the_case_in_the_batch_bit_for_bit(tamu_case, runs):
    """A one-case batch takes the same modal path (the full run would propagate it densely:
    1,125 steps are below MODAL_STEPS), so the sweep's case-alone acceptance (issue 13) holds
    exactly, whatever the chunking."""
    plant, cfg, lean, _ = runs
    for i in (0, N // 2, N - 1):
        law = tamu_case.law_ii(G1, G2, alpha=ALPHA[i], u_max=U_MAX[i])
        alone = simulate(plant, law, cfg, n_cases=1, seeds=SEEDS[i : i + 1], metrics_only=True)
        assert alone.dataset.attrs["propagation"] == "modal"
        for name, value in lean.metrics.items():
            assert np.array_equal(alone.metrics[name][0], value[i], equal_nan=True), name


def test_the_fast_path_equals_the_general_dense_path(tamu_case, runs):
    """The linear plant (the sweep benchmark's: no friction, ideal sensors, no random torque,
    where no quantisation decision can turn a round-off difference into a quantum) against
    the Python loop (dense exponential ZOH, every history recorded): each state
    carries the modal change of coordinates' error cond(T) eps per step (x = T z, z
    propagated exactly per 2×2 block), at most steps × cond(T) × eps of the state's scale
    after ``steps`` integrator steps; a metric is then within that of its own scale (the
    energies, quadratic, within twice that). The settling time is a sample index: the same
    sample unless |θ − θ_f| passes within that tolerance of the band at the last crossing."""
    plant = runs[0]
    cfg = tamu_case.sim_config(duration=15.0, friction=False, noise=False)
    law = tamu_case.law_ii(G1, G2, alpha=ALPHA, u_max=U_MAX)
    lean = simulate(plant, law, cfg, n_cases=N, seeds=SEEDS, metrics_only=True)
    dense = simulate(plant, law, cfg, n_cases=N, seeds=SEEDS, compiled=False)
    T = modal_form(plant, np.inf)[0]
    steps = dense.dataset.sizes["time"] * dense.dataset.attrs["substeps"]
    tol = steps * np.linalg.cond(T) * EPS
    assert tol < 1e-8  # the bound is meaningful: far below the metrics' resolution
    scale = {
        "overshoot_deg": np.degrees(np.abs(dense.dataset["theta"].values).max()),
        "peak_rate_error_deg_s": np.degrees(np.abs(dense.dataset["theta_dot"].values).max()),
        "residual_energy_J": 2 * np.abs(dense.dataset["energy"].values).max(),
        "residual_energy_at_T_J": 2 * np.abs(dense.dataset["energy"].values).max(),
    }
    for name, value in dense.metrics.items():
        if name == "settling_time_s":
            assert np.array_equal(lean.metrics[name], value, equal_nan=True)
            continue
        s = scale.get(name, np.abs(value).max())
        assert np.abs(lean.metrics[name] - value).max() <= tol * s, name
