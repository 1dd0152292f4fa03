"""Shared pieces of the perturbation-feedback tests (seed 003 F8-F12): a rigid three-axis
nominal slew, the rebuilt EPS plants and a small flexible model whose modes couple to the
rigid rotation."""

import numpy as np
import pytest

from eigenaxis_slew import EigenaxisSlew
from flexsat.structures.modal_model import ModalModel


def coupled_modal(damping=0.005):
    """Four elastic modes (0.4-2.3 Hz, 0.5 % damping as the EPS) with rotational participation
    Δ ≠ 0, as modes of appendages cantilevered to a hub are: the rigid rotation and the modes
    are coupled, so the rigid nominal torque leaves the flexible vehicle off target (unlike
    exact free-free modes, for which Δ = 0 and the rotation is the rigid body's). Three
    nodes carry forces and displacement outputs."""
    J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
    rigid = np.zeros((6, 6))
    rigid[:3, :3] = 300.0 * np.eye(3)
    rigid[3:, 3:] = J
    participation = np.zeros((4, 6))
    participation[:, 3:] = [[3.0, 0.5, 0.0], [0.0, 4.0, 1.0], [1.0, 0.0, 5.0], [2.0, 2.0, 2.0]]
    shapes = 0.1 * np.random.default_rng(3).standard_normal((4, 3, 6))
    return ModalModel(
        node_ids=[1, 2, 3],
        coordinates=[[2.0, 0, 0], [0, 3.0, 0], [0, 0, -1.0]],
        frequencies=2 * np.pi * np.array([0.4, 0.9, 1.7, 2.3]),
        damping=damping,
        shapes=shapes,
        rigid_mass=rigid,
        participation=participation,
    )


@pytest.fixture(scope="session")
def eigenaxis_slew():
    """The class :class:`EigenaxisSlew` (a nominal factory)."""
    return EigenaxisSlew


@pytest.fixture(scope="session")
def coupled_model():
    """:func:`coupled_modal`: forces and outputs at nodes 1-3."""
    return coupled_modal()


@pytest.fixture(scope="session")
def eps_case():
    from flexsat.cases.eps import eps

    return eps()


@pytest.fixture(scope="session")
def eps_truth_plant(eps_case):
    """The paper's simulation model: 45 elastic modes, torquers at the CG node loading them,
    the final 7 forces, the rim displacements."""
    return eps_case.plant(n_modes=45)


@pytest.fixture(scope="session")
def eps_design_plant(eps_truth_plant):
    """The paper's controller model: the first 10 of the truth model's modes, from the same
    modal model (a separate 10-mode eigen-solution may rotate the repeated antenna pairs)."""
    return eps_truth_plant.reduced(10)
