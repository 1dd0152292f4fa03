r"""Automatic description of finite-element modes: which component moves, and how.

For a mass-normalised mode :math:`\phi` of an assembled model with mass matrix :math:`M`, the
modal kinetic energy (per unit :math:`\omega^2/2`) is :math:`\phi^T M \phi = 1`.  It is split
over named groups of nodes (the components) by the mass-matrix partition

.. math::

    e_g = \sum_{i \in g} \phi_i (M\phi)_i , \qquad \sum_g e_g = \phi^T M \phi ,

(dofs of nodes in no group form the group ``"other"``).  With a consistent mass matrix an
element joining two groups couples them, so a share can be slightly negative or above 1 for a
component that barely moves; the shares always add up to 100 %.

The component with the largest share is then described by its *motion*: the mode restricted to
that component's dofs, :math:`\phi_g`, is projected (least squares in the component's own mass
metric :math:`M_{gg}`) on the six rigid motions of the component's nodes about its centre of
mass,

.. math::

    q = \arg\min_q (\phi_g - R_g q)^T M_{gg} (\phi_g - R_g q),
    \qquad r = \frac{q^T R_g^T M_{gg} R_g q}{\phi_g^T M_{gg} \phi_g} \in [0, 1],

:math:`r` being the fraction of the component's kinetic energy that a rigid motion explains.

- :math:`r <` ``rigid_fraction`` (default 0.5): ``"bending/elastic"``;
- otherwise the rigid part is a translation (energy :math:`m|t|^2`) or a rotation
  (:math:`\theta^T I_c \theta`), whichever is larger.  A rotation about the component's own
  symmetry axis (the principal axis of :math:`I_c` whose moment stands apart from the other two:
  the normal of a dish, the long axis of a rod; or an axis given in ``axes``) is ``"torsion about
  its axis"``; any other rotation is named after the closest global axis (``"x-rotation"``,
  ``"z-rotation"``); a translation after the closest global axis (``"translation along y"``).

Modes below ``rigid_tol`` (Hz) are ``"rigid body"``.

>>> describe_modes(modes, {"truss": truss_ids, "15 m antenna": dish_ids})  # doctest: +SKIP
['rigid body', ..., '15 m antenna (92 %): torsion about its axis', ...]
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

if TYPE_CHECKING:
    from flexsat.structures.fem import FEModes

DOF_NAMES = ("ux", "uy", "uz", "rx", "ry", "rz")
_AXES = "xyz"

#: default frequency (Hz) below which a mode is a rigid-body mode
RIGID_TOL_HZ = 1e-3


@dataclass(frozen=True)
class ModeDescription:
    """What one mode does (see the module docstring for the definitions)."""

    index: int
    frequency_hz: float
    component: str | None  #: the group with the largest kinetic-energy share (None: rigid body)
    share: float  #: that group's share of the modal kinetic energy (0..1)
    motion: str  #: "rigid body", "torsion about its axis", "z-rotation", "bending/elastic", ...
    rigid_fit: float  #: fraction of the component's own kinetic energy a rigid motion explains
    shares: dict[str, float] = field(default_factory=dict)  #: every group's share

    def __str__(self) -> str:
        if self.component is None:
            return self.motion
        return f"{self.component} ({100 * self.share:.0f} %): {self.motion}"


def _check_groups(
    groups: Mapping[str, Iterable[int]], node_ids: npt.NDArray[np.int_]
) -> dict[str, npt.NDArray[np.int_]]:
    if not isinstance(groups, dict) or not groups:
        raise FieldError("groups", "must be a non-empty dict {name: node ids}")
    known = set(int(n) for n in node_ids)
    owner: dict[int, str] = {}
    out = {}
    for name, ids in groups.items():
        if not isinstance(name, str) or not name or name == "other":
            raise FieldError(
                "groups", f"names must be non-empty strings other than 'other', got {name!r}"
            )
        arr = np.unique(np.asarray(list(ids), dtype=int))
        if arr.size == 0:
            raise FieldError("groups", f"group {name!r} is empty")
        for n in arr.tolist():
            if n not in known:
                raise FieldError("groups", f"group {name!r}: node {n} is not in the model")
            if n in owner:
                raise FieldError("groups", f"node {n} is in both {owner[n]!r} and {name!r}")
            owner[n] = name
        out[name] = arr
    return out


def _rigid_vectors(
    dofs: Sequence[tuple[int, str]], coords_by_node: Mapping[int, FloatArray], reference: FloatArray
) -> FloatArray:
    """(len(dofs), 6) rigid motions: unit translations x, y, z, unit rotations about
    ``reference``."""
    R = np.zeros((len(dofs), 6))
    for row, (node, name) in enumerate(dofs):
        k = DOF_NAMES.index(name)
        if k < 3:
            r = coords_by_node[node] - reference
            R[row, k] = 1.0
            for a in range(3):
                e = np.zeros(3)
                e[a] = 1.0
                R[row, 3 + a] = np.cross(e, r)[k]
        else:
            R[row, k] = 1.0
    return R


def _centre_of_mass(A0: FloatArray) -> FloatArray:
    """Centre of mass c from the rigid mass matrix about the origin, using only the
    translations the model has: A0[k, 3 + a] = m_k (c × e_k)_a for each present translation k
    (least squares; components no present translation sees are 0)."""
    rows, rhs = [], []
    for k in range(3):
        m_k = A0[k, k]
        if m_k <= 0:
            continue
        e = np.zeros(3)
        e[k] = 1.0
        # (c × e_k) = -[e_k]× c  -> linear map of c
        skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
        rows.append(-m_k * skew)
        rhs.append(A0[k, 3:])
    if not rows:
        return np.zeros(3)
    c, *_ = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)
    return c


def _symmetry_axis(inertia: FloatArray, tol: float = 0.05) -> FloatArray | None:
    """The principal axis whose moment stands apart from the other two, or None when the
    three moments are all within ``tol`` (relative) of each other."""
    lam, vec = np.linalg.eigh(0.5 * (inertia + inertia.T))
    if lam[2] <= 0 or (lam[2] - lam[0]) <= tol * lam[2]:
        return None
    return vec[:, 2] if (lam[1] - lam[0]) < (lam[2] - lam[1]) else vec[:, 0]


def _closest_axis(v: FloatArray) -> str:
    return _AXES[int(np.argmax(np.abs(v)))]


class _Component:
    """A group's dofs, mass block and rigid-motion basis about its centre of mass."""

    def __init__(
        self,
        name: str,
        rows: npt.NDArray[np.int_],
        dofs: Sequence[tuple[int, str]],
        M: Any,
        coords_by_node: Mapping[int, FloatArray],
        axis: npt.ArrayLike | None = None,
    ) -> None:
        self.name = name
        self.rows = rows
        self.Mgg = M[rows][:, rows] if sp.issparse(M) else M[np.ix_(rows, rows)]
        sub = [dofs[i] for i in rows]
        R0 = _rigid_vectors(sub, coords_by_node, np.zeros(3))
        A0 = R0.T @ (self.Mgg @ R0)
        self.centre = _centre_of_mass(A0)
        self.mass = float(np.max(np.diag(A0)[:3]))
        centre = self.centre
        self.R = _rigid_vectors(sub, coords_by_node, centre)
        self.A = self.R.T @ (self.Mgg @ self.R)
        self.A_pinv = np.linalg.pinv(self.A, rcond=1e-10, hermitian=True)
        if axis is not None:
            a = np.asarray(axis, dtype=float)
            if a.shape != (3,) or not np.all(np.isfinite(a)) or np.linalg.norm(a) == 0:
                raise FieldError(
                    "axes", f"the axis of {name!r} must be a non-zero 3-vector, got {axis!r}"
                )
            self.axis = a / np.linalg.norm(a)
        elif np.all(np.diag(self.A)[3:] > 0) and np.all(np.diag(self.A)[:3] > 0):
            self.axis = _symmetry_axis(self.A[3:, 3:])
        else:  # a plane model: some rigid motions are absent, no symmetry axis is inferred
            self.axis = None

    def motion(
        self, phi: FloatArray, rigid_fraction: float, torsion_cos: float
    ) -> tuple[str, float]:
        phig = phi[self.rows]
        energy = float(phig @ (self.Mgg @ phig))
        if energy <= 0:
            return "at rest", 0.0
        q = self.A_pinv @ (self.R.T @ (self.Mgg @ phig))
        rigid = float(q @ self.A @ q)
        fit = min(max(rigid / energy, 0.0), 1.0)
        if fit < rigid_fraction:
            return "bending/elastic", fit
        t, th = q[:3], q[3:]
        e_t = float(t @ self.A[:3, :3] @ t)
        e_r = float(th @ self.A[3:, 3:] @ th)
        if e_t >= e_r:
            return f"translation along {_closest_axis(t)}", fit
        a = th / np.linalg.norm(th)
        if self.axis is not None and abs(float(a @ self.axis)) >= torsion_cos:
            return "torsion about its axis", fit
        return f"{_closest_axis(a)}-rotation", fit


