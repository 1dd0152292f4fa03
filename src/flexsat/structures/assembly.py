"""The assembled finite-element model and its modes: :class:`Assembly` (sparse K and M on the
active dofs, dof lookup, rigid-body vectors, mass properties, the modal solve) and
:class:`FEModes` (mass-normalised modes, per-node shapes). Built by
:meth:`flexsat.structures.fem.Structure.assemble`; all SI.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TypedDict

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from flexsat.input_checks import FieldError, require_finite
from flexsat.structures import elements as el
from flexsat.structures.modal_solve import solve_modes
from flexsat.units import FloatArray

__all__ = ["DOF_NAMES", "DOF_SLOT", "Assembly", "DependentDofs", "FEModes", "MassProperties"]

#: the six dofs of a node, in slot order
DOF_NAMES = ("ux", "uy", "uz", "rx", "ry", "rz")
#: a dof name's slot (0–5) in a node's six
DOF_SLOT = {name: i for i, name in enumerate(DOF_NAMES)}

IntArray = npt.NDArray[np.int_]


class MassProperties(TypedDict):
    """Rigid-body mass properties (:meth:`Assembly.mass_properties`)."""

    total_mass: float
    center_of_mass: FloatArray
    inertia: FloatArray
    inertia_center_of_mass: FloatArray


@dataclass(frozen=True, eq=False)
class DependentDofs:
    """The dofs eliminated by rigid links and their recovery ``u_d = G q`` from the active
    dofs q (:meth:`Structure.add_rigid_link`): node indices and dof slots (n_d,), G (n_d, ndof)
    sparse."""

    nodes: IntArray
    slots: IntArray
    G: sp.csr_matrix


@dataclass(frozen=True, eq=False)
class Assembly:
    """Assembled sparse model on the active dofs.

    Attributes
    ----------
    K, M : scipy.sparse.csr_matrix (ndof, ndof)
        Stiffness (elastic + geometric from the axial preloads) and mass, symmetric.
    dofs : list of (node_id, dof_name)
        Meaning of each row.
    node_ids : ndarray (n_nodes,)
    coordinates : ndarray (n_nodes, 3)
    n_clamped : int
        Number of clamped dofs of the structure (0: free-free).
    unclamped : Assembly or None
        For a clamped structure, the assembly of the same structure with the clamps released.
    dependent : DependentDofs or None
        The dofs of rigidly linked nodes, eliminated here, and their recovery.
    """

    K: sp.csr_matrix
    M: sp.csr_matrix
    dofs: list[tuple[int, str]]
    node_ids: IntArray
    coordinates: FloatArray
    n_clamped: int = 0
    unclamped: Assembly | None = None
    dependent: DependentDofs | None = None
    _lookup: dict[tuple[int, str], int] = field(init=False, repr=False)
    _node_of_dof: IntArray = field(init=False, repr=False)
    _slot_of_dof: IntArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        row = {int(n): i for i, n in enumerate(self.node_ids)}
        lookup = {(int(n), d): i for i, (n, d) in enumerate(self.dofs)}
        object.__setattr__(self, "_lookup", lookup)
        object.__setattr__(self, "_node_of_dof", np.array([row[int(n)] for n, _ in self.dofs], int))
        object.__setattr__(self, "_slot_of_dof", np.array([DOF_SLOT[d] for _, d in self.dofs], int))

    @property
    def n_dofs(self) -> int:
        """Number of active dofs."""
        return len(self.dofs)

    def index(self, node_id: int, dof: str) -> int:
        """Row of an active dof, e.g. ``index(12, "uz")``."""
        try:
            return self._lookup[(int(node_id), dof)]
        except (KeyError, TypeError, ValueError):
            raise ValueError(
                f"dof ({node_id!r}, {dof!r}): not an active dof (unknown node or dof name, "
                "clamped, or not touched by any element or mass)"
            ) from None

    def rigid_body_vectors(self, reference: npt.ArrayLike = (0.0, 0.0, 0.0)) -> FloatArray:
        """Unit rigid-body motions on the active dofs, shape (ndof, 6).

        Columns: translations along x, y, z (1 m) and rotations about x, y, z (1 rad) about
        ``reference``: u = t + θ × (x - reference) on translations and θ on rotations.
        """
        p = require_finite(reference, "reference")
        r = self.coordinates - p
        B = np.zeros((len(r), 6, 6))
        B[:, :3, :3] = np.eye(3)
        B[:, 3:, 3:] = np.eye(3)
        B[:, :3, 3:] = -el.skew(r)
        return B[self._node_of_dof, self._slot_of_dof]

    def mass_properties(self, reference: npt.ArrayLike = (0.0, 0.0, 0.0)) -> MassProperties:
        """Rigid-body mass properties from ``G = R^T M R`` (R: :meth:`rigid_body_vectors`).

        Needs all three translations represented (a 3-D model).

        Returns
        -------
        dict
            ``total_mass`` (kg), ``center_of_mass`` (3,), m, ``inertia`` (3, 3) about
            ``reference`` and ``inertia_center_of_mass`` (3, 3) about the centre of mass, kg m^2.
        """
        p = require_finite(reference, "reference")
        G = self.rigid_body_vectors(p).T @ (self.M @ self.rigid_body_vectors(p))
        m = G[0, 0]
        if not m > 0 or np.abs(G[:3, :3] - m * np.eye(3)).max() > 1e-9 * m:
            raise FieldError(
                "mass_properties",
                "the model must carry the same mass in x, y and z (a 3-D "
                f"model); translational masses are {np.diag(G)[:3]}",
            )
        a = np.array([G[5, 1] - G[4, 2], G[3, 2] - G[5, 0], G[4, 0] - G[3, 1]]) / (2.0 * m)
        inertia = (G[3:, 3:] + G[3:, 3:].T) / 2.0
        shift = m * (a @ a * np.eye(3) - np.outer(a, a))
        return MassProperties(
            total_mass=float(m),
            center_of_mass=p + a,
            inertia=inertia,
            inertia_center_of_mass=inertia - shift,
        )

    def modes(
        self, n_modes: int, rigid_body_modes: int | None = None, shift: float | None = None
    ) -> FEModes:
        """Lowest mass-normalized modes (see :func:`flexsat.structures.modal_solve.solve_modes`).

        Parameters
        ----------
        n_modes : int
            Number of modes, rigid-body ones included.
        rigid_body_modes : int, optional
            Expected number of near-zero modes (6 for a free 3-D body): checked, then replaced
            by exact M-orthonormal rigid-body vectors with ω = 0.  With None, a clamped
            structure must have no near-zero mode (else: mechanism).
        shift : float, optional
            Spectral shift, (rad/s)^2; the modes nearest to it are returned.
        """
        omegas, shapes = solve_modes(
            self.K,
            self.M,
            n_modes,
            rigid_body_modes=rigid_body_modes,
            shift=shift,
            rigid_vectors=self.rigid_body_vectors(),
            clamped=self.n_clamped > 0,
        )
        return FEModes(omegas, shapes, self)


@dataclass(frozen=True, eq=False)
class FEModes:
    """Mass-normalized natural modes of an :class:`Assembly`.

    Attributes
    ----------
    omegas : ndarray (n_modes,)
        rad/s, ascending; rigid-body modes (ω = 0) first.
    shapes : ndarray (ndof, n_modes)
        ``shapes.T @ M @ shapes = I``.
    assembly : Assembly
    """

    omegas: FloatArray
    shapes: FloatArray
    assembly: Assembly

    @property
    def frequencies_hz(self) -> FloatArray:
        """ω / 2π, Hz."""
        return self.omegas / (2.0 * np.pi)

    def at_nodes(self) -> FloatArray:
        """Mode shapes per node and dof, shape (n_modes, n_nodes, 6), 0 on inactive dofs."""
        a = self.assembly
        out = np.zeros((self.shapes.shape[1], len(a.node_ids), 6))
        out[:, a._node_of_dof, a._slot_of_dof] = self.shapes.T
        if a.dependent is not None:  # rigidly linked nodes move with their independent node
            d = a.dependent
            out[:, d.nodes, d.slots] = (d.G @ self.shapes).T
        return out
