"""Shared pieces of the perturbation-feedback tests (seed 003 F8-F12): a rigid three-axis
nominal slew, the rebuilt EPS plants and a small flexible model whose modes couple to the
rigid rotation."""

import numpy as np
import pytest

from flexsat.structures.modal_model import ModalModel


class EigenaxisSlew:
    """Rest-to-rest rotation by ``angle`` about a fixed body axis e in ``duration`` s, an exact
    rigid nominal for any inertia J (the three-axis TPBVP nominal of seed 003 stands in here).

    θ(τ) = Θ(35τ⁴ − 84τ⁵ + 70τ⁶ − 20τ⁷), τ = t/T: rate, acceleration and jerk vanish at both
    ends, so the torque starts and ends at zero as the paper's does (L827-L829). About a fixed
    axis the body and inertial components of e agree, so β = [cos θ/2, e sin θ/2], ω = θ̇ e and
    Euler's equation gives τ = J e θ̈ + ω × Jω (seed 003 Eq. 12).
    """

    def __init__(self, inertia, axis, angle, duration):
        self.inertia = np.asarray(inertia, float)
        self.axis = np.asarray(axis, float) / np.linalg.norm(axis)
        self.angle, self.duration = float(angle), float(duration)

    def _profile(self, t):
        s = np.clip(np.asarray(t, float) / self.duration, 0.0, 1.0)
        T, a = self.duration, self.angle
        return (
            a * (35 * s**4 - 84 * s**5 + 70 * s**6 - 20 * s**7),
            a * (140 * s**3 - 420 * s**4 + 420 * s**5 - 140 * s**6) / T,
            a * (420 * s**2 - 1680 * s**3 + 2100 * s**4 - 840 * s**5) / T**2,
        )

    def beta(self, t):
        theta = self._profile(t)[0][..., None]
        return np.concatenate([np.cos(theta / 2), np.sin(theta / 2) * self.axis], -1)

    def omega(self, t):
        return self._profile(t)[1][..., None] * self.axis

    def torque(self, t):
        _, rate, acc = self._profile(t)
        w = rate[..., None] * self.axis
        return acc[..., None] * (self.inertia @ self.axis) + np.cross(w, w @ self.inertia.T)


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
