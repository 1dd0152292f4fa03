"""Members of a finite-element :class:`~flexsat.structures.fem.Structure` and their element blocks.

A :class:`Member` is one element of a structure (its kind, end nodes and properties); the
builders in :data:`KIND_BUILDERS` turn all members of a kind into one batched stack of global
element matrices (element formulas: :mod:`flexsat.structures.elements`). Also here: which
properties a member has as design quantities, the sets in which the element matrices are
jointly affine (what ``Structure.property_derivative`` relies on), member masses and the axial
force of a member from its end displacements. All SI.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from flexsat.structures import elements as el
from flexsat.units import FloatArray

__all__ = [
    "AFFINE_SETS",
    "DESIGN_QUANTITIES",
    "GRID_KEYS",
    "KIND_BUILDERS",
    "KIND_SLOTS",
    "ElementBlocks",
    "Member",
    "axial_force",
    "member_masses",
    "with_properties",
]

IntArray = npt.NDArray[np.int_]
#: element blocks of one kind: global slot indices (n, d), K (n, d, d), M (n, d, d)
ElementBlocks = tuple[IntArray, FloatArray, FloatArray]

#: global dof slots (0-5: ux, uy, uz, rx, ry, rz) of each end of a member, per kind
KIND_SLOTS = {
    "frame": (0, 1, 2, 3, 4, 5),
    "beam2d": (0, 1, 5),
    "grid": (2, 3, 4),
    "rod": (0, 1, 2),
}


@dataclass
class Member:
    """One member: ``kind`` (a key of :data:`KIND_SLOTS`), end node *indices* (not ids),
    properties (SI; the keys the kind's builder reads), free label and axial preload (N)."""

    kind: str
    n1: int
    n2: int
    props: dict[str, Any]
    label: object = None
    preload: float = 0.0


# ------------------------------------------------------------------------------------------------
# per-kind batched element matrices: (global slot indices (n, d), K (n, d, d), M (n, d, d))
def _column(members: Sequence[Member], key: str) -> FloatArray:
    return np.array([m.props[key] for m in members], dtype=float)


def _slot_indices(members: Sequence[Member], kind: str) -> IntArray:
    slots = np.array(KIND_SLOTS[kind])
    n1 = np.array([m.n1 for m in members])[:, None]
    n2 = np.array([m.n2 for m in members])[:, None]
    return np.hstack([6 * n1 + slots, 6 * n2 + slots])


def _frame_geometry(members: Sequence[Member], xyz: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Lengths (between the offset ends) and 12x12 transformations of frame members."""
    x1 = xyz[[m.n1 for m in members]]
    x2 = xyz[[m.n2 for m in members]]
    offsets = np.array(
        [np.zeros((2, 3)) if m.props["offsets"] is None else m.props["offsets"] for m in members]
    )
    x1, x2 = x1 + offsets[:, 0], x2 + offsets[:, 1]
    given = np.array([m.props["orientation"] is not None for m in members])
    R = el.frame_rotation(x1, x2)
    if given.any():
        v = np.array([m.props["orientation"] for m, g in zip(members, given) if g])
        R[given] = el.frame_rotation(x1[given], x2[given], v)
    T = el.frame_transformation(R, offsets)
    return np.linalg.norm(x2 - x1, axis=1), T


def _frame_blocks(members: Sequence[Member], xyz: FloatArray, geometric: bool) -> ElementBlocks:
    c = {k: _column(members, k) for k in ("E", "G", "rho", "A", "Iy", "Iz", "J")}
    L, T = _frame_geometry(members, xyz)
    k = el.frame_local_stiffness(c["E"], c["G"], c["A"], c["Iy"], c["Iz"], c["J"], L)
    if geometric:
        k = k + el.frame_local_geometric_stiffness(_preloads(members), L)
    lumped = np.array([m.props["lumped"] for m in members])
    m = np.where(
        lumped[:, None, None],
        el.frame_local_mass(c["rho"], c["A"], c["Iy"], c["Iz"], L, lumped=True),
        el.frame_local_mass(c["rho"], c["A"], c["Iy"], c["Iz"], L),
    )
    return _slot_indices(members, "frame"), el.to_global(k, T), el.to_global(m, T)


def _preloads(members: Sequence[Member]) -> FloatArray:
    return np.array([m.preload for m in members], dtype=float)


def _ends(members: Sequence[Member], xyz: FloatArray) -> tuple[FloatArray, FloatArray]:
    return xyz[[m.n1 for m in members]], xyz[[m.n2 for m in members]]


def _beam2d_blocks(members: Sequence[Member], xyz: FloatArray, geometric: bool) -> ElementBlocks:
    c = {k: _column(members, k) for k in ("E", "rho", "A", "Iz")}
    x1, x2 = _ends(members, xyz)
    L = np.linalg.norm((x2 - x1)[:, :2], axis=1)
    T = el.beam2d_transformation(x1, x2)
    k = el.beam2d_local_stiffness(c["E"], c["A"], c["Iz"], L)
    if geometric:
        k = k + el.beam2d_local_geometric_stiffness(_preloads(members), L)
    lumped = np.array([m.props["lumped"] for m in members])
    m = np.where(
        lumped[:, None, None],
        el.beam2d_local_mass(c["rho"], c["A"], L, lumped=True),
        el.beam2d_local_mass(c["rho"], c["A"], L),
    )
    return _slot_indices(members, "beam2d"), el.to_global(k, T), el.to_global(m, T)


def _grid_blocks(members: Sequence[Member], xyz: FloatArray, geometric: bool) -> ElementBlocks:
    c = {k: _column(members, k) for k in ("EI", "GJ", "m", "It")}
    x1, x2 = _ends(members, xyz)
    L = np.linalg.norm((x2 - x1)[:, :2], axis=1)
    T = el.grid_transformation(x1, x2)
    k = el.grid_local_stiffness(c["EI"], c["GJ"], L)
    if geometric:
        k = k + el.grid_local_geometric_stiffness(_preloads(members), L)
    m = el.grid_local_mass(c["m"], c["It"], L)
    return _slot_indices(members, "grid"), el.to_global(k, T), el.to_global(m, T)


def _rod_blocks(members: Sequence[Member], xyz: FloatArray, geometric: bool) -> ElementBlocks:
    c = {k: _column(members, k) for k in ("E", "rho", "A")}
    x1, x2 = _ends(members, xyz)
    L = np.linalg.norm(x2 - x1, axis=1)
    k = el.rod_stiffness(c["E"], c["A"], x1, x2)
    if geometric:
        k = k + el.rod_geometric_stiffness(_preloads(members), x1, x2)
    lumped = np.array([m.props["lumped"] for m in members])
    m = np.where(
        lumped[:, None, None],
        el.rod_mass(c["rho"], c["A"], L, lumped=True),
        el.rod_mass(c["rho"], c["A"], L),
    )
    return _slot_indices(members, "rod"), k, m


#: the member properties :meth:`Structure.property_derivative` differentiates, per kind
DESIGN_QUANTITIES = {
    "frame": ("A", "Iy", "Iz", "J", "E", "G", "rho"),
    "beam2d": ("A", "Iz", "E", "rho"),
    "rod": ("A", "E", "rho"),
    "grid": ("EI", "GJ", "mass_per_length", "torsional_inertia_per_length"),
}
#: sets of properties in which the element matrices are jointly affine
AFFINE_SETS = {
    "frame": ({"A", "Iy", "Iz", "J"}, {"E", "G", "rho"}),
    "beam2d": ({"A", "Iz"}, {"E", "rho"}),
    "rod": ({"A"}, {"E", "rho"}),
    "grid": ({"EI", "GJ", "mass_per_length", "torsional_inertia_per_length"},),
}
GRID_KEYS = {"mass_per_length": "m", "torsional_inertia_per_length": "It"}


def with_properties(member: Member, values: dict[str, float]) -> Member:
    """A copy of ``member`` with the given properties replaced (G follows a tied E)."""
    props = dict(member.props)
    for quantity, value in values.items():
        props[GRID_KEYS.get(quantity, quantity)] = float(value)
    if "E" in values and member.kind == "frame" and props["G_per_E"] is not None:
        props["G"] = float(values["E"]) * props["G_per_E"]
    return Member(member.kind, member.n1, member.n2, props, member.label, member.preload)


def member_masses(members: Sequence[Member], xyz: FloatArray) -> FloatArray:
    """Mass of each member of one kind, kg: ρ A L (L between offset ends), or m L for grids."""
    if not members:
        return np.zeros(0)
    kind = members[0].kind
    if kind == "frame":
        x1, x2 = _ends(members, xyz)
        for i, m in enumerate(members):
            if m.props["offsets"] is not None:
                x1[i] += m.props["offsets"][0]
                x2[i] += m.props["offsets"][1]
        L = np.linalg.norm(x2 - x1, axis=1)
    else:
        x1, x2 = _ends(members, xyz)
        planar = kind in ("beam2d", "grid")
        L = np.linalg.norm((x2 - x1)[:, :2] if planar else x2 - x1, axis=1)
    if kind == "grid":
        return _column(members, "m") * L
    return _column(members, "rho") * _column(members, "A") * L


KIND_BUILDERS = {
    "frame": _frame_blocks,
    "beam2d": _beam2d_blocks,
    "grid": _grid_blocks,
    "rod": _rod_blocks,
}


def axial_force(member: Member, xyz: FloatArray, displacement: FloatArray) -> float:
    """EA/L x̂·(u_end2 - u_end1) from global node displacements (n_nodes, 6); 0 for grids."""
    if member.kind == "grid":
        return 0.0
    p = member.props
    u1, u2 = displacement[member.n1], displacement[member.n2]
    x1, x2 = xyz[member.n1], xyz[member.n2]
    d1 = d2 = np.zeros(3)
    if member.kind == "frame" and p["offsets"] is not None:
        d1, d2 = p["offsets"]
    if member.kind == "beam2d":
        x1, x2 = x1 * [1, 1, 0], x2 * [1, 1, 0]
    e1 = u1[:3] + np.cross(u1[3:], d1)
    e2 = u2[:3] + np.cross(u2[3:], d2)
    axis = (x2 + d2) - (x1 + d1)
    L = np.linalg.norm(axis)
    return float(p["E"] * p["A"] / L * float(axis @ (e2 - e1)) / L)
