r"""Modal model of a flexible body: the flexible-body object every later module consumes.

Think of a NASTRAN modal superelement: natural frequencies, modal damping, mass-normalised mode
shapes at a set of nodes, the rigid-body mass matrix and the rigid–elastic coupling. SI inside.

Conventions
-----------
Each node carries six degrees of freedom in global axes, ``(ux, uy, uz, rx, ry, rz)``; a dof
the underlying model does not have reads zero in every mode. With m modes the physical
displacements are :math:`u = \Phi \eta` and the shapes are mass normalised,
:math:`\Phi^T M \Phi = I`, so the modal coordinates η have units of :math:`\sqrt{kg}\,m`,
translation shapes :math:`kg^{-1/2}` and rotation shapes :math:`kg^{-1/2} m^{-1}`.

Rigid motion about the ``reference`` point p is described by the 6-vector of a translation and
a small rotation, mapped to the dofs by the rigid-body vectors R: a node at :math:`r` relative to
p moves by :math:`t + \theta \times r` and rotates by θ. Then

.. math::

    M_{rr} = R^T M R = \begin{bmatrix} m I & -m [c\times] \\ m [c\times] & I_p \end{bmatrix},
    \qquad L = \Phi^T M R \;\; (m \times 6),

with c the centre of mass relative to p, :math:`I_p` the inertia about p and L the modal
momentum (participation) integrals; for a lumped-mass model
:math:`L_{i,t} = \sum_k m_k \phi_{ik}` and
:math:`L_{i,\theta} = \sum_k (m_k\, r_k \times \phi_{ik} + J_k \psi_{ik})`.
Because the shapes are M-orthonormal, Bessel's inequality :math:`L^T L \preceq M_{rr}` holds
(with equality for a complete set); it is checked on construction.

Boundary
--------
``"free"``: modes of the unconstrained body; rigid modes (ω ≈ 0) may come first.
``"cantilevered"``: modes with the attachment at p fixed; rigid motion is carried separately
(hybrid coordinates). Attached to a rigid body moving with rigid coordinates :math:`x_r`, the
linearised equations are

.. math::

    \begin{bmatrix} M_{rr} & L^T \\ L & I \end{bmatrix}
    \begin{bmatrix} \ddot x_r \\ \ddot \eta \end{bmatrix}
    + \begin{bmatrix} 0 & 0 \\ 0 & \mathrm{diag}(2\zeta\omega) \end{bmatrix}
    \begin{bmatrix} \dot x_r \\ \dot \eta \end{bmatrix}
    + \begin{bmatrix} 0 & 0 \\ 0 & \mathrm{diag}(\omega^2) \end{bmatrix}
    \begin{bmatrix} x_r \\ \eta \end{bmatrix} = \begin{bmatrix} f_r \\ \Phi^T f \end{bmatrix}.

Models with fewer than six dofs per node
----------------------------------------
A plane model (e.g. a grid with uz, rx, ry only) cannot represent every rigid motion: the
corresponding rows of :math:`M_{rr}` and columns of L are zero. Mass properties are then those of
the rigid motions the model has: a translation is present when its diagonal mass is > 0, a
rotation when its inertia about p is > 0 or both translations normal to its axis are present;
absent ones read zero.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, TypeAlias

import numpy as np
import numpy.typing as npt
from scipy.sparse import issparse
from scipy.sparse.linalg import norm as sparse_norm

from flexsat.input_checks import FieldError, require_count, require_finite, require_nonneg
from flexsat.netcdf import write_netcdf
from flexsat.units import FloatArray

__all__ = [
    "BOUNDARIES",
    "DOFS",
    "FORMAT_VERSION",
    "RIGID_FREQUENCY",
    "ModalModel",
    "hub_appendage_matrices",
]

#: Dof order of the last axis of ``ModalModel.shapes``.
DOFS = ("ux", "uy", "uz", "rx", "ry", "rz")
BOUNDARIES = ("free", "cantilevered")
#: Version written to (and required from) the ``flexsat_modal_model_version`` file attribute.
FORMAT_VERSION = 1
#: Modes at or below this frequency are rigid-body modes for :meth:`ModalModel.elastic`, rad/s.
#: A structural mode of a spacecraft below 0.01 rad/s (1.6 mHz, ~10 × orbital rate) is not
#: plausible, while the rigid modes of a free-free eigen-solve come out as roundoff-size ω.
RIGID_FREQUENCY = 1e-2

if TYPE_CHECKING:
    import control
    from flexsat.structures.beam import TipMassCantilever
    from flexsat.structures.fem import FEModes

#: a direction: ``"x"``, ``"y"``, ``"z"`` or a 3-vector, or a list of them / a (k, 3) array
Direction: TypeAlias = npt.ArrayLike
#: an output of :meth:`ModalModel.to_second_order`: (influence vector, "displacement" or
#: "velocity")
Output: TypeAlias = tuple[npt.ArrayLike, str]


class HubAppendageParameters(Protocol):
    """What :meth:`ModalModel.from_hub_appendage` reads of
    :class:`flexsat.dynamics.hub_appendage.HubAppendageParams` (a higher layer)."""

    @property
    def n_appendages(self) -> int: ...
    @property
    def length(self) -> float: ...
    @property
    def hub_radius(self) -> float: ...
    @property
    def tip_radius(self) -> float: ...
    @property
    def tip_mass(self) -> float: ...
    @property
    def tip_inertia(self) -> float: ...
    @property
    def rho(self) -> float: ...
    @property
    def EI(self) -> float: ...
    def beam(self) -> TipMassCantilever: ...


class HubAppendageModel(Protocol):
    """What :meth:`ModalModel.from_hub_appendage` reads of
    :class:`flexsat.dynamics.hub_appendage.HubAppendage` (a higher layer)."""

    @property
    def params(self) -> HubAppendageParameters: ...
    @property
    def n_modes(self) -> int: ...
    @property
    def cantilever_frequencies(self) -> FloatArray: ...
    @property
    def coupling(self) -> FloatArray: ...
    @property
    def damping_ratios(self) -> FloatArray: ...


_AXES = ("x", "y", "z")
_TOL = 1e-9  # relative tolerance of the rigid-mass checks (roundoff of R^T M R is ~1e-14)
_FREE_STIFFNESS_TOL = 1e-9  # ||K R|| / (||K|| ||R||) below which an FE model is free


# ------------------------------------------------------------------------------------------------
# small linear-algebra helpers
def _skew(v: FloatArray) -> FloatArray:
    """Cross-product matrix [v×], so that [v×] w = v × w."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _rigid_mass_from_moments(
    mass: float, first_moment: FloatArray, second_moment: FloatArray, rotary: FloatArray
) -> FloatArray:
    r"""Rigid-body mass matrix about p from the moments of the mass distribution.

    .. math::

        M_{rr} = \begin{bmatrix} m I & -[s\times] \\ [s\times] & \mathrm{tr}(P) I - P + J
        \end{bmatrix}, \qquad s = \int r\, dm, \quad P = \int r r^T dm,

    with J the rotary inertia of the bodies about their own centres.
    """
    s = _skew(first_moment)
    rot = np.trace(second_moment) * np.eye(3) - second_moment + rotary
    return np.block([[mass * np.eye(3), -s], [s, rot]])