def classify_modes(
    modes: FEModes,
    groups: Mapping[str, Iterable[int]],
    rigid_tol: float = RIGID_TOL_HZ,
    rigid_fraction: float = 0.5,
    torsion_angle_deg: float = 30.0,
    axes: Mapping[str, npt.ArrayLike] | None = None,
) -> list[ModeDescription]:
    """Describe every mode of ``modes`` (an ``FEModes``: ``omegas``, mass-normalised ``shapes``
    and its ``assembly`` with ``M``, ``dofs``, ``node_ids``, ``coordinates``).

    Parameters
    ----------
    groups : dict
        ``{component name: node ids}``; a node belongs to at most one group.
    rigid_tol : float
        Modes below this frequency (Hz) are rigid-body modes.
    rigid_fraction : float
        The share of the component's kinetic energy a rigid motion must explain for the motion
        to be called a translation/rotation/torsion rather than ``"bending/elastic"``.
    torsion_angle_deg : float
        A rotation within this angle of the component's symmetry axis is a torsion.
    axes : dict, optional
        ``{component name: axis 3-vector}`` to give a component's symmetry axis explicitly.
    """
    if not np.isfinite(rigid_tol) or rigid_tol < 0:
        raise FieldError("rigid_tol", f"must be a finite frequency >= 0 Hz, got {rigid_tol!r}")
    if not 0 < rigid_fraction <= 1:
        raise FieldError("rigid_fraction", f"must be in (0, 1], got {rigid_fraction!r}")
    if not 0 <= torsion_angle_deg <= 90:
        raise FieldError("torsion_angle_deg", f"must be in [0, 90], got {torsion_angle_deg!r}")
    asm = modes.assembly
    node_ids = np.asarray(asm.node_ids, dtype=int)
    coords_by_node = {
        int(n): np.asarray(c, dtype=float) for n, c in zip(node_ids, np.asarray(asm.coordinates))
    }
    checked = _check_groups(groups, node_ids)
    axes = dict(axes or {})
    unknown = set(axes) - set(checked)
    if unknown:
        raise FieldError(
            "axes", f"unknown component(s) {sorted(unknown)}; groups: {sorted(checked)}"
        )
    M = sp.csr_matrix(asm.M) if sp.issparse(asm.M) else np.asarray(asm.M, dtype=float)
    dofs = [(int(n), str(d)) for n, d in asm.dofs]
    node_group = {int(n): name for name, ids in checked.items() for n in ids}
    rows_of: dict[str, list[int]] = {name: [] for name in checked}
    rows_of["other"] = []
    for row, (n, _) in enumerate(dofs):
        rows_of[node_group.get(n, "other")].append(row)
    if not rows_of["other"]:
        del rows_of["other"]
    components = {
        name: _Component(
            name, np.asarray(rows_of[name], dtype=int), dofs, M, coords_by_node, axes.get(name)
        )
        for name in checked
        if rows_of[name]
    }

    shapes = np.asarray(modes.shapes, dtype=float)
    freqs = np.asarray(modes.omegas, dtype=float) / (2 * np.pi)
    torsion_cos = float(np.cos(np.radians(torsion_angle_deg)))
    out = []
    for j in range(shapes.shape[1]):
        phi = shapes[:, j]
        e = phi * (M @ phi)
        total = float(e.sum())
        shares = {
            name: float(e[rows].sum()) / total if total > 0 else 0.0
            for name, rows in rows_of.items()
        }
        if abs(freqs[j]) < rigid_tol:
            out.append(ModeDescription(j, float(freqs[j]), None, 1.0, "rigid body", 1.0, shares))
            continue
        top = max(shares, key=lambda name: shares[name])
        if top == "other":
            motion, fit = "unassigned nodes", 0.0
        else:
            motion, fit = components[top].motion(phi, rigid_fraction, torsion_cos)
        out.append(ModeDescription(j, float(freqs[j]), top, shares[top], motion, fit, shares))
    return out


def describe_modes(
    modes: FEModes,
    groups: Mapping[str, Iterable[int]],
    rigid_tol: float = RIGID_TOL_HZ,
    **options: Any,
) -> list[str]:
    """One phrase per mode, e.g. ``"15 m antenna (92 %): torsion about its axis"``.

    See :func:`classify_modes` for the parameters (``rigid_fraction``, ``torsion_angle_deg``,
    ``axes``) and the module docstring for the definitions."""
    return [str(d) for d in classify_modes(modes, groups, rigid_tol=rigid_tol, **options)]


__all__ = ["ModeDescription", "RIGID_TOL_HZ", "classify_modes", "describe_modes"]
