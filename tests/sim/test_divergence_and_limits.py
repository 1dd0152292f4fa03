"""Claims: a diverging simulation stops and says which case, when and why (never a NaN result);
a run beyond flexsat.limits is refused before it starts, naming the field and the limit."""

import dataclasses
import time

import numpy as np
import pytest

from flexsat import limits
from flexsat.control import PD
from flexsat.sim import BearingFriction, SimConfig, SimulationDiverged, simulate
from flexsat.sim.engine import DIVERGENCE_BOUND


@pytest.fixture(scope="module")
def plant(tamu_case):
    return tamu_case.model()


def test_destabilising_gains_raise_instead_of_returning_nan(tamu_case, plant):
    # kd dt / I ≈ 1e7 / 75 / 1.6 ≫ 2: the sampled rate loop multiplies θ' by ~ -1e5 per period
    with pytest.raises(SimulationDiverged) as info:
        simulate(plant, PD(1e9, 1e7, target=tamu_case.angle), SimConfig(duration=15.0))
    error = info.value
    assert error.cases == (0,)
    assert 0 < error.time < 1.0  # found within a few samples, not after 15 s of overflow
    message = str(error)
    assert message.startswith(f"simulation diverged at t = {error.time:.6g} s")
    assert "case(s) 0" in message
    assert "the feedback gains destabilise it at the 75 Hz control rate" in message
    assert "Nyquist frequency 37.5 Hz" in message


def test_batch_names_only_the_diverging_case(tamu_case, plant):
    law = PD(np.array([5.0, 1e9, 5.0]), np.array([20.0, 1e7, 20.0]), target=tamu_case.angle)
    with pytest.raises(SimulationDiverged) as info:
        simulate(plant, law, SimConfig(duration=2.0))
    assert info.value.cases == (1,)


def test_stable_batch_runs_to_finite_results(tamu_case, plant):
    result = simulate(
        plant, PD(np.array([5.0, 10.0]), 20.0, target=tamu_case.angle), SimConfig(duration=2.0)
    )
    assert np.isfinite(result.dataset["theta"].values).all()


class _NaNCommand:
    """A PD law whose command is NaN from the second sample on (a broken control law)."""

    def __init__(self, law):
        self._law = law

    def __getattr__(self, name):
        return getattr(self._law, name)

    def __call__(self, t, y, state):
        u, state = self._law(t, y, state)
        return (u if t == 0 else np.full_like(np.asarray(u, float), np.nan)), state


def test_non_finite_command_from_a_finite_state_blames_the_law(tamu_case, plant):
    with pytest.raises(SimulationDiverged, match="control law returned a non-finite torque"):
        simulate(plant, _NaNCommand(PD(5.0, 20.0, target=tamu_case.angle)), SimConfig(duration=1.0))


def test_non_finite_start_is_an_input_error(tamu_case, plant):
    law = PD(5.0, 20.0, target=tamu_case.angle)
    with pytest.raises(ValueError, match=r"^theta: must be finite"):
        plant.state_from(theta=float("nan"))
    state = np.zeros(plant.nx)
    state[1] = np.inf
    with pytest.raises(ValueError, match=r"^initial_state: must be finite"):
        simulate(plant, law, SimConfig(duration=1.0), initial_state=state)


def test_divergence_bound_leaves_room_for_energies(plant):
    # energies are quadratic in the state: at the bound they must still be finite
    x = np.full((1, plant.nx), DIVERGENCE_BOUND)
    assert np.isfinite(plant.energy(x)).all()


# -- resource limits ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "kwargs, message",
    [
        (
            dict(duration=1e12),
            r"^duration: control samples \(duration × control_rate\) = 7\.5e\+13, "
            r"above the limit 2,000,000",
        ),
        (
            dict(duration=1.0, seed=1e29),
            r"^seed: must be an integer in \[0, 4294967295\], got 1e\+29",
        ),
        (dict(duration=1.0, seed=10**29), r"^seed: must be an integer in \[0, 4294967295\]"),
        (dict(duration=1.0, seed=-1), r"^seed: must be an integer"),
        (dict(duration=1.0, substeps=10**6), r"^substeps: .* above the limit 1,000"),
    ],
)
def test_config_beyond_the_limits_is_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SimConfig(**kwargs)


def test_stiff_friction_is_refused_before_it_hangs(tamu_case, plant):
    config = dataclasses.replace(tamu_case.sim_config(15.0), friction=BearingFriction(1e30, 0.0))
    start = time.perf_counter()
    with pytest.raises(
        ValueError,
        match=r"^friction: a stable integration of the friction .* "
        r"above the limit 1,000 .*raise smoothing",
    ):
        simulate(plant, PD(5.0, 20.0, target=tamu_case.angle), config)
    assert time.perf_counter() - start < 5.0  # refused up front (was an unbounded loop)


def test_memory_estimate_is_checked_before_allocating(tamu_case, plant, monkeypatch):
    law = PD(5.0, 20.0, target=tamu_case.angle)
    # 1 s at 75 Hz = 76 samples; 1,000 cases of 13 histories kept once, plus the loop's
    # 32-sample buffer of 22 states and 3 noise streams, 8 B each:
    # 8 × 1000 × (76 × 13 + 32 × 25) = 14,304,000 B = 13.6 MiB, one byte over the patched limit
    monkeypatch.setattr(limits, "MAX_MEMORY", 8 * 1000 * (76 * 13 + 32 * 25) - 1)
    with pytest.raises(
        ValueError,
        match=r"^duration: a run of 76 samples × 1000 cases × 13 "
        r"values \(and a 32-sample buffer of 25\) needs about "
        r"13.6 MB of memory, above the limit",
    ):
        simulate(plant, law, SimConfig(duration=1.0), n_cases=1000)
    with pytest.raises(
        ValueError,
        match=r"^n_cases: cases in one batch = 1e\+05.* above the "
        r"limit 100,000",
    ):
        simulate(plant, law, SimConfig(duration=1.0), n_cases=limits.MAX_CASES + 1)


def test_modes_beyond_the_limit_are_refused_before_the_model_is_built(tamu_case):
    from flexsat.cases import tamu

    with pytest.raises(
        ValueError,
        match=r"^n_modes: modes per appendage = 1e\+05, above the "
        r"limit 100",
    ):
        tamu(n_modes=100_000).model()


def test_a_divergence_in_a_chunk_is_named_by_the_batch_s_case_numbers():
    from flexsat.sim.engine import SimulationDiverged, offset_cases

    local = SimulationDiverged(
        "simulation diverged at t = 1 s (sample 75) in case(s) 0, 4: a state entry ...",
        (0, 4),
        1.0,
        "unstable",
    )
    batch = offset_cases(local, 1000)
    assert batch.cases == (1000, 1004) and (batch.time, batch.cause) == (1.0, "unstable")
    assert "in case(s) 1000, 1004: a state entry" in str(batch)