def _scales(rigid_mass: FloatArray) -> FloatArray:
    """√diag of the rigid mass (1 where zero): makes the 6x6 checks unit-free."""
    d = np.sqrt(np.clip(np.diag(rigid_mass), 0.0, None))
    return np.where(d > 0, d, 1.0)


def _first_moment(rigid_mass: FloatArray) -> FloatArray:
    """s = m c from the rotation–translation block [s×] (an entry absent in a plane model is 0)."""
    B = rigid_mass[3:, :3]
    s = np.zeros(3)
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3  # [s×]_ji = s_k = −[s×]_ij
        s[k] = B[j, i] if B[j, i] != 0 else -B[i, j]
    return s


def _present(rigid_mass: FloatArray) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """Which rigid translations and rotations the model has (see module docstring)."""
    d = np.diag(rigid_mass)
    trans = d[:3] > 0
    normal = np.array([trans[(k + 1) % 3] and trans[(k + 2) % 3] for k in range(3)])
    return trans, (d[3:] > 0) | normal


# ------------------------------------------------------------------------------------------------
# validation
def _array(value: npt.ArrayLike, field: str, shape: tuple[int, ...], names: str) -> FloatArray:
    arr = require_finite(value, field)
    if arr.shape != shape:
        raise FieldError(field, f"must have shape {names} = {shape}, got {arr.shape}")
    return arr


def _node_ids(value: npt.ArrayLike) -> npt.NDArray[np.int64]:
    ids = require_finite(value, "node_ids")
    if ids.ndim != 1 or ids.size == 0:
        raise FieldError("node_ids", f"must be a non-empty 1-D array, got shape {ids.shape}")
    if np.any(ids != np.rint(ids)):
        raise FieldError("node_ids", f"must be integers, got {value!r}")
    integers = ids.astype(np.int64)
    unique, counts = np.unique(integers, return_counts=True)
    if np.any(counts > 1):
        raise FieldError("node_ids", f"must be unique, repeated {unique[counts > 1].tolist()}")
    return integers


def _frequencies(value: npt.ArrayLike) -> FloatArray:
    w = require_nonneg(value, "frequencies")
    if w.ndim != 1 or w.size == 0:
        raise FieldError("frequencies", f"must be a 1-D array of at least one mode, got {w.shape}")
    if np.any(np.diff(w) < 0):
        raise FieldError("frequencies", "must be in ascending order")
    return w


