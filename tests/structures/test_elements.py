"""Element matrices: symmetry, rigid-body null spaces, rigid-body mass properties, and an
independent derivation of the bending matrices by Gauss quadrature of the Hermite shape
functions.

Tolerances: every check compares quantities that are equal in exact arithmetic and computed
with O(10) floating-point operations per entry, so rtol 1e-12 relative to the matrix norm
(entries span EA/L ... 12 EI/L^3, a few orders of magnitude, well inside double precision).
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.structures import elements as el

rng = np.random.default_rng(7)
E, G, RHO = 70e9, 26e9, 2700.0
A, IY, IZ, J = 3e-4, 2e-8, 5e-8, 4e-8
RTOL = 1e-12


def skew(d):
    return np.array([[0, -d[2], d[1]], [d[2], 0, -d[0]], [-d[1], d[0], 0]])


def rigid_vectors(nodes, reference, rotations=True):
    """Rigid-body motions (t, theta) -> node dofs, (n_nodes * dofs, 6)."""
    blocks = []
    for x in nodes:
        top = np.hstack([np.eye(3), -skew(x - reference)])
        bottom = np.hstack([np.zeros((3, 3)), np.eye(3)])
        blocks.append(np.vstack([top, bottom]) if rotations else top)
    return np.vstack(blocks)


def random_frame():
    """Random member: node positions, rigid offsets, orientation vector, global T, length."""
    x1, x2 = rng.normal(size=3), rng.normal(size=3)
    offsets = 0.2 * rng.normal(size=(2, 3))
    v = rng.normal(size=3)
    e1, e2 = x1 + offsets[0], x2 + offsets[1]
    T = el.frame_transformation(el.frame_rotation(e1, e2, v), offsets)
    return x1, x2, e1, e2, T, np.linalg.norm(e2 - e1)


def rigid_mass_matrix(m, center, inertia_c, reference):
    """[[m I, m S(c - p)^T], [m S(c - p), I_p]] with the parallel-axis theorem."""
    a = center - reference
    Ip = inertia_c + m * (a @ a * np.eye(3) - np.outer(a, a))
    return np.block([[m * np.eye(3), m * skew(a).T], [m * skew(a), Ip]])


# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("trial", range(5))
def test_frame_stiffness_symmetric_with_six_rigid_null_vectors(trial):
    x1, x2, _, _, T, L = random_frame()
    K = el.to_global(el.frame_local_stiffness(E, G, A, IY, IZ, J, L), T)
    norm = np.abs(K).max()
    assert np.abs(K - K.T).max() <= RTOL * norm
    R = rigid_vectors([x1, x2], reference=rng.normal(size=3))
    assert np.abs(K @ R).max() <= 1e-10 * norm * np.abs(R).max()
    eig = np.linalg.eigvalsh(K)
    assert np.sum(eig > 1e-10 * norm) == 6  # exactly six deformation modes


def test_frame_transformation_is_orthogonal_without_offsets():
    R = el.frame_rotation(rng.normal(size=(4, 3)), rng.normal(size=(4, 3)), rng.normal(size=(4, 3)))
    T = el.frame_transformation(R)
    assert T.shape == (4, 12, 12)
    assert np.allclose(np.swapaxes(T, 1, 2) @ T, np.eye(12), atol=1e-14)
    assert np.allclose(np.linalg.det(R), 1.0, atol=1e-14)


def test_frame_rotation_conventions():
    # member along X, default v = Z: y = Z, z = x × Z = -Y
    assert np.allclose(el.frame_rotation([0, 0, 0], [2, 0, 0]), [[1, 0, 0], [0, 0, 1], [0, -1, 0]])
    # member along Z uses v = Y: z = Z × Y = -X, y = Y
    assert np.allclose(el.frame_rotation([0, 0, 0], [0, 0, 3]), [[0, 0, 1], [0, 1, 0], [-1, 0, 0]])
    # orientation v lies in the local x-y plane
    R = el.frame_rotation([0, 0, 0], [1, 1, 0], [0, 0, 5])
    assert np.isclose(R[2] @ [0, 0, 1], 0.0)
    with pytest.raises(ValueError, match="orientation: must not be parallel"):
        el.frame_rotation([0, 0, 0], [1, 1, 0], [2, 2, 0])


@pytest.mark.parametrize("trial", range(3))
def test_frame_consistent_mass_reproduces_rigid_body_inertia(trial):
    """R^T M R = mass, first moment and inertia of a slender bar (m L^2/12 transverse about its
    centre) plus the torsional inertia rho (Iy + Iz) L about its axis (no section rotary
    inertia in bending: Euler-Bernoulli)."""
    x1, x2, e1, e2, T, L = random_frame()
    M = el.to_global(el.frame_local_mass(RHO, A, IY, IZ, L), T)
    p = rng.normal(size=3)
    R = rigid_vectors([x1, x2], p)
    m, axis = RHO * A * L, (e2 - e1) / L
    along = np.outer(axis, axis)
    Ic = m * L**2 / 12 * (np.eye(3) - along) + RHO * (IY + IZ) * L * along
    expected = rigid_mass_matrix(m, (e1 + e2) / 2, Ic, p)
    assert np.allclose(R.T @ M @ R, expected, rtol=0, atol=RTOL * np.abs(expected).max())
    assert np.abs(M - M.T).max() <= RTOL * np.abs(M).max()
    assert np.linalg.eigvalsh(M).min() > 0


def test_frame_lumped_mass_hrz():
    """HRZ: exact mass and centre; transverse inertia m L^2/4 + 2 m L^2/78 about the centre."""
    x1, x2 = np.zeros(3), np.array([1.5, 0.0, 0.0])
    L = 1.5
    Ml = el.frame_local_mass(RHO, A, IY, IZ, L, lumped=True)
    assert np.count_nonzero(Ml - np.diag(np.diag(Ml))) == 0
    T = el.frame_transformation(el.frame_rotation(x1, x2))
    R = rigid_vectors([x1, x2], reference=np.zeros(3))
    m = RHO * A * L
    transverse = m * L**2 / 4 + 2 * m * L**2 / 78
    Ic = np.diag([RHO * (IY + IZ) * L, transverse, transverse])
    expected = rigid_mass_matrix(m, (x1 + x2) / 2, Ic, np.zeros(3))
    got = R.T @ el.to_global(Ml, T) @ R
    assert np.allclose(got, expected, rtol=0, atol=RTOL * np.abs(expected).max())


# ------------------------------------------------------------------------------------------------
# independent derivation of the x-y bending blocks: Gauss quadrature of Hermite cubics
def hermite(xi, L):
    """Shape functions and their 1st and 2nd x-derivatives, dofs (v1, theta1, v2, theta2)."""
    N = np.array(
        [
            1 - 3 * xi**2 + 2 * xi**3,
            L * (xi - 2 * xi**2 + xi**3),
            3 * xi**2 - 2 * xi**3,
            L * (-(xi**2) + xi**3),
        ]
    )
    dN = (
        np.array(
            [
                -6 * xi + 6 * xi**2,
                L * (1 - 4 * xi + 3 * xi**2),
                6 * xi - 6 * xi**2,
                L * (-2 * xi + 3 * xi**2),
            ]
        )
        / L
    )
    d2N = np.array([-6 + 12 * xi, L * (-4 + 6 * xi), 6 - 12 * xi, L * (-2 + 6 * xi)]) / L**2
    return N, dN, d2N


def quadrature(L, which):
    pts, wts = np.polynomial.legendre.leggauss(6)
    out = np.zeros((4, 4))
    for p, w in zip((pts + 1) / 2, wts / 2):
        f = hermite(p, L)[which]
        out += w * L * np.outer(f, f)
    return out


XY = [1, 5, 7, 11]


def test_bending_matrices_match_quadrature_of_hermite_shape_functions():
    L, N = 0.7, -3.0e4
    K = el.frame_local_stiffness(E, G, A, IY, IZ, J, L)[np.ix_(XY, XY)]
    M = el.frame_local_mass(RHO, A, IY, IZ, L)[np.ix_(XY, XY)]
    Kg = el.frame_local_geometric_stiffness(N, L)[np.ix_(XY, XY)]
    assert np.allclose(K, E * IZ * quadrature(L, 2), rtol=1e-13, atol=0)
    assert np.allclose(M, RHO * A * quadrature(L, 0), rtol=1e-13, atol=0)
    assert np.allclose(Kg, N * quadrature(L, 1), rtol=1e-13, atol=0)


def test_geometric_stiffness_properties():
    x1, x2, _, _, T, L = random_frame()
    Kg = el.to_global(el.frame_local_geometric_stiffness(1e3, L), T)
    assert np.abs(Kg - Kg.T).max() <= RTOL * np.abs(Kg).max()
    translations = rigid_vectors([x1, x2], np.zeros(3))[:, :3]
    assert np.abs(Kg @ translations).max() <= RTOL * np.abs(Kg).max()
    assert np.linalg.eigvalsh(Kg).min() > -RTOL * np.abs(Kg).max()  # tension: PSD


# ------------------------------------------------------------------------------------------------
# planar beam and grid = the corresponding sub-blocks of the 3-D frame
def frame_global(x1, x2, v, N=0.0, lumped=False):
    L = np.linalg.norm(x2 - x1)
    T = el.frame_transformation(el.frame_rotation(x1, x2, v))
    return (
        el.to_global(el.frame_local_stiffness(E, G, A, IY, IZ, J, L), T),
        el.to_global(el.frame_local_mass(RHO, A, IY, IZ, L, lumped), T),
        el.to_global(el.frame_local_geometric_stiffness(N, L), T),
        L,
    )


@pytest.mark.parametrize("lumped", [False, True])
def test_beam2d_equals_in_plane_block_of_frame(lumped):
    alpha = 0.6
    x1 = np.array([0.3, -0.2, 1.0])
    x2 = x1 + 2 * np.array([np.cos(alpha), np.sin(alpha), 0.0])
    v = [-np.sin(alpha), np.cos(alpha), 0.0]  # local z = global Z: Iz bends in the X-Y plane
    K3, M3, G3, L = frame_global(x1, x2, v, N=500.0, lumped=lumped)
    idx = np.ix_([0, 1, 5, 6, 7, 11], [0, 1, 5, 6, 7, 11])
    T = el.beam2d_transformation(x1, x2)
    assert np.allclose(
        el.to_global(el.beam2d_local_stiffness(E, A, IZ, L), T),
        K3[idx],
        rtol=0,
        atol=RTOL * np.abs(K3).max(),
    )
    assert np.allclose(
        el.to_global(el.beam2d_local_mass(RHO, A, L, lumped), T),
        M3[idx],
        rtol=0,
        atol=RTOL * np.abs(M3).max(),
    )
    assert np.allclose(
        el.to_global(el.beam2d_local_geometric_stiffness(500.0, L), T),
        G3[idx],
        rtol=0,
        atol=RTOL * np.abs(G3).max(),
    )


def test_grid_equals_out_of_plane_block_of_frame():
    x1, x2 = np.array([1.0, 2.0, 0.0]), np.array([-0.5, 3.1, 0.0])
    K3, M3, G3, L = frame_global(x1, x2, None, N=-800.0)  # default v = Z: Iz bends out of plane
    idx = np.ix_([2, 3, 4, 8, 9, 10], [2, 3, 4, 8, 9, 10])
    T = el.grid_transformation(x1, x2)
    K = el.to_global(el.grid_local_stiffness(E * IZ, G * J, L), T)
    M = el.to_global(el.grid_local_mass(RHO * A, RHO * (IY + IZ), L), T)
    Kg = el.to_global(el.grid_local_geometric_stiffness(-800.0, L), T)
    for got, ref in ((K, K3), (M, M3), (Kg, G3)):
        assert np.allclose(got, ref[idx], rtol=0, atol=RTOL * np.abs(ref).max())


# ------------------------------------------------------------------------------------------------
def test_rod_matrices():
    x1, x2 = rng.normal(size=3), rng.normal(size=3)
    L, n = np.linalg.norm(x2 - x1), (x2 - x1) / np.linalg.norm(x2 - x1)
    K = el.rod_stiffness(E, A, x1, x2)
    R = rigid_vectors([x1, x2], rng.normal(size=3), rotations=False)
    assert np.abs(K @ R).max() <= RTOL * np.abs(K).max() * np.abs(R).max()
    stretch = np.concatenate([-n, n]) / 2  # ends move apart by 1 m
    assert stretch @ K @ stretch == pytest.approx(E * A / L, rel=1e-13)
    Kg = el.rod_geometric_stiffness(10.0, x1, x2)
    assert np.abs(Kg @ R[:, :3]).max() <= RTOL * np.abs(Kg).max()
    assert np.abs(Kg @ stretch).max() <= RTOL * np.abs(Kg).max()
    m, c = RHO * A * L, (x1 + x2) / 2
    R0 = rigid_vectors([x1, x2], np.zeros(3), rotations=False)
    for lumped, transverse in ((False, m * L**2 / 12), (True, m * L**2 / 4)):
        Ic = transverse * (np.eye(3) - np.outer(n, n))  # no inertia about the rod axis
        expected = rigid_mass_matrix(m, c, Ic, np.zeros(3))
        got = R0.T @ el.rod_mass(RHO, A, L, lumped) @ R0
        assert np.allclose(got, expected, rtol=0, atol=RTOL * np.abs(expected).max())


def test_batched_shapes_broadcast():
    L = np.array([1.0, 2.0, 3.0])
    assert el.frame_local_stiffness(E, G, A, IY, IZ, J, L).shape == (3, 12, 12)
    assert el.frame_local_mass(RHO, A, IY, IZ, 2.0).shape == (12, 12)
    assert el.grid_local_mass(1.0, 0.0, L).shape == (3, 6, 6)
    single = el.frame_local_stiffness(E, G, A, IY, IZ, J, 2.0)
    assert np.array_equal(el.frame_local_stiffness(E, G, A, IY, IZ, J, L)[1], single)
