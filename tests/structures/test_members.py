"""Members and their element blocks (flexsat.structures.members) against textbook matrices."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.structures.members import (
    KIND_BUILDERS,
    Member,
    axial_force,
    member_masses,
    with_properties,
)

EPS = np.finfo(float).eps
# an aluminium tube-like section: E, G (Pa), ρ (kg/m³), A (m²), Iy, Iz, J (m⁴)
E, G, RHO, A, IY, IZ, J = 70e9, 26e9, 2700.0, 3e-4, 2e-8, 5e-8, 6e-8
L = 1.5


def _frame(offsets=None, G_per_E=None, orientation=(0.0, 1.0, 0.0)) -> Member:
    """Along global x with local y = global Y (orientation vector v in the local x-y plane)."""
    props = dict(E=E, G=G, G_per_E=G_per_E, rho=RHO, A=A, Iy=IY, Iz=IZ, J=J)
    props.update(orientation=orientation, offsets=offsets, lumped=False)
    return Member("frame", 0, 2, props)


XYZ = np.array([[0.0, 0.0, 0.0], [9.0, 9.0, 9.0], [L, 0.0, 0.0]])


def test_one_frame_member_s_block_is_the_textbook_12_by_12_stiffness():
    """A member along global x with v = global Y (local = global axes): the Euler–Bernoulli
    space-frame entries (J. S. Przemieniecki, *Theory of Matrix Structural Analysis*,
    McGraw-Hill 1968, ch. 5):
    EA/L, 12EI/L³, ±6EI/L², 4EI/L, 2EI/L, GJ/L, with the signs of right-handed rotations
    (θ_y = −w′, so the w–θ_y coupling is −6EI_y/L²); I_z bends in the local x-y plane.
    Tolerance: a few ε of each entry (the transformation is the identity)."""
    slots, K, _ = KIND_BUILDERS["frame"]([_frame()], XYZ, False)
    assert slots.tolist() == [[0, 1, 2, 3, 4, 5, 12, 13, 14, 15, 16, 17]]
    k = K[0]
    expected = {
        (0, 0): E * A / L,
        (0, 6): -E * A / L,
        (1, 1): 12 * E * IZ / L**3,
        (1, 5): 6 * E * IZ / L**2,
        (1, 7): -12 * E * IZ / L**3,
        (1, 11): 6 * E * IZ / L**2,
        (2, 2): 12 * E * IY / L**3,
        (2, 4): -6 * E * IY / L**2,
        (2, 10): -6 * E * IY / L**2,
        (3, 3): G * J / L,
        (3, 9): -G * J / L,
        (4, 4): 4 * E * IY / L,
        (4, 10): 2 * E * IY / L,
        (5, 5): 4 * E * IZ / L,
        (5, 11): 2 * E * IZ / L,
        (11, 11): 4 * E * IZ / L,
        (6, 6): E * A / L,
        (7, 7): 12 * E * IZ / L**3,
        (8, 8): 12 * E * IY / L**3,
        (9, 9): G * J / L,
        (10, 10): 4 * E * IY / L,
        (7, 11): -6 * E * IZ / L**2,
        (8, 10): 6 * E * IY / L**2,
        (2, 8): -12 * E * IY / L**3,
        (4, 8): 6 * E * IY / L**2,
        (5, 7): -6 * E * IZ / L**2,
    }  # upper triangle; every other entry is 0
    full = np.zeros((12, 12))
    for (i, j), v in expected.items():
        full[i, j] = full[j, i] = v
    assert np.allclose(k, full, rtol=10 * EPS, atol=0)


def test_the_default_orientation_puts_local_y_along_global_z():
    """No orientation: v = global Z (NASTRAN CBAR style), so local y = Z and local z = x × Z =
    −Y: I_z then bends the member in the global x-Z plane (12 E I_z / L³ on u_z)."""
    _, K, _ = KIND_BUILDERS["frame"]([_frame(orientation=None)], XYZ, False)
    assert K[0][2, 2] == pytest.approx(12 * E * IZ / L**3, rel=10 * EPS)
    assert K[0][1, 1] == pytest.approx(12 * E * IY / L**3, rel=10 * EPS)


def test_a_rigid_translation_carries_the_member_s_mass_rho_a_l():
    """uᵀ M u = ρ A L for a unit translation (consistent and lumped mass alike)."""
    u = np.zeros(12)
    u[[1, 7]] = 1.0
    for lumped in (False, True):
        member = _frame()
        member.props["lumped"] = lumped
        _, _, M = KIND_BUILDERS["frame"]([member], XYZ, False)
        assert u @ M[0] @ u == pytest.approx(RHO * A * L, rel=10 * EPS)
    assert member_masses([_frame()], XYZ) == pytest.approx([RHO * A * L], rel=EPS)


def test_offsets_set_the_length_between_the_member_ends():
    """Rigid offsets of 0.25 m inward at both ends: the flexible length is L − 0.5 m, so the
    mass is ρ A (L − 0.5) and the axial stiffness EA / (L − 0.5)."""
    off = np.array([[0.25, 0.0, 0.0], [-0.25, 0.0, 0.0]])
    assert member_masses([_frame(off)], XYZ) == pytest.approx([RHO * A * (L - 0.5)], rel=4 * EPS)
    _, K, _ = KIND_BUILDERS["frame"]([_frame(off)], XYZ, False)
    assert K[0][0, 0] == pytest.approx(E * A / (L - 0.5), rel=10 * EPS)


def test_axial_force_of_a_stretched_member_is_ea_delta_over_l():
    """End 2 moved δ along the axis (and both ends moved sideways, which carries no force)."""
    d = np.zeros((3, 6))
    d[2, 0] = 1e-4
    d[:, 1] = 3e-3
    assert axial_force(_frame(), XYZ, d) == pytest.approx(E * A * 1e-4 / L, rel=1e-12)


def test_a_tied_shear_modulus_follows_a_new_young_s_modulus():
    """with_properties: G = E · G/E when G is tied (no G given), untouched otherwise."""
    tied = with_properties(_frame(G_per_E=G / E), {"E": 2 * E})
    assert tied.props["E"] == 2 * E and tied.props["G"] == pytest.approx(2 * G, rel=EPS)
    free = with_properties(_frame(), {"E": 2 * E})
    assert free.props["G"] == G
