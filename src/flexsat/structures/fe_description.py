r"""A finite-element model described as data (SI), built into a
:class:`~flexsat.structures.fem.Structure` and its
:class:`~flexsat.structures.modal_model.ModalModel`.

A scenario's inline ``model: {fe: ...}`` section (:mod:`flexsat.scenarios.models`) converts its
quantities to SI and fills an :class:`FEDescription`; a Python user can fill one directly. The
description names materials and sections by key and elements by their end node ids, the way a
bulk-data deck does (GRID, MAT1, PBAR, CBAR, CONM2, SPC), so every reference is checked here and
a problem names the entry it is in (``elements[3].material: unknown material 'alu'``) as a
:class:`~flexsat.input_checks.FieldError`.

Modes: a structure without clamps is free-free: its ``n_modes`` elastic modes are solved with the
six rigid-body modes, which are checked and replaced by exact ones
(:meth:`flexsat.structures.fem.Assembly.modes`); a clamped one has ``n_modes`` modes, none rigid.
Damping is a modal ratio ζ on the elastic modes (0 on the rigid ones).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from numbers import Integral
from typing import TypeVar

import numpy as np
import numpy.typing as npt

from flexsat import limits
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_physical_inertia,
)
from flexsat.structures.fem import DOF_NAMES, Structure
from flexsat.structures.modal_model import ModalModel
from flexsat.structures.sections import Material, Section

__all__ = [
    "ELEMENT_KINDS",
    "ClampSpec",
    "ElementSpec",
    "FEDescription",
    "MassSpec",
    "NodeSpec",
    "RigidLinkSpec",
]

#: member kinds a description may use: a 3-D Euler-Bernoulli frame, an axial rod
ELEMENT_KINDS = ("frame", "rod")
T = TypeVar("T")
#: rigid-body modes of a free 3-D structure
_RIGID_MODES = 6


@dataclass(frozen=True)
class NodeSpec:
    """A node: its integer id and position ``xyz`` (3,), m."""

    id: int
    xyz: npt.ArrayLike


@dataclass(frozen=True)
class ElementSpec:
    """A member between two nodes.

    Attributes
    ----------
    kind : {"frame", "rod"}
        :meth:`Structure.add_frame` or :meth:`Structure.add_rod` (a rod takes the section's
        area only).
    nodes : (int, int)
        End node ids; the local x axis runs from the first to the second.
    material, section : str
        Keys of :attr:`FEDescription.materials` and :attr:`FEDescription.sections`.
    orientation : (3,), optional
        A frame's orientation vector v in its local x-y plane (NASTRAN CBAR), global axes.
    offsets : ((3,), (3,)), optional
        A frame's rigid end offsets from its two nodes, global axes, m.
    lumped : bool
        Lumped (HRZ) instead of consistent member mass.
    """

    kind: str
    nodes: tuple[int, int]
    material: str
    section: str
    orientation: npt.ArrayLike | None = None
    offsets: npt.ArrayLike | None = None
    lumped: bool = False


@dataclass(frozen=True)
class MassSpec:
    r"""A lumped mass (kg) at a node, its inertia about its own centre (kg m²: a 3-vector of
    principal values in global axes or a 3x3 tensor) and its rigid offset from the node (m)
    (:meth:`Structure.add_mass`).

    A described mass is a body: its inertia must be one a mass distribution has (positive
    semi-definite, principal moments satisfying the triangle inequality
    :math:`I_1 + I_2 \ge I_3`, :func:`flexsat.input_checks.require_physical_inertia`), checked
    when the structure is built. (:meth:`Structure.add_mass` itself accepts a single-axis inertia
    such as ``(0, 0, J)``, which a planar model whose out-of-plane dofs are suppressed uses.)"""

    node: int
    mass: float
    inertia: npt.ArrayLike | None = None
    offset: npt.ArrayLike | None = None


@dataclass(frozen=True)
class RigidLinkSpec:
    """Nodes tied rigidly to an independent ``node`` (:meth:`Structure.add_rigid_link`, an
    RBE2 on all six dofs): a rigid hub carrying attachment points, a stiff bracket."""

    node: int
    nodes: Sequence[int]


@dataclass(frozen=True)
class ClampSpec:
    """Fixed dofs of a node: ``"all"`` or names from :data:`flexsat.structures.fem.DOF_NAMES`
    (:meth:`Structure.clamp`), a support (released for the rigid mass of the hybrid-coordinate
    modal model, :meth:`ModalModel.from_fe`)."""

    node: int
    dofs: str | tuple[str, ...] = "all"


@dataclass(frozen=True)
class FEDescription:
    """A finite-element structure as data, SI (module docstring).

    Attributes
    ----------
    nodes : sequence of NodeSpec
    materials : mapping of str to Material
    sections : mapping of str to Section
    elements : sequence of ElementSpec
    masses : sequence of MassSpec
    rigid_links : sequence of RigidLinkSpec
    clamps : sequence of ClampSpec
        None: free-free.
    n_modes : int
        Elastic modes to keep.
    damping : float or sequence of float
        Modal damping ratio ζ of every elastic mode, or one per elastic mode.
    reference : (3,), optional
        Reference point of the modal model, m; default the origin for a free structure, the
        first clamped node for a clamped one (its attachment).
    name : str
    """

    nodes: Sequence[NodeSpec]
    materials: Mapping[str, Material]
    sections: Mapping[str, Section]
    elements: Sequence[ElementSpec]
    masses: Sequence[MassSpec] = ()
    rigid_links: Sequence[RigidLinkSpec] = ()
    clamps: Sequence[ClampSpec] = ()
    n_modes: int = 10
    damping: float | Sequence[float] = 0.0
    reference: npt.ArrayLike | None = None
    name: str = ""
    _ids: frozenset[int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        require_count(self.n_modes, "n_modes")
        limits.check_count(self.n_modes, limits.MAX_MODES, "n_modes", "elastic modes")
        zeta = require_nonneg(self.damping, "damping", "")
        if zeta.ndim > 1 or (zeta.ndim == 1 and zeta.size != self.n_modes):
            raise FieldError(
                "damping",
                f"give one ratio or one per elastic mode ({self.n_modes}), got shape {zeta.shape}",
            )
        if not self.nodes:
            raise FieldError("nodes", "at least one node is needed")
        if not self.elements:
            raise FieldError("elements", "at least one element is needed")
        object.__setattr__(
            self, "_ids", frozenset(_node_id(n.id, i) for i, n in enumerate(self.nodes))
        )
        for name, value, kind in (
            *((f"materials.{k}", v, Material) for k, v in self.materials.items()),
            *((f"sections.{k}", v, Section) for k, v in self.sections.items()),
        ):
            if not isinstance(value, kind):
                raise FieldError(name, f"must be a {kind.__name__}, got {type(value).__name__}")

    @property
    def free(self) -> bool:
        """Whether the structure is free-free (no clamp)."""
        return not self.clamps

    def _known_node(self, node: object, path: str) -> int:
        if isinstance(node, bool) or not isinstance(node, Integral) or int(node) not in self._ids:
            shown = ", ".join(map(str, sorted(self._ids)[:12]))
            raise FieldError(
                path,
                f"unknown node {node!r} (nodes: {shown}{' ...' if len(self._ids) > 12 else ''})",
            )
        return int(node)

    def structure(self) -> Structure:
        """The :class:`Structure` of this description.

        Raises
        ------
        FieldError
            Naming the entry: ``nodes[2].id``, ``elements[3].nodes``, ``elements[3].material``,
            ``masses[0].inertia``, ``rigid_links[0].nodes``, ``clamps[1].dofs``, ... and the
            rule.
        """
        s = Structure(self.name)
        for i, node in enumerate(self.nodes):
            with _entry(f"nodes[{i}]"):
                s.add_node(node.id, node.xyz)
        for i, element in enumerate(self.elements):
            path = f"elements[{i}]"
            with _entry(path):
                self._add_element(s, element, path)
        for i, mass in enumerate(self.masses):
            path = f"masses[{i}]"
            mass_node = self._known_node(mass.node, f"{path}.node")
            with _entry(path):
                s.add_mass(mass_node, mass.mass, inertia=mass.inertia, offset=mass.offset)
                if mass.inertia is not None:  # add_mass checked its shape and symmetry
                    J = np.asarray(mass.inertia, dtype=float)
                    require_physical_inertia(np.diag(J) if J.ndim == 1 else J, "inertia", False)
        for i, link in enumerate(self.rigid_links):
            path = f"rigid_links[{i}]"
            independent = self._known_node(link.node, f"{path}.node")
            dependent = [self._known_node(n, f"{path}.nodes") for n in link.nodes]
            if not dependent:
                raise FieldError(f"{path}.nodes", "at least one node to tie")
            with _entry(path):
                s.add_rigid_link(independent, dependent)
        for i, clamp in enumerate(self.clamps):
            path = f"clamps[{i}]"
            clamp_node = self._known_node(clamp.node, f"{path}.node")
            if not (clamp.dofs == "all" or (not isinstance(clamp.dofs, str) and clamp.dofs)):
                raise FieldError(
                    f"{path}.dofs", f"'all' or a list of {DOF_NAMES}, got {clamp.dofs!r}"
                )
            with _entry(path):  # a 3-D frame uses every dof: each clamp attaches to a support
                s.clamp(clamp_node, clamp.dofs, support=True)
        return s

    def _add_element(self, s: Structure, element: ElementSpec, path: str) -> None:
        if element.kind not in ELEMENT_KINDS:
            raise FieldError("kind", f"must be one of {ELEMENT_KINDS}, got {element.kind!r}")
        try:
            n1, n2 = element.nodes
        except (TypeError, ValueError):
            raise FieldError("nodes", f"two node ids, got {element.nodes!r}") from None
        n1 = self._known_node(n1, f"{path}.nodes")
        n2 = self._known_node(n2, f"{path}.nodes")
        if n1 == n2:
            raise FieldError("nodes", f"two different nodes, got ({n1}, {n2})")
        material = _lookup(self.materials, element.material, "material")
        section = _lookup(self.sections, element.section, "section")
        if element.kind == "rod":
            for name in ("orientation", "offsets"):
                if getattr(element, name) is not None:
                    raise FieldError(name, "a rod has no orientation or offsets (a frame has)")
            s.add_rod(n1, n2, material, section.A, lumped=element.lumped)
            return
        if element.orientation is not None and not np.any(np.asarray(element.orientation)):
            raise FieldError("orientation", "must be a nonzero vector in the local x-y plane")
        s.add_frame(
            n1,
            n2,
            material,
            section,
            orientation=element.orientation,
            offsets=element.offsets,
            lumped=element.lumped,
        )

    def modal_model(self) -> ModalModel:
        """The modal model: ``n_modes`` elastic modes (and the six rigid-body modes of a free
        structure) of :meth:`structure`, :meth:`ModalModel.from_fe`.

        Raises
        ------
        FieldError
            As :meth:`structure`; ``n_modes`` beyond the model's dofs; a free structure without
            exactly six rigid-body modes or a clamped one with a mechanism (``structure``).
        """
        structure = self.structure()
        try:
            assembly = structure.assemble()
        except FieldError:
            raise
        except ValueError as exc:  # "node 7: not connected to any element or mass"
            raise FieldError("structure", str(exc)) from None
        rigid = _RIGID_MODES if self.free else 0
        wanted = self.n_modes + rigid
        if wanted > assembly.n_dofs:
            raise FieldError(
                "n_modes",
                f"the model has {assembly.n_dofs} dofs, so at most {assembly.n_dofs - rigid} "
                f"elastic modes; got {self.n_modes}",
            )
        try:
            modes = assembly.modes(wanted, rigid_body_modes=rigid or None)
        except FieldError as exc:  # the solver's mechanism / rigid-mode checks: the structure's
            raise FieldError("structure", f"{exc.field}: {exc.rule}") from None
        zeta = np.broadcast_to(np.asarray(self.damping, dtype=float), (self.n_modes,))
        return ModalModel.from_fe(
            modes,
            damping=np.r_[np.zeros(rigid), zeta],
            reference=self._reference(),
            boundary="free" if self.free else None,
        )

    def _reference(self) -> npt.ArrayLike:
        if self.reference is not None:
            p = require_finite(self.reference, "reference")
            if p.shape != (3,):
                raise FieldError("reference", f"must have 3 coordinates, got shape {p.shape}")
            return p
        if self.free:
            return np.zeros(3)
        first = self.clamps[0].node
        return next(np.asarray(n.xyz, dtype=float) for n in self.nodes if n.id == first)


@contextmanager
def _entry(path: str) -> Iterator[None]:
    """Place a FieldError (or a Structure's ``"node 7: ..."`` ValueError) raised for one entry
    under its path: ``elements[3]`` + ``material`` -> ``elements[3].material``."""
    try:
        yield
    except FieldError as exc:
        if exc.field.startswith(path):
            raise
        raise FieldError(f"{path}.{exc.field}", exc.rule) from None
    except ValueError as exc:
        raise FieldError(path, str(exc)) from None


def _node_id(value: object, index: int) -> int:
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise FieldError(f"nodes[{index}].id", f"must be an integer, got {value!r}")
    return int(value)


def _lookup(table: Mapping[str, T], key: str, what: str) -> T:
    if key not in table:
        known = ", ".join(map(repr, table)) or "none"
        raise FieldError(what, f"unknown {what} {key!r} (the {what}s: {known})")
    return table[key]
