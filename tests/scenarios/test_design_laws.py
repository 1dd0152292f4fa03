"""The law-design stage of a design study (flexsat.scenarios.design_laws) on a decoupled body."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
from flexsat.scenarios.design_laws import LawSpec, design_law, design_state
from flexsat.structures.modal_model import ModalModel

J = np.array([100.0, 150.0, 200.0])  # principal inertias, kg m²
OMEGA = 2 * np.pi * np.array([0.4, 0.9, 1.7])  # elastic modes, rad/s
ZETA = 0.01


def _plant() -> FlexibleSpacecraft:
    """A rigid body with principal axes and three elastic modes of zero participation: the
    rigid and elastic motions do not couple through the mass matrix."""
    rigid = np.zeros((6, 6))
    rigid[:3, :3] = 300.0 * np.eye(3)
    rigid[3:, 3:] = np.diag(J)
    model = ModalModel(
        node_ids=[1, 2],
        coordinates=[[2.0, 0, 0], [0, 3.0, 0]],
        frequencies=OMEGA,
        damping=ZETA,
        shapes=0.1 * np.random.default_rng(5).standard_normal((3, 2, 6)),
        rigid_mass=rigid,
        participation=np.zeros((3, 6)),
    )
    return FlexibleSpacecraft(model, forces=[(2, "x")], torque_node=1)


def _pair(wn: float, zeta: float) -> np.ndarray:
    return wn * np.array([-zeta + 1j * np.sqrt(1 - zeta**2), -zeta - 1j * np.sqrt(1 - zeta**2)])


def test_the_design_state_drops_beta0():
    """[β_v, ω, η, η̇]: one state fewer than the plant, no torque or force lost."""
    plant = _plant()
    A, B = design_state(plant)
    assert A.shape == (plant.nx - 1, plant.nx - 1) and B.shape == (plant.nx - 1, 4)


@pytest.mark.parametrize("bandwidth, damping", [(0.3, 0.7), (1.2, 0.4)])
def test_pd_law_poles_are_the_requested_rigid_pairs_and_the_untouched_modes(bandwidth, damping):
    """Linearised, each axis is J θ'' + K_d θ' + K_p θ / 2 = 0 (β_v = θ/2), so the rigid poles
    are ω_c(−ζ ± j√(1−ζ²)) on all three axes; with no rigid–elastic coupling (Δ = 0) the
    closed loop is block triangular and the elastic poles stay at the modes' ω_i, ζ_i. No pole
    at 0: β₀ is out of the design state. Tolerance: eigenvalues of a block-triangular matrix
    with 2 × 2 non-normal blocks (cond ≲ 1/ζ), ~1e-13 relative; 1e-9 leaves margin."""
    arrays, _ = design_law(
        LawSpec(label="PD", type="pd", bandwidth=bandwidth, damping=damping), _plant(), 0.1
    )
    assert arrays["Kp"] == pytest.approx(2 * J * bandwidth**2, rel=1e-15)
    assert arrays["Kd"] == pytest.approx(2 * damping * bandwidth * J, rel=1e-15)
    expected = np.concatenate([_pair(bandwidth, damping)] * 3 + [_pair(w, ZETA) for w in OMEGA])
    got = list(arrays["poles"])
    assert len(got) == expected.size
    for pole in expected:  # match each expected pole to its own computed one
        k = int(np.argmin(np.abs(np.array(got) - pole)))
        assert abs(got.pop(k) - pole) <= 1e-9 * abs(pole)
    # sorted by real part, then imaginary
    assert np.all(np.diff(arrays["poles"].real) >= 0)
