"""The structures tested on their own as plants: a point force, displacement sensors, the
modal model of their first modes."""

import numpy as np
import pytest

from flexsat.cases import cantilever_beam, free_free_beam, nafems_fv2, tamu_grid


@pytest.mark.parametrize("case", [cantilever_beam, free_free_beam, nafems_fv2, tamu_grid])
def test_plant_frequencies_are_the_cases_own(case):
    """The plant's modal blocks carry the case's FE frequencies; a free beam's six rigid
    modes come first at 0 (its ``frequencies_hz`` lists the elastic ones)."""
    c = case()
    plant = c.plant(n_modes=8)
    w = plant.modal_blocks.frequencies
    rigid = plant.modal_blocks.n_rigid
    assert rigid == (6 if case is free_free_beam else 0)
    np.testing.assert_allclose(w[rigid:] / (2 * np.pi), c.frequencies_hz(8)[: 8 - rigid], rtol=1e-9)
    assert [ch.name for ch in plant.inputs] == ["force"]


def test_static_tip_deflection_of_the_cantilever_is_pl3_over_3ei():
    """A tip force P on the cantilever: the modal plant's static tip deflection tends to
    P L³ / (3 EI) (Euler–Bernoulli); 8 modes leave the truncation error of the modal sum,
    Σ_{r>8} φ_r(L)²/ω_r², below 1e-3 of it."""
    c = cantilever_beam()
    plant = c.plant(n_modes=8)
    A, B = plant.linear_part()
    x_static = -np.linalg.solve(A, B[:, 0])
    C, _, _ = plant.output_matrices(f"displacement_{c.n_elements}")
    expected = c.length**3 / (3 * min(c.E * c.section.Iy, c.E * c.section.Iz))
    assert abs((C @ x_static)[0] - expected) <= 1e-3 * expected


def test_bad_plant_options_name_the_field():
    with pytest.raises(ValueError, match="n_modes"):
        cantilever_beam().plant(n_modes=0)
    with pytest.raises(ValueError, match="plane: the plant is built on the in-plane model"):
        nafems_fv2(plane="3d").plant()
    with pytest.raises(ValueError, match="sensor_nodes: node 999"):
        tamu_grid().plant(sensor_nodes=(999,))
