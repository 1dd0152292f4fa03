r"""Element matrices of linear frame, planar beam, grid and rod elements (batched).

Every function broadcasts over its array arguments: scalars give one matrix, arrays of shape
``(n,)`` give a stack of shape ``(n, d, d)``.  Matrices are in *local* element axes unless the
name says otherwise; :func:`to_global` applies a transformation ``T`` as ``T^T k T``.

Sources
-------
* Stiffness, consistent mass and transformation of the 3-D frame: J. S. Przemieniecki,
  *Theory of Matrix Structural Analysis* (McGraw-Hill 1968; Dover 1985), ch. 5 (stiffness of
  the uniform beam element), ch. 6 (transformation) and ch. 11 (consistent mass);
  Euler-Bernoulli: no shear deformation, no rotary inertia of the bending rotations.
* Consistent geometric stiffness under a constant axial force N (tension > 0): Przemieniecki
  ch. 15; Cook, Malkus, Plesha & Witt, *Concepts and Applications of Finite Element Analysis*,
  4th ed. (2002), ch. 18: ``N/(30 L) [[36, 3L, -36, 3L], [3L, 4L^2, -3L, -L^2], ...]`` per
  bending plane (= N ∫ N'^T N' dx of the Hermite cubics), and ``N/L (I - n n^T)`` for rods.
* Lumped masses: HRZ diagonal scaling (Hinton, Rock & Zienkiewicz, Earthquake Eng. Struct.
  Dyn. 4, 245-249, 1976; Cook ch. 11): rho A L/2 per translation and rho A L^3/78 per bending
  rotation.
* Rigid end offsets: u_end = u_node + theta × d, theta_end = theta_node (rigid link, as the
  NASTRAN CBAR offsets ``WA``/``WB`` in global axes).

Local conventions
-----------------
Frame dofs per node (u, v, w, theta_x, theta_y, theta_z); x along the member, ``Iz`` bending in
the x-y plane (v' = theta_z), ``Iy`` bending in the x-z plane (w' = -theta_y), ``J`` torsion.
Planar beam dofs per node (u, v, theta_z) in the global X-Y plane.  Grid dofs per node
(w, theta_x, theta_y) for a member in the global X-Y plane, w along global Z (w' = -theta_y).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = [
    "beam2d_local_geometric_stiffness",
    "beam2d_local_mass",
    "beam2d_local_stiffness",
    "beam2d_transformation",
    "frame_local_geometric_stiffness",
    "frame_local_mass",
    "frame_local_stiffness",
    "frame_rotation",
    "frame_transformation",
    "grid_local_geometric_stiffness",
    "grid_local_mass",
    "grid_local_stiffness",
    "grid_transformation",
    "rod_geometric_stiffness",
    "rod_mass",
    "rod_stiffness",
    "skew",
    "to_global",
]

_XZ = np.array([1.0, -1.0, 1.0, -1.0])  # theta -> -theta maps x-y plane bending to x-z plane
_PARALLEL_TOL = 1e-9  # |x × v| below this (unit vectors) counts as parallel


# ------------------------------------------------------------------------------------------------
# one-dimensional building blocks, shapes (..., 2, 2) and (..., 4, 4)
def _bar_stiffness(EA: npt.ArrayLike, L: npt.ArrayLike) -> FloatArray:
    """Linear bar stiffness EA/L [[1, -1], [-1, 1]]."""
    c = np.asarray(EA, float) / np.asarray(L, float)
    return c[..., None, None] * np.array([[1.0, -1.0], [-1.0, 1.0]])


def _bar_mass(m: npt.ArrayLike, L: npt.ArrayLike) -> FloatArray:
    """Consistent mass m L/6 [[2, 1], [1, 2]] of a linear bar (m per length)."""
    c = np.asarray(m, float) * np.asarray(L, float) / 6.0
    return c[..., None, None] * np.array([[2.0, 1.0], [1.0, 2.0]])


def _hermite(
    c: npt.ArrayLike, L: npt.ArrayLike, powers: npt.ArrayLike, template: npt.ArrayLike
) -> FloatArray:
    """c * template_ij * L**powers_ij (broadcast), the cubic Hermite bending matrices."""
    c, L = np.broadcast_arrays(np.asarray(c, float), np.asarray(L, float))
    return c[..., None, None] * np.asarray(template) * L[..., None, None] ** np.asarray(powers)


_P = [[0, 1, 0, 1], [1, 2, 1, 2], [0, 1, 0, 1], [1, 2, 1, 2]]  # powers of L in the templates


def _hermite_stiffness(EI: npt.ArrayLike, L: npt.ArrayLike) -> FloatArray:
    """EI/L^3 [[12, 6L, -12, 6L], [6L, 4L^2, -6L, 2L^2], ...] (x-y plane convention)."""
    t = [[12, 6, -12, 6], [6, 4, -6, 2], [-12, -6, 12, -6], [6, 2, -6, 4]]
    return _hermite(np.asarray(EI) / np.asarray(L, float) ** 3, L, _P, t)


def _hermite_mass(m: npt.ArrayLike, L: npt.ArrayLike) -> FloatArray:
    """m L/420 [[156, 22L, 54, -13L], [22L, 4L^2, 13L, -3L^2], ...] (x-y plane convention)."""
    t = [[156, 22, 54, -13], [22, 4, 13, -3], [54, 13, 156, -22], [-13, -3, -22, 4]]
    return _hermite(np.asarray(m) * np.asarray(L, float) / 420.0, L, _P, t)


def _hermite_geometric(N: npt.ArrayLike, L: npt.ArrayLike) -> FloatArray:
    """N/(30 L) [[36, 3L, -36, 3L], [3L, 4L^2, -3L, -L^2], ...] (x-y plane convention)."""
    t = [[36, 3, -36, 3], [3, 4, -3, -1], [-36, -3, 36, -3], [3, -1, -3, 4]]
    return _hermite(np.asarray(N) / (30.0 * np.asarray(L, float)), L, _P, t)


def _xz(block: FloatArray) -> FloatArray:
    """Bending block of the x-z plane (w, theta_y) from the x-y plane one (v, theta_z)."""
    return block * _XZ[:, None] * _XZ[None, :]


def _place(
    shape: tuple[int, ...], size: int, *parts: tuple[Sequence[int], FloatArray]
) -> FloatArray:
    """Assemble (index list, block) pairs into zero matrices of shape (..., size, size)."""
    out = np.zeros(shape + (size, size))
    for idx, block in parts:
        ix = np.asarray(idx)
        out[..., ix[:, None], ix[None, :]] += block
    return out


def _batch_shape(*arrays: npt.ArrayLike) -> tuple[int, ...]:
    return np.broadcast_shapes(*(np.shape(a) for a in arrays))


def _lumped(diagonal: Sequence[npt.ArrayLike], shape: tuple[int, ...]) -> FloatArray:
    """Diagonal matrices from a list of per-dof arrays (broadcast to ``shape``)."""
    d = np.stack([np.broadcast_to(np.asarray(v, float), shape) for v in diagonal], -1)
    return d[..., :, None] * np.eye(d.shape[-1])


# ------------------------------------------------------------------------------------------------
# 3-D frame (12 dofs)
_F_AXIAL, _F_TORSION = [0, 6], [3, 9]
_F_XY, _F_XZ = [1, 5, 7, 11], [2, 4, 8, 10]


def frame_local_stiffness(
    E: npt.ArrayLike,
    G: npt.ArrayLike,
    A: npt.ArrayLike,
    Iy: npt.ArrayLike,
    Iz: npt.ArrayLike,
    J: npt.ArrayLike,
    L: npt.ArrayLike,
) -> FloatArray:
    """Local 12x12 stiffness of a 3-D Euler-Bernoulli frame (Przemieniecki ch. 5).

    Parameters
    ----------
    E, G : array_like
        Young's and shear moduli, Pa.
    A, Iy, Iz, J : array_like
        Area (m^2), second moments about local y and z and torsion constant (m^4).
    L : array_like
        Length, m.

    Returns
    -------
    ndarray, shape (..., 12, 12)
    """
    E, G, L = (np.asarray(v, float) for v in (E, G, L))
    shape = _batch_shape(E, G, A, Iy, Iz, J, L)
    return _place(
        shape,
        12,
        (_F_AXIAL, _bar_stiffness(E * A, L)),
        (_F_TORSION, _bar_stiffness(G * np.asarray(J), L)),
        (_F_XY, _hermite_stiffness(E * np.asarray(Iz), L)),
        (_F_XZ, _xz(_hermite_stiffness(E * np.asarray(Iy), L))),
    )


def frame_local_mass(
    rho: npt.ArrayLike,
    A: npt.ArrayLike,
    Iy: npt.ArrayLike,
    Iz: npt.ArrayLike,
    L: npt.ArrayLike,
    lumped: bool = False,
) -> FloatArray:
    """Local 12x12 mass of a 3-D frame: consistent (Przemieniecki ch. 11) or HRZ-lumped.

    The torsional inertia per length is rho (Iy + Iz) (polar moment); rotary inertia of the
    bending rotations is neglected in the consistent matrix (Euler-Bernoulli).

    Parameters
    ----------
    rho : array_like
        Density, kg/m^3.
    A, Iy, Iz : array_like
        Area (m^2) and second moments of area (m^4).
    L : array_like
        Length, m.
    lumped : bool
        False: consistent mass.  True: diagonal, rho A L/2 per translation, rho (Iy + Iz) L/2
        per twist and rho A L^3/78 per bending rotation (HRZ).

    Returns
    -------
    ndarray, shape (..., 12, 12)
    """
    rho, L = np.asarray(rho, float), np.asarray(L, float)
    shape = _batch_shape(rho, A, Iy, Iz, L)
    m = rho * np.asarray(A)
    ip = rho * (np.asarray(Iy) + np.asarray(Iz))
    if lumped:
        t, r, tw = m * L / 2.0, m * L**3 / 78.0, ip * L / 2.0
        return _lumped([t, t, t, tw, r, r] * 2, shape)
    return _place(
        shape,
        12,
        (_F_AXIAL, _bar_mass(m, L)),
        (_F_TORSION, _bar_mass(ip, L)),
        (_F_XY, _hermite_mass(m, L)),
        (_F_XZ, _xz(_hermite_mass(m, L))),
    )


def frame_local_geometric_stiffness(N: npt.ArrayLike, L: npt.ArrayLike) -> FloatArray:
    """Local 12x12 consistent geometric stiffness of a frame under axial force N (tension > 0).

    Both bending planes, ``N/(30 L)`` times the cubic Hermite matrix (Przemieniecki ch. 15,
    Cook ch. 18); the axial and torsional rows are zero.

    Returns
    -------
    ndarray, shape (..., 12, 12)
    """
    N, L = np.asarray(N, float), np.asarray(L, float)
    kg = _hermite_geometric(N, L)
    return _place(_batch_shape(N, L), 12, (_F_XY, kg), (_F_XZ, _xz(kg)))


def frame_rotation(
    x1: npt.ArrayLike, x2: npt.ArrayLike, orientation: npt.ArrayLike | None = None
) -> FloatArray:
    """Rotation matrices whose rows are the local x, y, z axes in global coordinates.

    Local x runs from ``x1`` to ``x2``; ``orientation`` is a vector v in the local x-y plane
    (NASTRAN CBAR convention): z = x × v / |x × v|, y = z × x.  The default v is global Z,
    or global Y for a member parallel to Z.

    Parameters
    ----------
    x1, x2 : array_like, shape (..., 3)
        Positions of the two member ends, m (distinct).
    orientation : array_like, shape (..., 3), optional

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    d = np.asarray(x2, float) - np.asarray(x1, float)
    ex = d / np.linalg.norm(d, axis=-1, keepdims=True)
    if orientation is None:
        along_z = np.linalg.norm(np.cross(ex, [0.0, 0.0, 1.0]), axis=-1) < _PARALLEL_TOL
        v = np.where(along_z[..., None], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0])
    else:
        v = np.broadcast_to(np.asarray(orientation, float), ex.shape)
    ez = np.cross(ex, v)
    nz = np.linalg.norm(ez, axis=-1, keepdims=True) / np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(~(nz > _PARALLEL_TOL)):
        raise FieldError("orientation", "must not be parallel to the member axis")
    ez = ez / np.linalg.norm(ez, axis=-1, keepdims=True)
    return np.stack([ex, np.cross(ez, ex), ez], axis=-2)


