r"""What the modal-model readers (NASTRAN OP2/OP4, plain OP2, UFF) share: units, ω, rigid mass.

Model units
-----------
NASTRAN is unit-free: a model's consistent units are given as pint strings for ``length``,
``mass`` and ``time`` (:data:`SI_UNITS` is the default). With :math:`\ell_u` metres, :math:`m_u`
kilograms and :math:`t_u` seconds per model unit and
:math:`s = \sqrt{m_u}\,(1, 1, 1, \ell_u, \ell_u, \ell_u)`, mass-normalised shapes are divided by
s, a rigid mass is multiplied by :math:`s s^T`, a participation by s (column-wise), lengths by
:math:`\ell_u` and circular frequencies divided by :math:`t_u`.

Mass properties from rigid-body modes
-------------------------------------
A file without a mass matrix still gives the rigid mass and the participation
:math:`L = \Phi^T M R` when it holds the six rigid-body modes of a free model: with R the rigid
vectors at the nodes (rows that the rigid shapes have) and :math:`\Phi_r A = R` solved by least
squares, M-orthonormality gives :math:`L_r = A`, :math:`L = 0` for the elastic modes and
:math:`M_{rr} = A^T A`. Because file values are rounded (six digits in a UFF, single precision
in an OP2), :math:`A^T A` is projected onto the rigid-mass form (m I, [s×] coupling, symmetric
inertia) and :math:`L_r` is replaced by :math:`U M_{rr}^{1/2}` with U the orthogonal polar factor
of A, so that :math:`L^T L = M_{rr}` exactly.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError, require_finite
from flexsat.units import FloatArray, to_si

__all__ = [
    "SI_UNITS",
    "eigen_frequencies",
    "mass_properties_from_modes",
    "rigid_vectors",
    "unit_scales",
]

#: Default model units (SI), also the keys ``units`` must have.
SI_UNITS = {"length": "m", "mass": "kg", "time": "s"}

_RIGID_FIT_TOL = 1e-3  # relative misfit of rigid motion by the rigid modes (6-digit data: ~1e-5)


def unit_scales(units: Mapping[str, str] | None) -> tuple[float, float, float]:
    """Metres, kilograms and seconds per model unit of length, mass and time.

    Parameters
    ----------
    units : mapping or None
        Pint unit strings for exactly ``"length"``, ``"mass"`` and ``"time"``; None is SI.
    """
    given = SI_UNITS if units is None else dict(units)
    if set(given) != set(SI_UNITS):
        raise FieldError(
            "units",
            f"must map exactly 'length', 'mass' and 'time' to unit strings, got {sorted(given)}",
        )
    length, mass, time = (
        to_si(f"1 {given[k]}", SI_UNITS[k], f"units[{k!r}]") for k in ("length", "mass", "time")
    )
    return length, mass, time


def eigen_frequencies(lam: FloatArray, time: float, rigid_frequency: float) -> FloatArray:
    r"""ω in rad/s from eigenvalues λ in model units: :math:`\sqrt{\max(\lambda, 0)} / t_u`.

    Modes at or below ``rigid_frequency`` (rad/s) are rigid-body modes: their eigen-solver
    roundoff is set to 0. Refused (field ``rigid_frequency``) when the result is not ascending,
    or when a negative λ is larger than rigid-body roundoff (:math:`\sqrt{-\lambda} / t_u` above
    ``rigid_frequency``: an unstable, e.g. buckled prestressed, model).
    """
    unstable = np.flatnonzero(np.sqrt(np.clip(-lam, 0.0, None)) / time > rigid_frequency)
    if unstable.size:
        i = int(unstable[0])
        raise FieldError(
            "rigid_frequency",
            f"mode {i + 1} has eigenvalue {lam[i]:.6g} < 0, |ω| = "
            f"{np.sqrt(-lam[i]) / time:.3g} rad/s above {rigid_frequency:g} rad/s: not rigid-body "
            "roundoff but an unstable model",
        )
    w = np.sqrt(np.clip(lam, 0.0, None)) / time
    w = np.where(w <= rigid_frequency, 0.0, w)
    if np.any(np.diff(w) < 0):
        low = ", ".join(f"{x:.3g}" for x in np.sort(w[w > 0])[:3])
        raise FieldError(
            "rigid_frequency",
            "eigenvalues are not ascending once the modes at or below "
            f"{rigid_frequency:g} rad/s are set to 0 (lowest others {low} rad/s); if those are "
            "rigid-body modes, raise rigid_frequency",
        )
    return w


def rigid_vectors(coordinates: FloatArray, reference: FloatArray) -> FloatArray:
    """(n * 6, 6) rigid-body vectors: a node at r from the reference moves t + θ × r, turns θ."""
    R = np.zeros((len(coordinates), 6, 6))
    R[:, :3, :3] = R[:, 3:, 3:] = np.eye(3)
    for i, (x, y, z) in enumerate(coordinates - reference):
        R[i, :3, 3:] = [[0.0, z, -y], [-z, 0.0, x], [y, -x, 0.0]]  # θ × r = -[r×] θ
    return R.reshape(-1, 6)


def _rigid_mass_form(B: FloatArray) -> FloatArray:
    """Nearest [[m I, -[s×]], [[s×], J]] to B: mean mass, skew coupling, symmetric inertia."""
    C = 0.5 * (B[3:, :3] - B[:3, 3:])
    S = 0.5 * (C - C.T)
    J = 0.5 * (B[3:, 3:] + B[3:, 3:].T)
    return np.block([[np.trace(B[:3, :3]) / 3 * np.eye(3), -S], [S, J]])


def _sqrtm_psd(A: FloatArray) -> FloatArray:
    e, V = np.linalg.eigh(A)
    return (V * np.sqrt(np.clip(e, 0.0, None))) @ V.T


def _rigid_from_modes(
    rigid_shapes: FloatArray, coordinates: FloatArray, reference: FloatArray, path: Path
) -> tuple[FloatArray, FloatArray]:
    """Rigid mass and participation rows of six mass-normalised rigid-body modes (SI)."""
    phi = rigid_shapes.reshape(len(rigid_shapes), -1).T  # (n * 6, 6)
    R = rigid_vectors(coordinates, reference)
    rows = np.any(phi != 0, axis=1)
    A, *_ = np.linalg.lstsq(phi[rows], R[rows], rcond=None)
    misfit = np.linalg.norm(phi[rows] @ A - R[rows]) / np.linalg.norm(R[rows])
    if misfit > _RIGID_FIT_TOL:
        raise ValueError(
            f"{path}: the six rigid-body modes do not span the rigid motions at the nodes "
            f"(relative misfit {misfit:.2g}); pass rigid_mass= and participation="
        )
    rigid_mass = _rigid_mass_form(A.T @ A)
    W, _, Vt = np.linalg.svd(A)
    return rigid_mass, W @ Vt @ _sqrtm_psd(rigid_mass)


def mass_properties_from_modes(
    frequencies: FloatArray,
    shapes: FloatArray,
    coordinates: FloatArray,
    reference: FloatArray,
    rigid_mass: npt.ArrayLike | None,
    participation: npt.ArrayLike | None,
    path: Path,
    kind: str,
) -> tuple[FloatArray, FloatArray, str]:
    """(rigid_mass, participation, boundary): given, or derived from six rigid-body modes.

    Parameters
    ----------
    frequencies : ndarray (m,)
        rad/s, rigid-body modes exactly 0.
    shapes : ndarray (m, n, 6)
        Mass-normalised, SI, global axes.
    coordinates : ndarray (n, 3)
        Node locations, m.
    reference : ndarray (3,)
        Point of the rigid motion, m.
    rigid_mass, participation : array_like (6, 6) and (m, 6), optional
        Both or neither; when given they are returned as they are (SI).
    path : Path
        The file read, named in errors.
    kind : str
        What the file is, for the error when no mass matrix can be had ("a universal file").

    Returns
    -------
    tuple
        Rigid mass (6, 6), participation (m, 6) and the boundary: "free" with rigid-body
        modes, else "cantilevered".
    """
    rigid = frequencies == 0.0
    boundary = "free" if rigid.any() else "cantilevered"
    if (rigid_mass is None) != (participation is None):
        raise ValueError("rigid_mass, participation: give both or neither")
    if rigid_mass is not None and participation is not None:
        return (
            require_finite(rigid_mass, "rigid_mass"),
            require_finite(participation, "participation"),
            boundary,
        )
    if rigid.sum() != 6:
        raise ValueError(
            f"{path}: {kind} has no mass matrix; rigid_mass and participation are derived "
            f"from six rigid-body modes, found {rigid.sum()}: pass rigid_mass= and participation="
        )
    rigid_mass, rigid_rows = _rigid_from_modes(shapes[rigid], coordinates, reference, path)
    participation = np.zeros((frequencies.size, 6))
    participation[rigid] = rigid_rows
    return rigid_mass, participation, boundary
