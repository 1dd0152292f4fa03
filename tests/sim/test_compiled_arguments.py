"""The compiled loop's arguments (flexsat.sim.compiled_arguments): the modal coordinates are
taken where propagating them pays (the step-count rule), x = T z diagonalises the hybrid
plant's linear part into 2 × 2 blocks of its own frequencies and damping, and a dispersed
plant's cases each get their own, equal to the case alone.

Tolerances: T⁻¹ A T against the blocks to 16 n cond(T) eps of ‖A‖ (a product's round-off)."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.cases.tamu import tamu
from flexsat.dynamics.dispersion import stack_plants
from flexsat.sim.compiled_arguments import MODAL_STEPS, channel_width, modal_form

pytestmark = pytest.mark.numerics

EPS = np.finfo(float).eps


def _hub(hub_inertia="50 ozf*in*s**2"):
    return tamu(hub_inertia=hub_inertia).model()


def test_few_steps_keep_the_dense_form_and_many_take_the_modal_one():
    plant = _hub()
    assert modal_form(plant, MODAL_STEPS - 1) is None
    assert modal_form(plant, MODAL_STEPS) is not None


def test_t_makes_the_linear_part_blocks_of_its_frequencies_and_damping():
    """T⁻¹ A T = diag([[0, 1], [−ω², −2ζω]] ...) with the returned ω, ζ (a rigid pair ω = 0)."""
    plant = _hub()
    T, Ti, w, zeta = modal_form(plant, MODAL_STEPS)
    A, _ = plant.linear_part()
    n = A.shape[0]
    Az = Ti @ A @ T
    want = np.zeros_like(Az)
    for k, (wk, zk) in enumerate(zip(w, zeta)):
        want[2 * k, 2 * k + 1] = 1.0
        want[2 * k + 1, 2 * k] = -(wk**2)
        want[2 * k + 1, 2 * k + 1] = -2 * zk * wk
    bound = 16 * n * np.linalg.cond(T) * EPS * np.abs(A).max()
    assert np.abs(Az - want).max() <= bound
    assert np.abs(T @ Ti - np.eye(n)).max() <= 16 * n * np.linalg.cond(T) * EPS


def test_a_dispersed_plant_gets_each_cases_own_coordinates_equal_to_the_case_alone():
    plants = [_hub(f"{h} ozf*in*s**2") for h in (45.0, 50.0, 55.0)]
    stacked = modal_form(stack_plants(plants), MODAL_STEPS)
    assert stacked is not None and stacked[0].ndim == 3
    for c, p in enumerate(plants):
        alone = modal_form(p, MODAL_STEPS)
        np.testing.assert_allclose(stacked[2][c], alone[2], rtol=1e-12)
        np.testing.assert_allclose(
            np.abs(stacked[0][c]), np.abs(alone[0]), rtol=0, atol=1e-12 * np.abs(alone[0]).max()
        )


def test_channel_width_is_the_output_channels_size():
    from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft

    plant = RigidSpacecraft(np.diag([1.0, 2.0, 3.0]))
    widths = {c.name: channel_width(plant, c.name) for c in plant.outputs}
    assert widths["attitude"] == 4 and widths["rate"] == 3