def _damping(value: npt.ArrayLike, n_modes: int) -> FloatArray:
    zeta = require_nonneg(value, "damping")
    if zeta.ndim == 0:
        return np.full(n_modes, float(zeta))
    if zeta.shape != (n_modes,):
        raise FieldError(
            "damping", f"must be a scalar or have shape (m,) = ({n_modes},), got {zeta.shape}"
        )
    return zeta


def _check_rigid_mass(rigid_mass: FloatArray) -> None:
    """Symmetric, positive semi-definite, translational block m·I, coupling block [s×]."""
    d = _scales(rigid_mass)
    S = rigid_mass / np.outer(d, d)
    if np.max(np.abs(S - S.T)) > _TOL:
        raise FieldError("rigid_mass", "must be symmetric")
    if np.linalg.eigvalsh(0.5 * (S + S.T)).min() < -_TOL:
        raise FieldError("rigid_mass", "must be positive semi-definite")
    trans, _ = _present(rigid_mass)
    if not trans.any():
        raise FieldError("rigid_mass", "total mass must be > 0 (translational diagonal is zero)")
    masses = np.diag(rigid_mass)[:3][trans]
    off = S[:3, :3] - np.diag(np.diag(S[:3, :3]))
    if np.ptp(masses) > _TOL * masses.max() or np.max(np.abs(off)) > _TOL:
        raise FieldError(
            "rigid_mass", "translational block must be m·I (0 for absent translations)"
        )
    rows = np.diag(rigid_mass)[3:] > 0
    mask = np.outer(rows, trans)
    misfit = (rigid_mass[3:, :3] - _skew(_first_moment(rigid_mass))) / np.outer(d[3:], d[:3])
    if np.max(np.abs(misfit[mask]), initial=0.0) > _TOL:
        raise FieldError("rigid_mass", "rotation–translation block must be m[c×] (skew)")


def _check_bessel(rigid_mass: FloatArray, participation: FloatArray) -> None:
    r"""Mass-normalised modes satisfy :math:`L^T L \preceq M_{rr}` (Bessel's inequality)."""
    d = _scales(rigid_mass)
    gap = (rigid_mass - participation.T @ participation) / np.outer(d, d)
    if np.linalg.eigvalsh(0.5 * (gap + gap.T)).min() < -_TOL:
        raise FieldError(
            "participation",
            "Lᵀ L exceeds rigid_mass (mass-normalised modes must satisfy "
            "Bessel's inequality Lᵀ L <= rigid_mass); check the normalisation of the shapes",
        )


def _boundary(value: str) -> str:
    if value not in BOUNDARIES:
        raise FieldError("boundary", f"must be one of {BOUNDARIES}, got {value!r}")
    return value


def _frozen(arr: npt.NDArray[Any]) -> npt.NDArray[Any]:
    arr = np.array(arr)
    arr.flags.writeable = False
    return arr


# ------------------------------------------------------------------------------------------------
# directions
_AXIS_VECTORS = dict(zip(_AXES, np.eye(3)))


def _is_single(direction: Any) -> bool:
    """A name or one vector (also a malformed scalar, refused later), not a list of them."""
    if isinstance(direction, str) or np.ndim(direction) == 0:
        return True
    return np.ndim(direction) == 1 and not any(isinstance(d, str) for d in direction)


def _directions(direction: Any, field: str) -> tuple[FloatArray, bool]:
    """Unit direction rows (k, 3) from 'x'/'y'/'z' or vectors, and whether one was given."""
    try:
        single = _is_single(direction)
        items = [direction] if single else list(direction)
        rows = [_AXIS_VECTORS[d] if isinstance(d, str) else np.asarray(d, float) for d in items]
        vecs: FloatArray | None = np.array(rows, dtype=float)
    except (KeyError, ValueError, TypeError):
        vecs = None
    if vecs is None or vecs.ndim != 2 or vecs.shape[1] != 3 or vecs.shape[0] == 0:
        raise FieldError(
            field, f"must be 'x', 'y', 'z' or a 3-vector (or a list of them), got {direction!r}"
        )
    norms = np.linalg.norm(vecs, axis=1)
    if not np.all(np.isfinite(norms)) or np.any(norms == 0):
        raise FieldError(field, f"must be a finite non-zero direction, got {direction!r}")
    return vecs / norms[:, None], single


def _axis_index(axis: int | str) -> int:
    if isinstance(axis, str) and axis in _AXES:
        return _AXES.index(axis)
    if isinstance(axis, (int, np.integer)) and not isinstance(axis, bool) and 0 <= axis <= 2:
        return int(axis)
    raise FieldError("axis", f"must be 0, 1, 2 or 'x', 'y', 'z', got {axis!r}")


# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class ModalModel:
    r"""Flexible body in modal form (see the module docstring for the conventions).

    Parameters
    ----------
    node_ids : array_like of int, shape (n,)
        Unique node identifiers.
    coordinates : array_like, shape (n, 3)
        Node positions, m.
    frequencies : array_like, shape (m,)
        Natural frequencies ω, rad/s, >= 0 and ascending.
    damping : float or array_like, shape (m,)
        Modal damping ratios ζ >= 0.
    shapes : array_like, shape (m, n, 6)
        Mass-normalised mode shapes at the nodes, dofs (ux, uy, uz, rx, ry, rz); zero where a
        dof does not exist.
    rigid_mass : array_like, shape (6, 6)
        :math:`M_{rr} = R^T M R` about ``reference``.
    participation : array_like, shape (m, 6)
        Modal momentum integrals :math:`L = \Phi^T M R` (translation x, y, z; rotation about
        ``reference`` x, y, z).
    reference : array_like, shape (3,)
        Point about which rigid motion is described (attachment point if cantilevered), m.
    boundary : {"free", "cantilevered"}

    Raises
    ------
    ValueError
        Message starts with the field: non-finite values, inconsistent shapes, negative or
        unsorted frequencies, negative damping, duplicate node ids, a rigid mass that is not
        symmetric, positive semi-definite, m·I in translation and [s×] in coupling, or a
        participation violating :math:`L^T L \preceq M_{rr}`.
    """

    node_ids: npt.NDArray[np.int64]
    coordinates: FloatArray
    frequencies: FloatArray
    damping: FloatArray
    shapes: FloatArray
    rigid_mass: FloatArray
    participation: FloatArray
    reference: FloatArray = field(default_factory=lambda: np.zeros(3))
    boundary: str = "free"

    def __post_init__(self) -> None:
        ids = _node_ids(self.node_ids)
        w = _frequencies(self.frequencies)
        m, n = w.size, ids.size
        coordinates = _array(self.coordinates, "coordinates", (n, 3), "(n, 3)")
        damping = _damping(self.damping, m)
        shapes = _array(self.shapes, "shapes", (m, n, 6), "(m, n, 6)")
        rigid_mass = _array(self.rigid_mass, "rigid_mass", (6, 6), "(6, 6)")
        participation = _array(self.participation, "participation", (m, 6), "(m, 6)")
        reference = _array(self.reference, "reference", (3,), "(3,)")
        _check_rigid_mass(rigid_mass)
        _check_bessel(rigid_mass, participation)
        fields: dict[str, npt.NDArray[Any]] = dict(
            node_ids=ids,
            coordinates=coordinates,
            frequencies=w,
            damping=damping,
            shapes=shapes,
            rigid_mass=rigid_mass,
            participation=participation,
            reference=reference,
        )
        for name, value in fields.items():
            object.__setattr__(self, name, _frozen(value))
        object.__setattr__(self, "boundary", _boundary(self.boundary))

    def __repr__(self) -> str:
        f = self.frequencies_hz
        return (
            f"ModalModel(boundary={self.boundary!r}, n_modes={self.n_modes}, "
            f"n_nodes={self.node_ids.size}, {f[0]:.4g}–{f[-1]:.4g} Hz, "
            f"mass={self.total_mass:.6g} kg)"
        )

    # --------------------------------------------------------------------------------------------
    # sizes and mass properties
    @property
    def n_modes(self) -> int:
        return self.frequencies.size

    @property
    def frequencies_hz(self) -> FloatArray:
        """Natural frequencies ω / 2π, Hz."""
        return self.frequencies / (2 * np.pi)

    @property
    def total_mass(self) -> float:
        """m, kg (the diagonal of the translational block of ``rigid_mass``)."""
        return float(np.diag(self.rigid_mass)[:3].max())

    @property
    def center_of_mass(self) -> FloatArray:
        """Centre of mass p + c, m, with m[c×] the rotation–translation block of ``rigid_mass``."""
        return self.reference + _first_moment(self.rigid_mass) / self.total_mass

    def inertia(self, about: npt.ArrayLike | None = None) -> FloatArray:
        r"""Inertia tensor about a point, kg m², by the parallel-axis theorem.

        .. math::

            I_a = I_p + m [c\times]^2 - m [(c - a)\times]^2,

        with :math:`I_p` the rotation block of ``rigid_mass``, c the centre of mass and a the
        point, both relative to p (:math:`-m[r\times]^2 = m(|r|^2 I - r r^T)`).

        Parameters
        ----------
        about : array_like, shape (3,), optional
            Point, m, in the frame of ``coordinates``; default the centre of mass.
        """
        m = self.total_mass
        c = _first_moment(self.rigid_mass) / m
        a = c if about is None else _array(about, "about", (3,), "(3,)") - self.reference
        shift = m * (_skew(c) @ _skew(c) - _skew(c - a) @ _skew(c - a))
        _, rot = _present(self.rigid_mass)
        return self.rigid_mass[3:, 3:] + np.where(np.outer(rot, rot), shift, 0.0)

    # --------------------------------------------------------------------------------------------
    # mode selection
    def _select(self, keep: npt.NDArray[np.bool_], caller: str) -> ModalModel:
        if not np.any(keep):
            raise ValueError(f"{caller}: no mode left")
        return replace(
            self,
            frequencies=self.frequencies[keep],
            damping=self.damping[keep],
            shapes=self.shapes[keep],
            participation=self.participation[keep],
        )

    def truncate(
        self, n_modes: int | None = None, max_frequency: float | None = None
    ) -> ModalModel:
        """Keep the first ``n_modes`` modes and/or those with ω <= ``max_frequency`` (rad/s)."""
        if n_modes is None and max_frequency is None:
            raise FieldError("truncate", "give n_modes, max_frequency or both")
        keep = np.ones(self.n_modes, dtype=bool)
        if n_modes is not None:
            keep[require_count(n_modes, "n_modes") :] = False
        if max_frequency is not None:
            keep &= self.frequencies <= require_nonneg(max_frequency, "max_frequency")
        return self._select(keep, "truncate")

    def elastic(self, rigid_frequency: float = RIGID_FREQUENCY) -> ModalModel:
        """Drop the rigid-body modes, those with ω <= ``rigid_frequency`` (rad/s)."""
        rigid = self.frequencies <= require_nonneg(rigid_frequency, "rigid_frequency")
        return self._select(~rigid, "elastic")

    # --------------------------------------------------------------------------------------------
    # modal influence vectors
    def _node(self, node: int, field: str = "node") -> FloatArray:
        """Shapes (m, 6) at one node."""
        is_id = isinstance(node, (int, np.integer)) and not isinstance(node, bool)
        hits = np.flatnonzero(self.node_ids == node) if is_id else np.zeros(0, dtype=np.intp)
        if len(hits) != 1:
            shown = ", ".join(map(str, self.node_ids[:8]))
            shown += " ..." if self.node_ids.size > 8 else ""
            raise FieldError(field, f"unknown node {node!r} (nodes: {shown})")
        return self.shapes[:, hits[0], :]

    def _project(self, block: FloatArray, direction: Direction, field: str) -> FloatArray:
        vecs, single = _directions(direction, field)
        out = block @ vecs.T
        return out[:, 0] if single else out

    def _relative_rotation(self, node_a: int, node_b: int) -> FloatArray:
        rot_a, rot_b = self._node(node_a, "node_a")[:, 3:], self._node(node_b, "node_b")[:, 3:]
        if node_a == node_b:
            raise FieldError("node_b", f"must differ from node_a ({node_a!r})")
        return rot_b - rot_a

    def force_input(self, node: int, direction: Direction) -> FloatArray:
        r"""Modal force of a unit force at ``node`` along ``direction``: :math:`\Phi_t^T d`.

        ``direction`` is 'x', 'y', 'z' or a 3-vector (normalised), shape (m,); or a list of
        those / a (k, 3) array, shape (m, k). Units kg^-1/2 (modal force per newton).
        """
        return self._project(self._node(node)[:, :3], direction, "direction")

    def torque_input(self, node: int, axis: Direction) -> FloatArray:
        r"""Modal force of a unit moment at ``node`` about ``axis``: :math:`\Phi_r^T a`."""
        return self._project(self._node(node)[:, 3:], axis, "axis")

    def moment_pair(self, node_a: int, node_b: int, axis: Direction) -> FloatArray:
        r"""Equal and opposite unit moments, +a at ``node_b`` and −a at ``node_a``.

        A piezoelectric patch between two nodes: :math:`(\Phi_{r,b} - \Phi_{r,a})^T a`.
        """
        return self._project(self._relative_rotation(node_a, node_b), axis, "axis")

    def displacement_output(self, node: int, direction: Direction) -> FloatArray:
        r"""Row c with :math:`d \cdot u_{node} = c^T \eta` (collocated with force_input)."""
        return self.force_input(node, direction)

    def rotation_output(self, node: int, axis: Direction) -> FloatArray:
        r"""Row c with :math:`a \cdot \theta_{node} = c^T \eta` (collocated with torque_input)."""
        return self.torque_input(node, axis)

    def strain_output(self, node_a: int, node_b: int, axis: Direction) -> FloatArray:
        r"""Relative rotation :math:`a \cdot (\theta_b - \theta_a) = c^T \eta` of the patch ends.

        The collocated piezoelectric sensor of :meth:`moment_pair` (same vector).
        """
        return self.moment_pair(node_a, node_b, axis)

    # --------------------------------------------------------------------------------------------
    # system matrices
    def _influence(self, vector: npt.ArrayLike, field: str) -> FloatArray:
        """One influence vector (m,) or matrix (m, k) as columns (m, k)."""
        arr = require_finite(vector, field)
        arr = arr[:, None] if arr.ndim == 1 else arr
        if arr.ndim != 2 or arr.shape[0] != self.n_modes:
            raise FieldError(
                field,
                f"must have shape (m,) or (m, k) with m = {self.n_modes}, got {np.shape(vector)}",
            )
        return arr

    def _columns(self, vectors: Sequence[npt.ArrayLike]) -> FloatArray:
        cols = [self._influence(v, f"inputs[{i}]") for i, v in enumerate(vectors)]
        return np.hstack([np.zeros((self.n_modes, 0))] + cols)

    def _output_rows(self, outputs: Sequence[Output]) -> tuple[FloatArray, FloatArray]:
        Cq, Cv = [np.zeros((0, self.n_modes))], [np.zeros((0, self.n_modes))]
        for i, item in enumerate(outputs):
            vector, kind = item if isinstance(item, tuple) and len(item) == 2 else (None, item)
            if not isinstance(kind, str) or kind not in ("displacement", "velocity"):
                raise FieldError(
                    f"outputs[{i}]",
                    f"must be a pair (vector, 'displacement' or 'velocity'), got {item!r}",
                )
            rows = self._influence(vector, f"outputs[{i}]").T
            Cq.append(rows if kind == "displacement" else np.zeros_like(rows))
            Cv.append(rows if kind == "velocity" else np.zeros_like(rows))
        return np.vstack(Cq), np.vstack(Cv)

    def to_second_order(
        self, inputs: Sequence[npt.ArrayLike] = (), outputs: Sequence[Output] = ()
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        r"""Second-order modal system :math:`M \ddot\eta + D \dot\eta + K \eta = B u`,
        :math:`y = C_q \eta + C_v \dot\eta`.

        .. math::

            M = I, \quad D = \mathrm{diag}(2 \zeta_i \omega_i), \quad K = \mathrm{diag}(\omega_i^2).

        Parameters
        ----------
        inputs : sequence of array_like (m,) or (m, k)
            Modal influence vectors (e.g. :meth:`force_input`), one input column each.
        outputs : sequence of (array_like, {"displacement", "velocity"})
            Output rows and whether they read η or η̇.

        Returns
        -------
        M, D, K : ndarray (m, m)
        B : ndarray (m, p)
        Cq, Cv : ndarray (q, m)
        """
        w, z = self.frequencies, self.damping
        B = self._columns(inputs)
        Cq, Cv = self._output_rows(outputs)
        return np.eye(self.n_modes), np.diag(2 * z * w), np.diag(w**2), B, Cq, Cv

    def to_statespace(
        self, inputs: Sequence[npt.ArrayLike] = (), outputs: Sequence[Output] = ()
    ) -> control.StateSpace:
        r"""python-control StateSpace with state :math:`x = [\eta, \dot\eta]`.

        .. math::

            A = \begin{bmatrix} 0 & I \\ -K & -D \end{bmatrix}, \quad
            B = \begin{bmatrix} 0 \\ B_2 \end{bmatrix}, \quad C = [C_q \; C_v], \quad D = 0.

        Arguments as :meth:`to_second_order`.
        """
        import control

        _, D, K, B, Cq, Cv = self.to_second_order(inputs, outputs)
        m = self.n_modes
        A = np.block([[np.zeros((m, m)), np.eye(m)], [-K, -D]])
        states = [f"eta[{i}]" for i in range(m)] + [f"eta_dot[{i}]" for i in range(m)]
        Bx = np.vstack([np.zeros_like(B), B])
        return control.ss(
            A, Bx, np.hstack([Cq, Cv]), np.zeros((Cq.shape[0], B.shape[1])), states=states
        )

    # --------------------------------------------------------------------------------------------
    # file format
    def save(self, path: str | Path) -> None:
        """Write one netCDF-4 file (xarray, engine h5netcdf); every variable carries ``units``.

        Variables (dims): ``node`` (node) coordinate = node ids, ``coordinates`` (node, axis),
        ``frequencies``/``damping`` (mode), ``translation_shapes``/``rotation_shapes``
        (mode, node, axis), ``mass_tt``/``mass_tr``/``mass_rt``/``mass_rr`` (axis, axis_j) the
        four 3x3 blocks of ``rigid_mass``, ``participation_translation``/``_rotation``
        (mode, axis), ``reference`` (axis). Shapes, rigid mass and participation are split by
        block so that each variable has one unit. Attributes: ``flexsat_modal_model_version``,
        ``boundary``.
        """
        from flexsat.structures.io_modal_netcdf import NETCDF_ENCODING, modal_model_dataset

        write_netcdf(modal_model_dataset(self), path, encoding=NETCDF_ENCODING)

    @classmethod
    def load(cls, path: str | Path) -> ModalModel:
        """Read a file written by :meth:`save` (validated like any construction)."""
        import xarray as xr

        from flexsat.structures.io_modal_netcdf import modal_model_from_dataset

        with xr.open_dataset(Path(path), engine="h5netcdf") as ds:
            return modal_model_from_dataset(ds.load())

    # --------------------------------------------------------------------------------------------
    # builders
    @classmethod
    def from_fe(
        cls,
        modes: FEModes,
        damping: npt.ArrayLike = 0.0,
        reference: npt.ArrayLike = (0.0, 0.0, 0.0),
        boundary: str | None = None,
    ) -> ModalModel:
        r"""Modal model of a finite-element solution (``flexsat.structures.fem.FEModes``).

        .. math::

            R = \text{assembly.rigid\_body\_vectors}(p), \quad
            M_{rr} = \tfrac12 (R^T M R + (R^T M R)^T), \quad L = \Phi^T (M R)_a,

        with M and R of the whole structure (``assembly.unclamped`` for a clamped one, so the
        attachment's share of consistent element mass is kept) and a the active rows. Shapes come
        from ``modes.at_nodes()``.

        Parameters
        ----------
        modes : FEModes
            ``omegas``, ``shapes`` (ndof, m), ``assembly`` (``M``, ``K``, ``node_ids``,
            ``coordinates``, ``rigid_body_vectors``) and ``at_nodes()``.
        damping : float or array_like (m,)
            Modal damping ratios.
        reference : array_like (3,)
            Rigid-motion reference point p, m (the attachment point of a cantilevered model).
        boundary : {"free", "cantilevered"}, optional
            Default: "cantilevered" when the structure has supports (``assembly.unclamped``);
            otherwise "free" when the stiffness annihilates the rigid-body vectors,
            :math:`\|K R\| \le 10^{-9} \|K\| \|R\|` (Frobenius norms), else "cantilevered".
            Give it explicitly for a free structure with axial preloads, whose geometric
            stiffness need not annihilate rigid rotations.
        """
        asm = modes.assembly
        reference = _array(reference, "reference", (3,), "(3,)")
        # hybrid coordinates: the attachment moves with the rigid body, so rigid mass and
        # coupling use the whole structure's mass (L includes M_ac R_c, exact with all modes)
        whole = asm.unclamped if asm.unclamped is not None else asm
        R = whole.rigid_body_vectors(reference)
        MR = whole.M @ R
        rigid = R.T @ MR
        rows = [whole.index(n, d) for n, d in asm.dofs] if whole is not asm else slice(None)
        return cls(
            node_ids=asm.node_ids,
            coordinates=asm.coordinates,
            frequencies=modes.omegas,
            damping=require_nonneg(damping, "damping"),  # a scalar or one per mode
            shapes=modes.at_nodes(),
            rigid_mass=0.5 * (rigid + rigid.T),
            participation=modes.shapes.T @ MR[rows],
            reference=reference,
            boundary=boundary or ("cantilevered" if whole is not asm else _fe_boundary(asm.K, R)),
        )

    @classmethod
    def from_hub_appendage(
        cls, model: HubAppendageModel, stations: npt.ArrayLike | None = None
    ) -> ModalModel:
        r"""The n appendages of a :class:`~flexsat.dynamics.hub_appendage.HubAppendage` as one
        cantilevered modal model (hybrid coordinates about the hub centre, reference 0).

        Geometry: appendage j lies along :math:`u_j = (\cos\alpha_j, \sin\alpha_j, 0)`,
        :math:`\alpha_j = 2\pi j / n`, root at :math:`l_0`, and bends in the XY plane about z
        (tangent :math:`t_j = e_z \times u_j`), all alike (anti-symmetric motion). Nodes are on
        appendage 0 (+x) at ``stations`` ξ from the root; the others follow by symmetry.

        Normalisation: the HubAppendage modes φ_i are mass normalised per beam, so coordinate
        q_i has modal mass n. The modal coordinate here is :math:`\eta_i = \sqrt n\, q_i` and
        the shapes are :math:`\phi_i / \sqrt n` (uy) and :math:`\phi_i' / \sqrt n` (rz), unit
        modal mass for the n appendages together. Then, with
        :math:`d_i` = ``model.coupling`` and :math:`e_i = \int\rho\phi_i + m\phi_i(l)
        = -EI \phi_i'''(0) / \omega_i^2` (integrated beam equation),

        .. math::

            L_{i,\theta_z} = \sqrt n\, d_i, \qquad
            L_{i,t} = \frac{e_i}{\sqrt n} \sum_j t_j \;(= 0 \text{ for } n \ge 2),

        and the rigid mass is that of n line masses ρ on [l_0, l] with tip masses m at l and
        tip rotary inertia J about z (the single-axis model has no out-of-plane tip inertia):
        :math:`M_{rr}[\theta_z, \theta_z] = n I_b`.

        Parameters
        ----------
        model : HubAppendage
        stations : array_like, optional
            Node stations ξ along the beam from the root, m, in [0, L]; default 5 equally
            spaced from root to tip. Node ids are 1, 2, ...
        """
        p, n = model.params, model.params.n_appendages
        xi = _stations(stations, p.length)
        modes = p.beam().modes(model.n_modes)
        w = model.cantilever_frequencies
        shapes = np.zeros((model.n_modes, xi.size, 6))
        shapes[:, :, 1] = modes.evaluate(xi, 0).T / np.sqrt(n)
        shapes[:, :, 5] = modes.evaluate(xi, 1).T / np.sqrt(n)
        e = -p.EI * modes.evaluate([0.0], 3)[0] / w**2
        alpha = 2 * np.pi * np.arange(n) / n
        u = np.column_stack([np.cos(alpha), np.sin(alpha), np.zeros(n)])
        participation = np.zeros((model.n_modes, 6))
        participation[:, :3] = np.outer(e, np.cross([0.0, 0.0, 1.0], u).sum(axis=0)) / np.sqrt(n)
        participation[:, 5] = np.sqrt(n) * model.coupling
        l0, l, m_tip = p.hub_radius, p.tip_radius, p.tip_mass
        rigid = _rigid_mass_from_moments(
            n * (p.rho * p.length + m_tip),
            (p.rho * (l**2 - l0**2) / 2 + m_tip * l) * u.sum(axis=0),
            (p.rho * (l**3 - l0**3) / 3 + m_tip * l**2) * u.T @ u,
            np.diag([0.0, 0.0, n * p.tip_inertia]),
        )
        return cls(
            node_ids=np.arange(1, xi.size + 1),
            coordinates=np.column_stack([l0 + xi, np.zeros((xi.size, 2))]),
            frequencies=w,
            damping=model.damping_ratios,
            shapes=shapes,
            rigid_mass=rigid,
            participation=participation,
            boundary="cantilevered",
        )


# ------------------------------------------------------------------------------------------------
# builder helpers
def _fe_boundary(K: Any, R: FloatArray) -> str:
    norm_K = sparse_norm(K) if issparse(K) else np.linalg.norm(K)
    free = np.linalg.norm(K @ R) <= _FREE_STIFFNESS_TOL * norm_K * np.linalg.norm(R)
    return "free" if free else "cantilevered"


def _stations(stations: npt.ArrayLike | None, length: float) -> FloatArray:
    if stations is None:
        return np.linspace(0.0, length, 5)
    xi = require_finite(stations, "stations")
    if xi.ndim != 1 or xi.size == 0 or np.any(xi < 0) or np.any(xi > length):
        raise FieldError(
            "stations", f"must be a non-empty 1-D array in [0, {length}] m, got {stations!r}"
        )
    return xi


def hub_appendage_matrices(
    modal: ModalModel, hub_inertia: float, axis: int | str = 2
) -> tuple[FloatArray, FloatArray, FloatArray]:
    r"""Hybrid-coordinate matrices of a rigid hub spinning about ``axis`` through the reference
    point, carrying a cantilevered modal model; coordinates (θ, η).

    .. math::

        M = \begin{bmatrix} I_{hub} + I_{app} & L^T \\ L & I \end{bmatrix}, \quad
        D = \mathrm{diag}(0, 2\zeta\omega), \quad K = \mathrm{diag}(0, \omega^2),

    with :math:`I_{app}` = ``rigid_mass`` [θ, θ] and L = ``participation`` [:, θ] for the
    rotation about ``axis``. For a model made by :meth:`ModalModel.from_hub_appendage` these
    are the HubAppendage matrices in the coordinates (θ, √n q).

    Parameters
    ----------
    modal : ModalModel
        Must be cantilevered.
    hub_inertia : float
        Inertia of the hub alone about the axis, kg m².
    axis : {0, 1, 2, "x", "y", "z"}

    Returns
    -------
    M, D, K : ndarray (m + 1, m + 1)
    """
    if modal.boundary != "cantilevered":
        raise FieldError(
            "modal",
            f"hybrid coordinates need a cantilevered model, got boundary {modal.boundary!r}",
        )
    j = 3 + _axis_index(axis)
    L = modal.participation[:, j]
    M = np.eye(modal.n_modes + 1)
    M[0, 0] = float(require_nonneg(hub_inertia, "hub_inertia")) + modal.rigid_mass[j, j]
    M[0, 1:] = M[1:, 0] = L
    w, z = modal.frequencies, modal.damping
    D = np.diag(np.concatenate([[0.0], 2 * z * w]))
    K = np.diag(np.concatenate([[0.0], w**2]))
    return M, D, K