def skew(d: npt.ArrayLike) -> FloatArray:
    """S(d) with S(d) v = d × v, shape (..., 3, 3)."""
    d = np.asarray(d, float)
    z = np.zeros(d.shape[:-1])
    return np.stack(
        [
            np.stack([z, -d[..., 2], d[..., 1]], -1),
            np.stack([d[..., 2], z, -d[..., 0]], -1),
            np.stack([-d[..., 1], d[..., 0], z], -1),
        ],
        -2,
    )


def frame_transformation(
    rotation: npt.ArrayLike, offsets: npt.ArrayLike | None = None
) -> FloatArray:
    """12x12 map from global node dofs to local member-end dofs.

    ``T = diag(R, R, R, R) @ T_off`` where ``R`` is :func:`frame_rotation` and
    ``T_off = [[I, -S(d), 0, 0], [0, I, 0, 0], [0, 0, I, -S(d2)], [0, 0, 0, I]]`` applies the
    rigid offsets d (node to member end, global axes): u_end = u_node + theta × d.

    Parameters
    ----------
    rotation : array_like, shape (..., 3, 3)
    offsets : array_like, shape (..., 2, 3), optional
        Offsets at end 1 and end 2, m.

    Returns
    -------
    ndarray, shape (..., 12, 12)
    """
    R = np.asarray(rotation, float)
    T = np.zeros(R.shape[:-2] + (12, 12))
    for b in range(4):
        T[..., 3 * b : 3 * b + 3, 3 * b : 3 * b + 3] = R
    if offsets is not None:
        off = np.broadcast_to(np.eye(12), T.shape).copy()
        d = np.asarray(offsets, float)
        off[..., 0:3, 3:6] = -skew(d[..., 0, :])
        off[..., 6:9, 9:12] = -skew(d[..., 1, :])
        T = T @ off
    return T


