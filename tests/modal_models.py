"""Small modal models shared by the tests of several packages."""

from __future__ import annotations

import numpy as np

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
