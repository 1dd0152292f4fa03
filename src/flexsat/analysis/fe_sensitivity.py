r"""Natural-frequency, mode-shape and mass derivatives of FE models with respect to design data.

A design parameter p of a :class:`flexsat.structures.fem.Structure` changes its stiffness and
mass matrices; ∂K/∂p and ∂M/∂p are assembled from the element matrices' analytic derivatives
(:meth:`~flexsat.structures.fem.Structure.property_derivative`: every element matrix is linear
in each single member property) and chained through the section formulas of
:class:`~flexsat.structures.sections.Section` (tube, rectangle). The eigen-derivatives of
K φ = λ M φ (λ = ω², φᵀ M φ = 1) are

.. math::

    \frac{\partial \lambda}{\partial p} = \varphi^T \Big(\frac{\partial K}{\partial p}
        - \lambda \frac{\partial M}{\partial p}\Big) \varphi, \qquad
    \frac{\partial \omega}{\partial p} = \frac{1}{2\omega}\frac{\partial \lambda}{\partial p},
    \qquad \frac{\partial f}{\partial p} = \frac{1}{2\pi}\frac{\partial \omega}{\partial p},

(Fox & Kapoor, "Rates of change of eigenvalues and eigenvectors", AIAA J. 6(12), 2426-2429,
1968), and the mode-shape derivatives come from Nelson's method (Nelson, AIAA J. 14(9),
1201-1205, 1976; :func:`flexsat.analysis.sensitivity.nelson_derivatives`), exact for a simple
eigenvalue and needing only the modes asked for.

Free-free structures: the rigid-body modes (λ = 0, repeated r times) stay at λ = 0 for every
parameter (rigid motions are null vectors of every element stiffness, whatever its
properties), so they are not differentiated: asking for one is refused by name (their shapes
span a subspace whose basis is not unique). Elastic modes of a free structure are handled by
Nelson's method unchanged: at an elastic λ, K − λ M is singular only along φ (the rigid modes
are eigenvectors of another eigenvalue), and the mode derivative keeps φᵀ M φ = 1.

Units: λ in (rad/s)², ω in rad/s, f in Hz; derivatives per SI unit of the parameter (m, m², m⁴,
Pa, kg/m³, kg, kg m²). Axial preloads are held fixed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from flexsat.analysis.sensitivity import GAP_RTOL, nelson_derivatives
from flexsat.input_checks import FieldError, require_finite, require_positive
from flexsat.structures.elements import skew
from flexsat.structures.fem import Assembly, Structure
from flexsat.structures.sections import Section
from flexsat.units import FloatArray

__all__ = [
    "FEModalDerivatives",
    "FEParameterMatrices",
    "LumpedInertia",
    "LumpedMass",
    "MemberProperty",
    "RectangleSection",
    "TubeSection",
    "fe_modal_derivatives",
    "fe_parameter_matrices",
    "rectangle_section_derivatives",
    "tube_section_derivatives",
]

_SECTION_RTOL = 1e-9  # given section dimensions must reproduce the stored A, Iy, Iz, J
_RECT_TERMS = 40  # odd terms of the rectangle torsion series, as in structures.sections
_AXES = {"x": "rx", "y": "ry", "z": "rz"}
_DOFS = ("ux", "uy", "uz", "rx", "ry", "rz")


# -- design parameters -------------------------------------------------------------------------
@dataclass(frozen=True)
class MemberProperty:
    """One member property shared by a group of members (see ``Structure.property_derivative``).

    Attributes
    ----------
    quantity : str
        ``"A"``, ``"Iy"``, ``"Iz"``, ``"J"``, ``"E"``, ``"G"``, ``"rho"`` (frame; fewer for
        beams and rods), or ``"EI"``, ``"GJ"``, ``"mass_per_length"``,
        ``"torsional_inertia_per_length"`` (grid).
    elements : tuple of int
        Element ids of the group.
    """

    quantity: str
    elements: tuple[int, ...]


@dataclass(frozen=True)
class TubeSection:
    """Outer diameter or wall thickness of a group of tube members (``Section.tube``).

    ``outer_diameter`` and ``thickness`` are the group's current dimensions, m; they are
    checked against the stored section properties of every member of the group.
    """

    dimension: str  # "outer_diameter" or "thickness"
    elements: tuple[int, ...]
    outer_diameter: float
    thickness: float


@dataclass(frozen=True)
class RectangleSection:
    """Width (local y) or height (local z) of a group of solid rectangles (``Section.rectangle``).

    ``width`` and ``height`` are the current dimensions, m, checked against the stored section.
    """

    dimension: str  # "width" or "height"
    elements: tuple[int, ...]
    width: float
    height: float


@dataclass(frozen=True)
class LumpedMass:
    r"""A point mass added at ``node`` (kg), its centre at the rigid ``offset`` r from the node
    (m, global axes; None: at the node).

    ∂M = Tᵀ diag(I₃, 0) T with T = [I, −[r×]] on the node's six dofs
    (:meth:`~flexsat.structures.fem.Structure.add_mass`): I₃ on the translations when r = 0.
    A node tied by a rigid link carries it to its independent node's dofs through the link's
    recovery u_d = G q (:class:`~flexsat.structures.fem.DependentDofs`), ∂M_r = Gᵀ ∂M G."""

    node: int
    offset: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class LumpedInertia:
    """A principal inertia added at ``node`` about global ``axis`` ("x", "y", "z"), kg m²
    (1 on that rotation; an offset of the body does not enter, :class:`LumpedMass`; a rigidly
    linked node as there)."""

    node: int
    axis: str


DesignParameter = MemberProperty | TubeSection | RectangleSection | LumpedMass | LumpedInertia


# -- section formulas and their derivatives ----------------------------------------------------
def tube_section_derivatives(outer_diameter: float, thickness: float) -> dict[str, FloatArray]:
    r"""∂(A, Iy, Iz, J)/∂D and ∂(A, Iy, Iz, J)/∂t of a circular tube (``Section.tube``).

    With d = D − 2t: A = π (D² − d²)/4, I = π (D⁴ − d⁴)/64, J = 2I (Roark, 8th ed., App. A),
    so ∂A/∂D = π (D − d)/2, ∂A/∂t = π d, ∂I/∂D = π (D³ − d³)/16, ∂I/∂t = π d³/8.

    Returns
    -------
    dict
        ``"outer_diameter"`` and ``"thickness"``: arrays (4,) of ∂(A, Iy, Iz, J), SI per m.
    """
    D = float(require_positive(outer_diameter, "outer_diameter"))
    t = float(require_positive(thickness, "thickness"))
    if t > D / 2:
        raise FieldError("thickness", f"must be <= outer_diameter / 2 = {D / 2!r}, got {t!r}")
    d = D - 2.0 * t
    dA_dD, dA_dt = math.pi * (D - d) / 2.0, math.pi * d
    dI_dD, dI_dt = math.pi * (D**3 - d**3) / 16.0, math.pi * d**3 / 8.0
    return {
        "outer_diameter": np.array([dA_dD, dI_dD, dI_dD, 2.0 * dI_dD]),
        "thickness": np.array([dA_dt, dI_dt, dI_dt, 2.0 * dI_dt]),
    }


def rectangle_section_derivatives(width: float, height: float) -> dict[str, FloatArray]:
    r"""∂(A, Iy, Iz, J)/∂b and ∂(A, Iy, Iz, J)/∂h of a solid rectangle (``Section.rectangle``).

    A = b h, I_y = b h³/12, I_z = h b³/12, and with a ≥ c the long and short sides, ρ = a/c and
    S(ρ) = Σ_{n odd} tanh(nπρ/2)/n⁵ (Timoshenko & Goodier §109)

    .. math::

        J = \frac{a c^3}{3} - \frac{64}{\pi^5} c^4 S(\rho),\quad
        \frac{\partial J}{\partial a} = \frac{c^3}{3} - \frac{64}{\pi^5} c^3 S'(\rho),\quad
        \frac{\partial J}{\partial c} = a c^2 - \frac{64}{\pi^5}\,(4 c^3 S - a c^2 S'),

    with S'(ρ) = Σ (π/2) sech²(nπρ/2)/n⁴, summed over the same 40 odd terms.

    Returns
    -------
    dict
        ``"width"`` and ``"height"``: arrays (4,) of ∂(A, Iy, Iz, J), SI per m.
    """
    b = float(require_positive(width, "width"))
    h = float(require_positive(height, "height"))
    a, c = max(b, h), min(b, h)
    n = np.arange(1, 2 * _RECT_TERMS, 2, dtype=float)
    x = n * math.pi * a / (2.0 * c)
    S = float(np.sum(np.tanh(x) / n**5))
    e = np.exp(-2.0 * x)  # sech²x = 4 e^{-2x} / (1 + e^{-2x})², without overflowing cosh
    dS = float(np.sum(0.5 * math.pi * 4.0 * e / (1.0 + e) ** 2 / n**4))
    k = 64.0 / math.pi**5
    dJ_da = c**3 / 3.0 - k * c**3 * dS
    dJ_dc = a * c**2 - k * (4.0 * c**3 * S - a * c**2 * dS)
    dJ_db, dJ_dh = (dJ_da, dJ_dc) if b >= h else (dJ_dc, dJ_da)
    return {
        "width": np.array([h, h**3 / 12.0, h * b**2 / 4.0, dJ_db]),
        "height": np.array([b, b * h**2 / 4.0, b**3 / 12.0, dJ_dh]),
    }


# -- ∂K/∂p, ∂M/∂p ------------------------------------------------------------------------------
@dataclass(frozen=True)
class FEParameterMatrices:
    """∂K/∂p_k, ∂M/∂p_k on the active dofs of ``structure.assemble()``, and ∂(mass)/∂p_k.

    Attributes
    ----------
    dK, dM : list of scipy.sparse.csr_matrix (ndof, ndof)
    mass : float
        Structural mass (members and lumped masses), kg.
    mass_gradient : (P,) ndarray
        ∂(mass)/∂p_k, kg per unit p_k (0 for inertias, E and G).
    assembly : Assembly
        ``structure.assemble()``, whose K and M these derivatives belong to.
    """

    dK: list[sp.csr_matrix]
    dM: list[sp.csr_matrix]
    mass: float
    mass_gradient: FloatArray
    assembly: Assembly


def _group(elements: object, field: str) -> tuple[int, ...]:
    if isinstance(elements, (str, bytes)) or not isinstance(elements, (Sequence, np.ndarray)):
        raise FieldError(field, f"must be a sequence of element ids, got {elements!r}")
    return tuple(elements)  # ids checked by Structure.property_derivative


def _check_section(
    structure: Structure, elements: tuple[int, ...], section: Section, what: str
) -> None:
    want = np.array([section.A, section.Iy, section.Iz, section.J])
    for e in set(elements):
        info = structure.element(e)
        props = info["properties"]
        if info["kind"] != "frame":
            raise FieldError(what, f"element {e} is a {info['kind']}, not a frame")
        got = np.array([props["A"], props["Iy"], props["Iz"], props["J"]])
        if np.any(np.abs(got - want) > _SECTION_RTOL * np.abs(want)):
            raise FieldError(
                what,
                f"the given dimensions give (A, Iy, Iz, J) = {want}, but element {e} has {got}",
            )


def _section_chain(
    structure: Structure, param: TubeSection | RectangleSection
) -> tuple[sp.csr_matrix, sp.csr_matrix, float]:
    elements = _group(param.elements, "elements")
    if isinstance(param, TubeSection):
        field, section = "TubeSection", Section.tube(param.outer_diameter, param.thickness)
        table = tube_section_derivatives(param.outer_diameter, param.thickness)
    else:
        field, section = "RectangleSection", Section.rectangle(param.width, param.height)
        table = rectangle_section_derivatives(param.width, param.height)
    if param.dimension not in table:
        raise FieldError("dimension", f"must be one of {tuple(table)}, got {param.dimension!r}")
    _check_section(structure, elements, section, field)
    # the element matrices are jointly affine in (A, Iy, Iz, J): one directional derivative
    direction = dict(zip(("A", "Iy", "Iz", "J"), table[param.dimension]))
    return structure.property_derivative(direction, elements)


def _node_motion(assembly: Assembly, node: int) -> sp.csr_matrix:
    """E (6, ndof): the six dofs of ``node`` from the active dofs, u_node = E q (a clamped or
    untouched dof: a zero row; a rigidly linked node: its rows of the link recovery G)."""
    n = assembly.n_dofs
    dep = assembly.dependent
    ids = [int(i) for i in assembly.node_ids]
    if dep is not None and node in ids and np.any(dep.nodes == ids.index(node)):
        where = np.flatnonzero(dep.nodes == ids.index(node))
        E = sp.lil_matrix((6, n))
        for r in where:
            E[int(dep.slots[r]), :] = dep.G[int(r)]
        return E.tocsr()
    active = set(assembly.dofs)
    rows = [(slot, assembly.index(node, d)) for slot, d in enumerate(_DOFS) if (node, d) in active]
    if not rows:
        return sp.csr_matrix((6, n))
    slots, cols = zip(*rows)
    return sp.csr_matrix((np.ones(len(rows)), (slots, cols)), shape=(6, n))


def _lumped_derivative(
    assembly: Assembly, node: int, block: FloatArray, field: str
) -> sp.csr_matrix:
    """Eᵀ B E (:func:`_node_motion`): the 6x6 ∂M ``block`` of a node on the active dofs; refused
    by name when none of the dofs it acts on moves (a clamped dof carries no mass into
    K φ = λ M φ)."""
    E = _node_motion(assembly, node)
    dM = (E.T @ sp.csr_matrix(block) @ E).tocsr()
    if dM.nnz == 0 or not np.any(dM.data):
        acts = tuple(d for d, b in zip(_DOFS, np.abs(block).sum(axis=1)) if b > 0)
        raise FieldError(
            field,
            f"node {node!r}: none of the dofs {acts} is active (unknown node, clamped, "
            "or not touched by an element or mass; an inertia needs an active rotation)",
        )
    return dM


def fe_parameter_matrices(
    structure: Structure, parameters: Sequence[DesignParameter]
) -> FEParameterMatrices:
    """∂K/∂p and ∂M/∂p of a structure for each design parameter, and the mass gradient.

    Member properties: ``Structure.property_derivative`` (exact, the element matrices are
    linear in each property). Section dimensions: the chain rule through
    :func:`tube_section_derivatives` / :func:`rectangle_section_derivatives`,
    ∂K/∂x = Σ_q (∂q/∂x) ∂K/∂q over q ∈ (A, Iy, Iz, J). Lumped mass m at a node: ∂M/∂m = 1 on
    its active translations; lumped inertia about an axis: 1 on that rotation.

    Parameters
    ----------
    structure : Structure
    parameters : sequence of MemberProperty, TubeSection, RectangleSection, LumpedMass,
        LumpedInertia

    Returns
    -------
    FEParameterMatrices
    """
    if not isinstance(structure, Structure):
        raise FieldError("structure", f"must be a Structure, got {type(structure).__name__}")
    if isinstance(parameters, (str, bytes)) or not isinstance(parameters, Sequence):
        raise FieldError(
            "parameters", f"must be a sequence of design parameters, got {parameters!r}"
        )
    if not parameters:
        raise FieldError("parameters", "must name at least one design parameter")
    assembly = structure.assemble()
    n = assembly.n_dofs
    dKs, dMs, dmass = [], [], []
    for param in parameters:
        if isinstance(param, MemberProperty):
            k, m, dm = structure.property_derivative(
                param.quantity, _group(param.elements, "elements")
            )
        elif isinstance(param, (TubeSection, RectangleSection)):
            k, m, dm = _section_chain(structure, param)
        elif isinstance(param, (LumpedMass, LumpedInertia)):
            block = np.zeros((6, 6))
            if isinstance(param, LumpedMass):
                block[:3, :3] = np.eye(3)
                if param.offset is not None:
                    r = require_finite(param.offset, "offset")
                    if r.shape != (3,):
                        raise FieldError("offset", f"must have 3 components, got {r.shape}")
                    T = np.eye(6)
                    T[:3, 3:] = -skew(r)
                    block = T.T @ block @ T
                field, dm = "LumpedMass", 1.0
            else:
                if param.axis not in _AXES:
                    raise FieldError("axis", f"must be 'x', 'y' or 'z', got {param.axis!r}")
                slot = _DOFS.index(_AXES[param.axis])
                block[slot, slot] = 1.0
                field, dm = "LumpedInertia", 0.0
            k = sp.csr_matrix((n, n))
            m = _lumped_derivative(assembly, param.node, block, field)
        else:
            raise FieldError(
                "parameters",
                f"each must be a MemberProperty, TubeSection, RectangleSection, LumpedMass or "
                f"LumpedInertia, got {type(param).__name__}",
            )
        dKs.append(k)
        dMs.append(m)
        dmass.append(dm)
    return FEParameterMatrices(
        dKs, dMs, structure.structural_mass(), np.array(dmass, dtype=float), assembly
    )


# -- eigen-derivatives -------------------------------------------------------------------------
@dataclass(frozen=True)
class FEModalDerivatives:
    """Selected modes of an FE structure and their derivatives with respect to design data.

    Attributes
    ----------
    indices : (s,) int
        Mode numbers (0-based, ascending ω, rigid-body modes first).
    eigenvalues : (s,) float
        λ = ω², (rad/s)².
    omegas : (s,) float
        ω, rad/s.
    frequencies_hz : (s,) float
        f = ω/2π, Hz.
    modes : (ndof, s) float
        Mass-normalised φ (signed as ``Assembly.modes`` signs them).
    eigenvalue_gradient : (P, s) float
        ∂λ/∂p_k, (rad/s)² per unit p_k.
    omega_gradient : (P, s) float
        ∂ω/∂p_k, rad/s per unit p_k.
    frequency_hz_gradient : (P, s) float
        ∂f/∂p_k, Hz per unit p_k.
    mode_gradient : (P, ndof, s) float
        ∂φ/∂p_k (Nelson), keeping φᵀ M φ = 1.
    mass : float
        Structural mass, kg.
    mass_gradient : (P,) float
        ∂(mass)/∂p_k.
    assembly : Assembly
    """

    indices: npt.NDArray[np.int_]
    eigenvalues: FloatArray
    omegas: FloatArray
    frequencies_hz: FloatArray
    modes: FloatArray
    eigenvalue_gradient: FloatArray
    omega_gradient: FloatArray
    frequency_hz_gradient: FloatArray
    mode_gradient: FloatArray
    mass: float
    mass_gradient: FloatArray
    assembly: Assembly


def _mode_numbers(modes: object) -> npt.NDArray[np.int_]:
    sel = np.atleast_1d(np.asarray(modes))
    if sel.ndim != 1 or sel.size == 0 or sel.dtype.kind not in "iu" or np.any(sel < 0):
        raise FieldError("modes", f"must be mode numbers (integers >= 0), got {modes!r}")
    if np.unique(sel).size != sel.size:
        raise FieldError("modes", f"must not repeat a mode, got {modes!r}")
    return sel


def fe_modal_derivatives(
    structure: Structure,
    parameters: Sequence[DesignParameter],
    modes: Sequence[int] | npt.ArrayLike,
    *,
    rigid_body_modes: int | None = None,
    gap_rtol: float = GAP_RTOL,
) -> FEModalDerivatives:
    """Frequencies and mode shapes of a structure and their derivatives (Fox-Kapoor, Nelson).

    Parameters
    ----------
    structure : Structure
    parameters : sequence of design parameters (see :func:`fe_parameter_matrices`)
    modes : sequence of int
        Mode numbers, 0-based, ascending ω, rigid-body modes counted.
    rigid_body_modes : int, optional
        As ``Assembly.modes`` (6 for a free 3-D body); selecting a rigid-body mode is refused.
    gap_rtol : float
        A selected λ closer than ``gap_rtol · λ_max`` (λ_max of the computed modes) to a
        neighbour counts as repeated and is refused: its derivatives divide by the gap.

    Returns
    -------
    FEModalDerivatives
    """
    sel = _mode_numbers(modes)
    gap_rtol = float(require_positive(gap_rtol, "gap_rtol"))
    mats = fe_parameter_matrices(structure, parameters)
    asm = mats.assembly
    n_massive = int(np.sum(asm.M.diagonal() > 0))
    if sel.max() >= n_massive:
        raise FieldError(
            "modes", f"must be < the number of dofs with mass ({n_massive}), got {int(sel.max())}"
        )
    # one mode above the highest selected one, to see the gap above it
    fe = asm.modes(min(int(sel.max()) + 2, n_massive), rigid_body_modes=rigid_body_modes)
    lam_all = fe.omegas**2
    rigid = np.flatnonzero(fe.omegas == 0.0)  # exactly 0: cleaned by Assembly.modes
    if np.isin(sel, rigid).any():
        raise FieldError(
            "modes",
            f"mode {int(sel[np.isin(sel, rigid)][0])} is one of {rigid.size} rigid-body modes "
            "(ω = 0, which stays 0 for every parameter; ω itself is not differentiable there and "
            "a repeated ω = 0 has no unique shape derivative): select elastic modes",
        )
    tol = gap_rtol * max(float(lam_all.max()), float(np.finfo(float).tiny))
    for i in sel:
        others = np.delete(lam_all, i)
        j = int(np.argmin(np.abs(others - lam_all[i])))
        if abs(others[j] - lam_all[i]) <= tol:
            j = j + (j >= i)
            raise FieldError(
                "modes",
                f"modes {min(i, j)} and {max(i, j)} are repeated (ω = {fe.omegas[i]:.6g} and "
                f"{fe.omegas[j]:.6g} rad/s, λ gap <= {tol:.3g} = gap_rtol x λ_max); Nelson's "
                "method needs a simple eigenvalue",
            )
    lam, phi = lam_all[sel], fe.shapes[:, sel]
    dlam, dphi = nelson_derivatives(asm.K, asm.M, mats.dK, mats.dM, lam, phi)
    omega = np.sqrt(lam)
    domega = dlam / (2.0 * omega)
    return FEModalDerivatives(
        indices=sel,
        eigenvalues=lam,
        omegas=omega,
        frequencies_hz=omega / (2.0 * np.pi),
        modes=phi,
        eigenvalue_gradient=dlam,
        omega_gradient=domega,
        frequency_hz_gradient=domega / (2.0 * np.pi),
        mode_gradient=dphi,
        mass=mats.mass,
        mass_gradient=mats.mass_gradient,
        assembly=asm,
    )