def to_global(k_local: FloatArray, T: FloatArray) -> FloatArray:
    """``T^T k T`` for stacks of element matrices, shape (..., d, d)."""
    return np.swapaxes(T, -1, -2) @ k_local @ T


# ------------------------------------------------------------------------------------------------
# planar beam in the global X-Y plane (6 dofs: u, v, theta_z per node)
_B_AXIAL, _B_BEND = [0, 3], [1, 2, 4, 5]


def beam2d_local_stiffness(
    E: npt.ArrayLike, A: npt.ArrayLike, Iz: npt.ArrayLike, L: npt.ArrayLike
) -> FloatArray:
    """Local 6x6 stiffness of a planar Euler-Bernoulli beam (axial + bending with Iz)."""
    E = np.asarray(E, float)
    shape = _batch_shape(E, A, Iz, L)
    return _place(
        shape,
        6,
        (_B_AXIAL, _bar_stiffness(E * A, L)),
        (_B_BEND, _hermite_stiffness(E * np.asarray(Iz), L)),
    )


def beam2d_local_mass(
    rho: npt.ArrayLike, A: npt.ArrayLike, L: npt.ArrayLike, lumped: bool = False
) -> FloatArray:
    """Local 6x6 planar-beam mass: consistent, or HRZ-lumped (rho A L/2, rho A L^3/78)."""
    m, L = np.asarray(rho, float) * np.asarray(A), np.asarray(L, float)
    shape = _batch_shape(m, L)
    if lumped:
        t, r = m * L / 2.0, m * L**3 / 78.0
        return _lumped([t, t, r] * 2, shape)
    return _place(shape, 6, (_B_AXIAL, _bar_mass(m, L)), (_B_BEND, _hermite_mass(m, L)))


