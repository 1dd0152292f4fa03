"""Finite-element structures: nodes, elements, lumped masses, clamps, preloads; assembly; modes.

A :class:`Structure` collects the model; :meth:`Structure.assemble` returns an
:class:`Assembly` with sparse stiffness and mass matrices on the *active* dofs only (touched by
an element or a lumped mass, and not clamped); :meth:`Assembly.modes` returns mass-normalized
:class:`FEModes` (both in :mod:`flexsat.structures.assembly`, re-exported here).  Element
matrices: :mod:`flexsat.structures.elements`; eigen-solver and its checks:
:mod:`flexsat.structures.modal_solve`.  All SI.

Assembly is batched per element type: the element matrices of all members of a type are built
as one ``(n, d, d)`` stack, scattered as COO triplets and summed into CSR.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from numbers import Integral
from typing import Any

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from flexsat.input_checks import FieldError, require_finite, require_nonneg, require_positive
from flexsat.structures import elements as el
from flexsat.structures.assembly import (
    DOF_NAMES,
    DOF_SLOT,
    Assembly,
    DependentDofs,
    FEModes,
    IntArray,
    MassProperties,
)
from flexsat.structures.members import (
    AFFINE_SETS,
    DESIGN_QUANTITIES,
    GRID_KEYS,
    KIND_BUILDERS,
    KIND_SLOTS,
    ElementBlocks,
    Member,
    axial_force,
    member_masses,
    with_properties,
)
from flexsat.structures.modal_solve import SYMMETRY_RTOL, factor_positive_definite
from flexsat.structures.sections import Material, Section
from flexsat.units import FloatArray

__all__ = ["DOF_NAMES", "Assembly", "DependentDofs", "FEModes", "MassProperties", "Structure"]

_ZERO_LENGTH_RTOL = 1e-10  # a member shorter than this times its end coordinates is zero-length
_PLANE_RTOL = 1e-9  # |z2 - z1| of a planar member, relative to its length


@dataclass
class _Lumped:
    node: int
    mass: float
    inertia: FloatArray | None
    offset: FloatArray | None = None


# ------------------------------------------------------------------------------------------------
class Structure:
    """A finite-element model built node by node and member by member.

    Parameters
    ----------
    name : str
        Free label.

    Notes
    -----
    Errors are ``ValueError`` with a message starting with the offending field or thing
    (``"node 7: unknown ..."``, ``"E: must be > 0 ..."``) and stating the rule.
    """

    def __init__(self, name: str = "") -> None:
        self.name = name
        self._index: dict[int, int] = {}
        self._ids: list[int] = []
        self._xyz: list[FloatArray] = []
        self._members: list[Member] = []
        self._masses: list[_Lumped] = []
        self._clamped: set[tuple[int, int]] = set()
        self._suppressed: set[tuple[int, int]] = set()  # clamps kept in Assembly.unclamped
        self._links: dict[int, int] = {}  # dependent node index -> independent node index

    # -- nodes ------------------------------------------------------------------------------
    def add_node(self, node_id: int, xyz: npt.ArrayLike) -> None:
        """Add a node with a unique integer id at position ``xyz`` (3,), m."""
        if isinstance(node_id, bool) or not isinstance(node_id, Integral):
            raise FieldError("node_id", f"must be an integer, got {node_id!r}")
        node_id = int(node_id)
        if node_id in self._index:
            raise ValueError(f"node {node_id}: duplicate node id")
        x = require_finite(xyz, f"node {node_id}: xyz")
        if x.shape != (3,):
            raise ValueError(f"node {node_id}: xyz must have 3 coordinates, got shape {x.shape}")
        self._index[node_id] = len(self._ids)
        self._ids.append(node_id)
        self._xyz.append(x)

    @property
    def node_ids(self) -> IntArray:
        """Node ids in insertion order."""
        return np.array(self._ids, dtype=int)

    @property
    def coordinates(self) -> FloatArray:
        """Node positions (n, 3), m, in the order of :attr:`node_ids`."""
        return np.array(self._xyz, dtype=float).reshape(-1, 3)

    @property
    def n_elements(self) -> int:
        """Number of members (element ids are 0 .. n_elements - 1)."""
        return len(self._members)

    def element(self, element: int) -> dict[str, Any]:
        """Description of a member: ``kind``, ``nodes`` (ids), ``label``, ``preload`` (N) and
        ``properties`` (the values of the quantities :meth:`property_derivative` takes, SI)."""
        m = self._members[self._element_index(element)]
        properties = {q: float(m.props[GRID_KEYS.get(q, q)]) for q in DESIGN_QUANTITIES[m.kind]}
        return dict(
            kind=m.kind,
            nodes=(self._ids[m.n1], self._ids[m.n2]),
            label=m.label,
            preload=m.preload,
            properties=properties,
        )

    def _element_index(self, element: object) -> int:
        if (
            isinstance(element, bool)
            or not isinstance(element, Integral)
            or not (0 <= int(element) < len(self._members))
        ):
            raise ValueError(f"element {element!r}: unknown element id")
        return int(element)

    def _node(self, node_id: int) -> int:
        try:
            return self._index[node_id]
        except (KeyError, TypeError):
            raise ValueError(f"node {node_id!r}: unknown node (add it with add_node)") from None

    # -- members ----------------------------------------------------------------------------
    def _add(self, kind: str, n1: int, n2: int, props: dict[str, Any], label: object) -> int:
        member = Member(kind, self._node(n1), self._node(n2), props, label)
        self._members.append(member)
        return len(self._members) - 1

    def _ends(
        self, n1: int, n2: int, offsets: FloatArray | None = None
    ) -> tuple[FloatArray, FloatArray, float]:
        x1, x2 = self._xyz[self._node(n1)], self._xyz[self._node(n2)]
        if offsets is not None:
            x1, x2 = x1 + offsets[0], x2 + offsets[1]
        length = float(np.linalg.norm(x2 - x1))
        if not length > _ZERO_LENGTH_RTOL * max(np.abs(x1).max(), np.abs(x2).max()):
            raise ValueError(f"member ({n1}, {n2}): zero length (its ends coincide)")
        return x1, x2, length

    def _planar(self, n1: int, n2: int) -> None:
        x1, x2, length = self._ends(n1, n2)
        if abs(x2[2] - x1[2]) > _PLANE_RTOL * length:
            raise ValueError(
                f"member ({n1}, {n2}): must lie in a plane z = const (global X-Y plane)"
            )
        if np.linalg.norm(x2[:2] - x1[:2]) <= _ZERO_LENGTH_RTOL * length:
            raise ValueError(f"member ({n1}, {n2}): zero length in the X-Y plane")

    def add_frame(
        self,
        n1: int,
        n2: int,
        material: Material,
        section: Section,
        orientation: npt.ArrayLike | None = None,
        offsets: npt.ArrayLike | None = None,
        lumped: bool = False,
        label: object = None,
    ) -> int:
        """Add a 3-D Euler-Bernoulli frame member (12 dofs); returns its element id.

        Parameters
        ----------
        n1, n2 : int
            End node ids; local x runs from n1 to n2.
        material : Material
        section : Section
            ``Iz`` bends in the local x-y plane, ``Iy`` in the local x-z plane.
        orientation : array_like (3,), optional
            Vector v in the local x-y plane (NASTRAN CBAR): z = x × v, y = z × x.  Default:
            global Z, or global Y for a member parallel to Z.
        offsets : ((3,), (3,)), optional
            Rigid offsets from node n1 and node n2 to the member ends, global axes, m.
        lumped : bool
            HRZ diagonal mass instead of the consistent mass.
        label : optional
            Free label.
        """
        _require_type(material, Material, "material")
        _require_type(section, Section, "section")
        if offsets is not None:
            offsets = require_finite(offsets, "offsets")
            if offsets.shape != (2, 3):
                raise FieldError("offsets", f"must have shape (2, 3), got {offsets.shape}")
        x1, x2, _ = self._ends(n1, n2, offsets)
        if orientation is not None:
            orientation = require_finite(orientation, "orientation")
            if orientation.shape != (3,):
                raise FieldError("orientation", f"must have 3 components, got {orientation.shape}")
        el.frame_rotation(x1, x2, orientation)  # refuses a vector parallel to the axis
        props = dict(
            E=material.E,
            G=material.shear_modulus,
            G_per_E=None if material.G is not None else material.shear_modulus / material.E,
            rho=material.rho,
            A=section.A,
            Iy=section.Iy,
            Iz=section.Iz,
            J=section.J,
            orientation=orientation,
            offsets=offsets,
            lumped=bool(lumped),
        )
        return self._add("frame", n1, n2, props, label)

    def add_beam2d(
        self,
        n1: int,
        n2: int,
        material: Material,
        section: Section,
        lumped: bool = False,
        label: object = None,
    ) -> int:
        """Add a planar beam in the global X-Y plane (dofs ux, uy, rz; bending with ``Iz``)."""
        _require_type(material, Material, "material")
        _require_type(section, Section, "section")
        self._planar(n1, n2)
        props = dict(
            E=material.E, rho=material.rho, A=section.A, Iz=section.Iz, lumped=bool(lumped)
        )
        return self._add("beam2d", n1, n2, props, label)

    def add_grid(
        self,
        n1: int,
        n2: int,
        EI: float,
        GJ: float,
        mass_per_length: float,
        torsional_inertia_per_length: float = 0.0,
        label: object = None,
    ) -> int:
        """Add a grid member in the global X-Y plane (dofs uz, rx, ry).

        Parameters
        ----------
        EI, GJ : float
            Transverse bending and Saint-Venant torsion stiffness, N m^2 (> 0).
        mass_per_length : float
            kg/m (>= 0).
        torsional_inertia_per_length : float
            Polar mass moment of inertia per length, kg m (>= 0; 0 leaves the twist massless).
        """
        self._planar(n1, n2)
        props = dict(
            EI=float(require_positive(EI, "EI")),
            GJ=float(require_positive(GJ, "GJ")),
            m=float(require_nonneg(mass_per_length, "mass_per_length")),
            It=float(require_nonneg(torsional_inertia_per_length, "torsional_inertia_per_length")),
        )
        return self._add("grid", n1, n2, props, label)

    def add_rod(
        self,
        n1: int,
        n2: int,
        material: Material,
        area: float,
        lumped: bool = False,
        label: object = None,
    ) -> int:
        """Add a truss rod (axial stiffness only; dofs ux, uy, uz)."""
        _require_type(material, Material, "material")
        self._ends(n1, n2)
        props = dict(
            E=material.E,
            rho=material.rho,
            A=float(require_positive(area, "area")),
            lumped=bool(lumped),
        )
        return self._add("rod", n1, n2, props, label)

    # -- masses, clamps, preloads -----------------------------------------------------------
    def add_mass(
        self,
        node: int,
        mass: float,
        inertia: npt.ArrayLike | None = None,
        offset: npt.ArrayLike | None = None,
    ) -> None:
        r"""Add a lumped mass (kg), optionally its inertia (kg m^2) and a rigid offset (m).

        ``inertia`` is a 3-vector (principal, global axes) or a symmetric positive
        semi-definite 3x3 matrix, about the mass's own centre; giving it makes the node's
        rotations active.

        ``offset`` places the mass's centre at :math:`r` from the node (global axes), carried
        by a rigid link: its displacement is :math:`u_c = u + \theta \times r = T q` with
        :math:`T = [I \;\; -[r\times]]` on the node's dofs :math:`q = (u, \theta)`, so the
        node receives the 6x6 mass (the rigid-body mass matrix about a point, e.g. Craig &
        Kurdila, *Fundamentals of Structural Dynamics*, 2nd ed., §16.2)

        .. math::

            M_{node} = \begin{bmatrix} m I & -m [r\times] \\ m [r\times] &
                J - m [r\times]^2 \end{bmatrix},

        the parallel-axis theorem on the rotation block. A nonzero offset activates the
        node's rotations.
        """
        index = self._node(node)
        m = float(require_nonneg(mass, "mass"))
        J = None
        if inertia is not None:
            J = require_finite(inertia, "inertia")
            if J.shape == (3,):
                J = np.diag(J)
            if J.shape != (3, 3):
                raise FieldError("inertia", f"must be a 3-vector or 3x3, got shape {J.shape}")
            scale = np.abs(J).max()
            if np.abs(J - J.T).max() > SYMMETRY_RTOL * scale:
                raise FieldError("inertia", "must be symmetric")
            if np.linalg.eigvalsh(J).min() < -SYMMETRY_RTOL * scale:
                raise FieldError("inertia", "must be positive semi-definite")
        r = None
        if offset is not None:
            r = require_finite(offset, "offset")
            if r.shape != (3,):
                raise FieldError("offset", f"must have 3 components, got shape {r.shape}")
            if not r.any():
                r = None
        self._masses.append(_Lumped(index, m, J, r))

    def clamp(
        self, node: int, dofs: str | Iterable[str] = "all", support: bool | None = None
    ) -> None:
        """Fix dofs of a node: ``"all"`` or an iterable of names from :data:`DOF_NAMES`.

        ``support`` says whether the clamp attaches the structure to its carrier (a hub, a
        test fixture), as opposed to suppressing dofs the model does not use (out-of-plane dofs
        of a planar model, an axially rigid member). Supports are released in
        ``Assembly.unclamped``; default: True for ``"all"``, False for a list of dofs.
        """
        index = self._node(node)
        everything = isinstance(dofs, str) and dofs == "all"
        names = DOF_NAMES if everything else dofs
        if isinstance(names, str):
            names = (names,)
        for name in names:
            if name not in DOF_SLOT:
                raise FieldError("dofs", f"unknown dof {name!r} (expected 'all' or {DOF_NAMES})")
            self._clamped.add((index, DOF_SLOT[name]))
            if not (everything if support is None else support):
                self._suppressed.add((index, DOF_SLOT[name]))

    def add_rigid_link(self, independent: int, dependent: Iterable[int]) -> None:
        r"""Tie nodes rigidly to an independent node (NASTRAN RBE2 on all six dofs).

        A dependent node at :math:`r` from the independent one moves with it as a rigid body,
        :math:`u_d = u_i + \theta_i \times r = u_i - [r\times]\theta_i`,
        :math:`\theta_d = \theta_i`; its dofs are eliminated at assembly,
        :math:`K_r = T^T K T`, :math:`M_r = T^T M T` with q = T q_r (Craig & Kurdila,
        *Fundamentals of Structural Dynamics*, 2nd ed., §16.2, rigid-body constraints), and
        recovered in the mode shapes (:meth:`FEModes.at_nodes`). A dependent node cannot be
        clamped, be the independent node of another link or be tied twice.

        Parameters
        ----------
        independent : int
            Node id whose six dofs carry the rigid body.
        dependent : iterable of int
            Node ids tied to it (elements and masses may attach to them).
        """
        master = self._node(independent)
        if master in self._links:
            raise FieldError(
                "independent", f"node {independent} is itself a dependent node of a rigid link"
            )
        for node_id in dependent:
            slave = self._node(node_id)
            if slave == master:
                raise FieldError("dependent", f"node {node_id} is the independent node")
            if slave in self._links:
                raise FieldError("dependent", f"node {node_id} is already rigidly linked")
            if slave in self._links.values():
                raise FieldError(
                    "dependent", f"node {node_id} is the independent node of another rigid link"
                )
            self._links[slave] = master

    def set_axial_preload(self, element: int, force: float) -> None:
        """Set the axial force of a member (tension > 0, N); adds its geometric stiffness."""
        self._members[self._element_index(element)].preload = float(require_finite(force, "force"))

    # -- assembly ---------------------------------------------------------------------------
    def assemble(self) -> Assembly:
        """Sparse K (elastic + geometric) and M on the active dofs.

        A supported structure's assembly also carries ``unclamped``, the assembly with its
        supports released (see :meth:`clamp`): with consistent mass the attachment dofs share
        element mass with the free ones, and hybrid-coordinate (cantilevered) modal models need
        that mass.
        """
        assembly = self._assemble(geometric=True, clamped=self._clamped)
        if self._clamped == self._suppressed:
            return assembly
        whole = self._assemble(geometric=False, clamped=self._suppressed)
        return dataclasses.replace(assembly, unclamped=whole)

    def _assemble(self, geometric: bool, clamped: Collection[tuple[int, int]]) -> Assembly:
        n_nodes = len(self._ids)
        touched = self._touched()
        parts = []
        for kind in KIND_SLOTS:
            members = [m for m in self._members if m.kind == kind]
            if members:
                parts.append(KIND_BUILDERS[kind](members, self.coordinates, geometric))
        if self._masses:
            parts.append(self._mass_blocks())
        _check_connected(touched, self._ids)
        active = self._active(touched, clamped)
        number = np.full(6 * n_nodes, -1)
        number[active.ravel()] = np.arange(int(active.sum()))
        K = _sparse(number, [(idx, k) for idx, k, _ in parts])
        M = _sparse(number, [(idx, m) for idx, _, m in parts])
        recovery = None
        if self._links:
            K, M, active, recovery = self._eliminate_links(K, M, active, number)
        node_idx, slot_idx = np.nonzero(active)
        dofs = [(self._ids[i], DOF_NAMES[s]) for i, s in zip(node_idx, slot_idx)]
        return Assembly(
            K,
            M,
            dofs,
            self.node_ids,
            self.coordinates,
            n_clamped=len(clamped),
            dependent=recovery,
        )

    def _eliminate_links(
        self,
        K: sp.csr_matrix,
        M: sp.csr_matrix,
        active: npt.NDArray[np.bool_],
        number: IntArray,
    ) -> tuple[sp.csr_matrix, sp.csr_matrix, npt.NDArray[np.bool_], DependentDofs]:
        """K and M reduced to the independent dofs by q = T q_r (:meth:`add_rigid_link`), the
        kept active mask and the recovery of the dependent dofs from the kept ones."""
        kept = active.copy()
        slaves = np.array(sorted(self._links))
        kept[slaves, :] = False
        reduced = np.full(6 * len(self._ids), -1)
        reduced[kept.ravel()] = np.arange(int(kept.sum()))
        n_active, n_kept = int(active.sum()), int(kept.sum())
        rows, cols, vals = [], [], []
        kept_slots = np.flatnonzero(kept.ravel())
        rows += list(number[kept_slots])
        cols += list(reduced[kept_slots])
        vals += [1.0] * kept_slots.size
        g_rows, g_cols, g_vals = [], [], []
        dependent_slots = []
        for slave in slaves:
            master = self._links[int(slave)]
            link = np.eye(6)
            link[:3, 3:] = -el.skew(self.coordinates[slave] - self.coordinates[master])
            for a in range(6):
                dependent_slots.append(6 * slave + a)
                for b in np.flatnonzero(link[a]):
                    column = reduced[6 * master + b]
                    if column < 0:  # a clamped dof of the independent node: zero motion
                        continue
                    rows.append(number[6 * slave + a])
                    cols.append(column)
                    vals.append(link[a, b])
                    g_rows.append(len(dependent_slots) - 1)
                    g_cols.append(column)
                    g_vals.append(link[a, b])
        T = sp.csr_matrix((vals, (rows, cols)), shape=(n_active, n_kept))
        K_r = (T.T @ K @ T).tocsr()
        M_r = (T.T @ M @ T).tocsr()
        G = sp.csr_matrix((g_vals, (g_rows, g_cols)), shape=(len(dependent_slots), n_kept))
        slots = np.array(dependent_slots)
        recovery = DependentDofs(slots // 6, slots % 6, G)
        return ((K_r + K_r.T) * 0.5).tocsr(), ((M_r + M_r.T) * 0.5).tocsr(), kept, recovery

    def _mass_blocks(self) -> ElementBlocks:
        """(global slot indices, K blocks, M blocks) of the lumped masses (6x6 each)."""
        idx = np.array([6 * lm.node + np.arange(6) for lm in self._masses])
        M = np.zeros((len(self._masses), 6, 6))
        for i, lm in enumerate(self._masses):
            M[i, :3, :3] = lm.mass * np.eye(3)
            if lm.inertia is not None:
                M[i, 3:, 3:] = lm.inertia
            if lm.offset is not None:  # rigid link to the mass centre (add_mass)
                T = np.eye(6)
                T[:3, 3:] = -el.skew(lm.offset)
                M[i] = T.T @ M[i] @ T
        return idx, np.zeros_like(M), M

    # -- derivatives with respect to member properties --------------------------------------
    def property_derivative(
        self, direction: str | Mapping[str, float], elements: Iterable[int]
    ) -> tuple[sp.csr_matrix, sp.csr_matrix, float]:
        """∂K/∂q, ∂M/∂q on the active dofs of :meth:`assemble`, and ∂(member mass)/∂q.

        q is one property shared by the members ``elements`` (a design group), changed by the
        same amount in each, or a direction in the space of several properties (then the
        derivative is Σ c_q ∂/∂q, e.g. ∂A/∂t, ∂Iy/∂t, ... of a section dimension t). Every
        element matrix of :mod:`flexsat.structures.elements` is affine in the section
        properties (A, Iy, Iz, J) jointly, with E, G, ρ held, and in the material properties
        (E, G, ρ) jointly, with the section held: EA, GJ, EI_y, EI_z, ρA, ρ(I_y + I_z) (and
        EI, GJ, m, I_t of a grid) each enter linearly (Przemieniecki 1968 ch. 5 and 11). So
        Σ c_q ∂k/∂q = k(q = c) − k(q = 0) with the other properties held: exact, not a
        difference quotient. Axial preloads are held fixed (their geometric stiffness does not
        depend on q).

        Parameters
        ----------
        direction : str or mapping of str to float
            One quantity (coefficient 1) or {quantity: coefficient}, all of one jointly affine
            set. Frame: section ``"A"``, ``"Iy"``, ``"Iz"``, ``"J"``; material ``"E"``,
            ``"G"``, ``"rho"``. Planar beam: ``"A"``, ``"Iz"`` / ``"E"``, ``"rho"``. Rod:
            ``"A"`` / ``"E"``, ``"rho"``. Grid (one set): ``"EI"``, ``"GJ"``,
            ``"mass_per_length"``, ``"torsional_inertia_per_length"``. ``"E"`` of a frame
            whose material has no explicit G also scales G = E / (2 (1 + ν)); with an explicit
            G it leaves G alone.
        elements : iterable of int
            Element ids of the group (non-empty, no repeats).

        Returns
        -------
        dK, dM : scipy.sparse.csr_matrix (ndof, ndof)
            Rows and columns as :meth:`assemble` (the supported, clamped dofs).
        dmass : float
            Derivative of the members' total mass (Σ ρ A L, or Σ m L for grids), kg per unit q.
        """
        coef = {direction: 1.0} if isinstance(direction, str) else dict(direction)
        if not coef:
            raise FieldError("direction", "must name at least one property")
        for quantity, value in coef.items():
            coef[quantity] = float(require_finite(value, f"direction[{quantity!r}]"))
        ids = [self._element_index(e) for e in elements]
        if not ids:
            raise FieldError("elements", "must name at least one element")
        if len(set(ids)) != len(ids):
            raise FieldError("elements", f"must not repeat an element, got {ids}")
        active = self._active(self._touched(), self._clamped)
        number = np.full(active.size, -1)
        number[active.ravel()] = np.arange(int(active.sum()))
        k_parts, m_parts, dmass = [], [], 0.0
        for kind in KIND_SLOTS:
            members = [self._members[i] for i in ids if self._members[i].kind == kind]
            if not members:
                continue
            sets = AFFINE_SETS[kind]
            if not any(set(coef) <= group for group in sets):
                raise FieldError(
                    "quantity",
                    f"{sorted(coef)} are not properties of one affine set of a {kind} member "
                    f"(expected a subset of one of {[sorted(g) for g in sets]})",
                )
            if "G" in coef and any(m.props["G_per_E"] is not None for m in members):
                raise FieldError(
                    "quantity",
                    "'G' of a material without an explicit G follows E = 2 (1 + ν) G; "
                    "differentiate 'E' (or give the material its own G)",
                )
            changed = [with_properties(m, coef) for m in members]
            zero = [with_properties(m, dict.fromkeys(coef, 0.0)) for m in members]
            idx, k, m = KIND_BUILDERS[kind](changed + zero, self.coordinates, False)
            n = len(members)
            k_parts.append((idx[:n], k[:n] - k[n:]))
            m_parts.append((idx[:n], m[:n] - m[n:]))
            masses = member_masses(changed + zero, self.coordinates)
            dmass += float(np.sum(masses[:n] - masses[n:]))
        dK, dM = _sparse(number, k_parts), _sparse(number, m_parts)
        if self._links:  # the same q = T q_r as the assembly: Tᵀ dK T is linear in dK
            dK, dM, _, _ = self._eliminate_links(dK, dM, active, number)
        return dK, dM, dmass

    def _touched(self) -> npt.NDArray[np.bool_]:
        """(n_nodes, 6): the dofs an element or a lumped mass touches."""
        touched = np.zeros((len(self._ids), 6), dtype=bool)
        for kind, slots in KIND_SLOTS.items():
            ends = np.array([(m.n1, m.n2) for m in self._members if m.kind == kind], dtype=int)
            if ends.size:
                touched[ends.ravel()[:, None], np.array(slots)[None, :]] = True
        for lm in self._masses:
            touched[lm.node, :3] = True
            touched[lm.node, 3:] |= lm.inertia is not None or lm.offset is not None
        for slave, master in self._links.items():
            touched[[slave, master], :] = True
        return touched

    def _active(
        self, touched: npt.NDArray[np.bool_], clamped: Collection[tuple[int, int]]
    ) -> npt.NDArray[np.bool_]:
        """(n_nodes, 6): the touched dofs less the clamped ones (before link elimination)."""
        active = touched.copy()
        for node, slot in clamped:
            if node in self._links:
                raise FieldError(
                    "clamp",
                    f"node {self._ids[node]} is a dependent node of a rigid link; clamp its "
                    f"independent node {self._ids[self._links[node]]}",
                )
            active[node, slot] = False
        if not active.any():
            raise FieldError("structure", "no active dofs (every dof is clamped)")
        return active

    def structural_mass(self) -> float:
        """Total mass of the members (Σ ρ A L; Σ m L for grids) and lumped masses, kg."""
        members = float(
            sum(
                np.sum(
                    member_masses([m for m in self._members if m.kind == kind], self.coordinates)
                )
                for kind in KIND_SLOTS
                if any(m.kind == kind for m in self._members)
            )
        )
        return members + sum(lm.mass for lm in self._masses)

    # -- preloads from gravity --------------------------------------------------------------
    def gravity_preload(self, g: npt.ArrayLike = (0.0, 0.0, -9.80665)) -> FloatArray:
        """Set every member's axial preload from a linear static solve under gravity.

        The load is ``f = M a`` with ``a`` the uniform acceleration field ``g`` on the
        translations and M the mass matrix before clamping (consistent or lumped member mass
        plus the lumped masses), solved on the free dofs with the elastic K (no geometric
        stiffness).  Each frame, rod and planar beam gets the
        axial force ``EA/L x̂·(u2 - u1)`` of its ends; grid members carry no axial force (0).
        Previous preloads are replaced.

        Parameters
        ----------
        g : array_like (3,)
            Gravity acceleration, m/s^2.

        Returns
        -------
        ndarray (n_elements,)
            Axial forces by element id, N (tension > 0).
        """
        g = require_finite(g, "g")
        if g.shape != (3,):
            raise FieldError("g", f"must have 3 components, got shape {g.shape}")
        if self._links:
            raise FieldError(
                "gravity_preload", "not available with rigid links (add_rigid_link) yet"
            )
        if not self._clamped:
            raise FieldError(
                "gravity_preload",
                "the structure must be clamped (a free structure has no static "
                "equilibrium under gravity)",
            )
        free = self._assemble(geometric=False, clamped=())
        f = free.M @ (free.rigid_body_vectors()[:, :3] @ g)
        asm = self._assemble(geometric=False, clamped=self._clamped)
        keys = 6 * free._node_of_dof + free._slot_of_dof  # ascending
        u = _static_solve(asm.K, f[np.searchsorted(keys, 6 * asm._node_of_dof + asm._slot_of_dof)])
        displacement = np.zeros((len(self._ids), 6))
        displacement[asm._node_of_dof, asm._slot_of_dof] = u
        forces = np.array([axial_force(m, self.coordinates, displacement) for m in self._members])
        for member, force in zip(self._members, forces):
            member.preload = float(force)
        return forces


def _require_type(value: object, cls: type, field: str) -> None:
    if not isinstance(value, cls):
        raise FieldError(field, f"must be a {cls.__name__}, got {type(value).__name__}")


def _check_connected(touched: npt.NDArray[np.bool_], ids: Sequence[int]) -> None:
    loose = np.flatnonzero(~touched.any(axis=1))
    if loose.size:
        raise ValueError(f"node {ids[loose[0]]}: not connected to any element or mass")


def _sparse(number: IntArray, blocks: Iterable[tuple[IntArray, FloatArray]]) -> sp.csr_matrix:
    """Sum element blocks (global slot indices (n, d), matrices (n, d, d)) on the active dofs."""
    rows, cols, vals = [], [], []
    for idx, mat in blocks:
        d = idx.shape[1]
        r = np.broadcast_to(number[idx][:, :, None], (len(idx), d, d)).ravel()
        c = np.broadcast_to(number[idx][:, None, :], (len(idx), d, d)).ravel()
        keep = (r >= 0) & (c >= 0) & (mat.ravel() != 0)
        rows.append(r[keep])
        cols.append(c[keep])
        vals.append(mat.ravel()[keep])
    n = int(number.max()) + 1
    A = sp.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    ).tocsr()
    return ((A + A.T) * 0.5).tocsr()


def _static_solve(K: sp.csr_matrix, f: FloatArray) -> FloatArray:
    """u = K^{-1} f for a K that must be positive definite (L D L^T, see modal_solve)."""
    try:
        u: FloatArray = factor_positive_definite(K).solve(f)
        return u
    except ValueError:
        raise FieldError(
            "gravity_preload", "stiffness matrix is singular (a mechanism, or too few clamps)"
        ) from None