def beam2d_local_geometric_stiffness(N: npt.ArrayLike, L: npt.ArrayLike) -> FloatArray:
    """Local 6x6 geometric stiffness of a planar beam under axial force N (tension > 0)."""
    return _place(_batch_shape(N, L), 6, (_B_BEND, _hermite_geometric(N, L)))


def _plane_rotation(x1: npt.ArrayLike, x2: npt.ArrayLike) -> FloatArray:
    d = np.asarray(x2, float)[..., :2] - np.asarray(x1, float)[..., :2]
    n = d / np.linalg.norm(d, axis=-1, keepdims=True)
    c, s = n[..., 0], n[..., 1]
    z, o = np.zeros_like(c), np.ones_like(c)
    rows = [np.stack([c, s, z], -1), np.stack([-s, c, z], -1), np.stack([z, z, o], -1)]
    return np.stack(rows, -2)


def _two_blocks(r: FloatArray) -> FloatArray:
    T = np.zeros(r.shape[:-2] + (6, 6))
    T[..., :3, :3] = r
    T[..., 3:, 3:] = r
    return T


def beam2d_transformation(x1: npt.ArrayLike, x2: npt.ArrayLike) -> FloatArray:
    """6x6 map from global (ux, uy, rz) at both nodes to the local planar-beam dofs."""
    return _two_blocks(_plane_rotation(x1, x2))


# ------------------------------------------------------------------------------------------------
# grid member in the global X-Y plane (6 dofs: w, theta_x, theta_y per node)
_G_TORSION, _G_BEND = [1, 4], [0, 2, 3, 5]


def grid_local_stiffness(EI: npt.ArrayLike, GJ: npt.ArrayLike, L: npt.ArrayLike) -> FloatArray:
    """Local 6x6 grid stiffness: transverse bending (EI, x-z plane) and torsion (GJ)."""
    shape = _batch_shape(EI, GJ, L)
    return _place(
        shape, 6, (_G_TORSION, _bar_stiffness(GJ, L)), (_G_BEND, _xz(_hermite_stiffness(EI, L)))
    )


def grid_local_mass(
    mass_per_length: npt.ArrayLike, torsional_inertia_per_length: npt.ArrayLike, L: npt.ArrayLike
) -> FloatArray:
    """Local 6x6 consistent grid mass: Hermite bending mass and linear torsional inertia."""
    shape = _batch_shape(mass_per_length, torsional_inertia_per_length, L)
    return _place(
        shape,
        6,
        (_G_TORSION, _bar_mass(torsional_inertia_per_length, L)),
        (_G_BEND, _xz(_hermite_mass(mass_per_length, L))),
    )


def grid_local_geometric_stiffness(N: npt.ArrayLike, L: npt.ArrayLike) -> FloatArray:
    """Local 6x6 geometric stiffness of a grid member under axial force N (transverse bending)."""
    return _place(_batch_shape(N, L), 6, (_G_BEND, _xz(_hermite_geometric(N, L))))


def grid_transformation(x1: npt.ArrayLike, x2: npt.ArrayLike) -> FloatArray:
    """6x6 map from global (uz, rx, ry) at both nodes to the local grid dofs (w, theta_x, theta_y).

    w = uz; (theta_x, theta_y) are the global rotations (rx, ry) turned into member axes.
    """
    r = _plane_rotation(x1, x2)
    g = np.zeros_like(r)
    g[..., 0, 0] = 1.0
    g[..., 1:, 1:] = r[..., :2, :2]
    return _two_blocks(g)


# ------------------------------------------------------------------------------------------------
# rod (truss bar), global translations only (6 dofs: ux, uy, uz per node)
def _axis_projector(x1: npt.ArrayLike, x2: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    d = np.asarray(x2, float) - np.asarray(x1, float)
    L = np.linalg.norm(d, axis=-1)
    n = d / L[..., None]
    return n[..., :, None] * n[..., None, :], L


def _bar_blocks(P: FloatArray, c: npt.ArrayLike) -> FloatArray:
    """c * [[P, -P], [-P, P]] of shape (..., 6, 6)."""
    B = np.concatenate([np.concatenate([P, -P], -1), np.concatenate([-P, P], -1)], -2)
    return B * np.asarray(c, float)[..., None, None]


def rod_stiffness(
    E: npt.ArrayLike, A: npt.ArrayLike, x1: npt.ArrayLike, x2: npt.ArrayLike
) -> FloatArray:
    """Global 6x6 rod stiffness EA/L [[n n^T, -n n^T], [-n n^T, n n^T]] (n: unit axis)."""
    P, L = _axis_projector(x1, x2)
    return _bar_blocks(P, np.asarray(E, float) * np.asarray(A) / L)


def rod_geometric_stiffness(N: npt.ArrayLike, x1: npt.ArrayLike, x2: npt.ArrayLike) -> FloatArray:
    """Global 6x6 rod geometric stiffness N/L [[I - n n^T, -(I - n n^T)], ...] (tension > 0)."""
    P, L = _axis_projector(x1, x2)
    return _bar_blocks(np.eye(3) - P, np.asarray(N, float) / L)


def rod_mass(
    rho: npt.ArrayLike, A: npt.ArrayLike, L: npt.ArrayLike, lumped: bool = False
) -> FloatArray:
    """Global 6x6 rod mass: consistent rho A L/6 [[2I, I], [I, 2I]] or lumped rho A L/2 I."""
    m = np.asarray(rho, float) * np.asarray(A) * np.asarray(L, float)
    block = np.eye(6) / 2.0 if lumped else np.kron([[2.0, 1.0], [1.0, 2.0]], np.eye(3)) / 6.0
    return m[..., None, None] * block
