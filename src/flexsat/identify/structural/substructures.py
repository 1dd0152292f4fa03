"""Substructure parameterisation of M, K, C for the Creamer-Junkins structural identification
(Junkins, Pollock & Rahman 1990, Att. 7).

The model is parameterised by substructure scalings (Att. 7 Eqs. 8, 23)::

    K(p) = K0 + sum_k p_k K_k,   M(q) = M0 + sum_k q_k M_k,   C(r) = C0 + sum_k r_k C_k

(``p = q = r = 1`` is the nominal model; ``K0, M0, C0`` are fixed parts, e.g. members carrying no
modal energy that are left out of the identification, Att. 7 Example 2).  The paper writes the
same thing as corrections ``gamma = q - 1``, ``beta = p - 1`` to a nominal model.

The identification itself is in :mod:`flexsat.identify.structural.undamped` and
:mod:`flexsat.identify.structural.damping`; :func:`modal_energy_distribution` (Att. 7 Table 1)
helps choose the substructures.

All matrices may be dense arrays or scipy sparse matrices; the eigen-solves are dense (models up
to a few thousand dofs).  Errors are ``ValueError`` naming the field.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from flexsat import limits
from flexsat.identify.structural.validation import (
    block_list,
    check_blocks,
    check_matrix,
    check_shapes,
)
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_nonneg,
    require_numeric,
)
from flexsat.structures.modal_solve import Matrix
from flexsat.units import FloatArray

__all__ = [
    "SubstructureModel",
    "require_model",
    "start_scalings",
    "substructures_from_builder",
    "modal_energy_distribution",
]


def require_model(model: object) -> SubstructureModel:
    """``model`` when it is a :class:`SubstructureModel`."""
    if not isinstance(model, SubstructureModel):
        raise FieldError("model", f"must be a SubstructureModel, got {type(model).__name__}")
    return model


def start_scalings(
    model: SubstructureModel, values: npt.ArrayLike | None, count: int, name: str
) -> FloatArray:
    """Start scalings of stiffness or mass: ``count`` numbers > 0 (default 1), a copy."""
    v = model.check_scalings(values, count, name).copy()
    if np.any(v <= 0):
        raise FieldError(
            name, f"must be > 0 (a substructure's stiffness or mass is scaled), got {v}"
        )
    return v


@dataclass(frozen=True, eq=False)
class SubstructureModel:
    """``K(p) = K0 + sum p_k K_k``, ``M(q) = M0 + sum q_k M_k``, ``C(r) = C0 + sum r_k C_k``.

    Parameters
    ----------
    K_blocks, M_blocks : list of (n, n) matrices
        Substructure stiffness and mass blocks (dense or sparse, symmetric).
    C_blocks : list of (n, n) matrices, optional
        Damping blocks (coupling pattern; any magnitude).
    K0, M0, C0 : (n, n), optional
        Fixed parts (default zero).
    names : optional labels for the substructures (stiffness/mass share names when the lists
        have the same length).
    """

    K_blocks: list[FloatArray]
    M_blocks: list[FloatArray]
    C_blocks: list[FloatArray] = field(default_factory=list)
    K0: FloatArray | None = None
    M0: FloatArray | None = None
    C0: FloatArray | None = None
    names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        stiffness = block_list(self.K_blocks, "K_blocks")
        if not stiffness and self.K0 is None:
            raise FieldError("K_blocks", "give at least one stiffness block (or K0)")
        first = (
            check_matrix(stiffness[0], "K_blocks[0]") if stiffness else check_matrix(self.K0, "K0")
        )
        n = first.shape[0]
        object.__setattr__(self, "K_blocks", check_blocks(stiffness, "K_blocks", n))
        object.__setattr__(self, "M_blocks", check_blocks(self.M_blocks, "M_blocks", n))
        object.__setattr__(self, "C_blocks", check_blocks(self.C_blocks, "C_blocks", n))
        if not self.M_blocks and self.M0 is None:
            raise FieldError("M_blocks", "give at least one mass block (or M0)")
        for name in ("K0", "M0", "C0"):
            value = getattr(self, name)
            object.__setattr__(
                self, name, np.zeros((n, n)) if value is None else check_matrix(value, name, n)
            )
        if isinstance(self.names, (str, bytes)) or not isinstance(self.names, Sequence):
            raise FieldError("names", f"must be a list of labels, got {self.names!r}")
        if not all(isinstance(label, str) for label in self.names):
            raise FieldError("names", f"must be strings, got {list(self.names)!r}")
        object.__setattr__(self, "names", tuple(self.names))

    @property
    def n_dofs(self) -> int:
        return _fixed(self.K0).shape[0]

    @property
    def n_stiffness(self) -> int:
        return len(self.K_blocks)

    @property
    def n_mass(self) -> int:
        return len(self.M_blocks)

    @property
    def n_damping(self) -> int:
        return len(self.C_blocks)

    def check_scalings(self, values: npt.ArrayLike | None, count: int, name: str) -> FloatArray:
        """Scalings ``values`` as a vector of ``count`` numbers (one per block), ones when None;
        refused by ``name`` otherwise."""
        if values is None:
            return np.ones(count)
        v = require_numeric(values, name, "vector").ravel()
        if v.shape != (count,):
            raise FieldError(name, f"must have {count} entries (one per block), got {v.size}")
        return v

    def K(self, p: npt.ArrayLike | None = None) -> FloatArray:
        scale = self.check_scalings(p, self.n_stiffness, "p")
        return _combination(_fixed(self.K0), scale, self.K_blocks)

    def M(self, q: npt.ArrayLike | None = None) -> FloatArray:
        scale = self.check_scalings(q, self.n_mass, "q")
        return _combination(_fixed(self.M0), scale, self.M_blocks)

    def C(self, r: npt.ArrayLike | None = None) -> FloatArray:
        scale = self.check_scalings(r, self.n_damping, "r")
        return _combination(_fixed(self.C0), scale, self.C_blocks)

    def modes(
        self,
        p: npt.ArrayLike | None = None,
        q: npt.ArrayLike | None = None,
        n_modes: int | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """Natural frequencies (rad/s, ascending) and mass-normalised shapes (n, n_modes).

        Solved by :func:`flexsat.structures.modal_solve.solve_modes` (shift-invert pencil,
        eigenvalues as Rayleigh quotients of the computed vectors): each eigenvalue comes out
        to its own relative accuracy, not to ``eps max(lambda)``.  A Cholesky-reduced solve
        (``scipy.linalg.eigh(K, M)``, above all its bisection subset driver) carries an absolute
        error ~ ``eps max(lambda)``: on the Att. 7 arm (lambda spanning 5e-4 .. 4e7) that is a
        1e-5 relative error on the base-spring mode, which varied with the BLAS kernel.
        """
        from flexsat.structures.modal_solve import solve_modes  # the FE package: on first use

        K, M = self.K(p), self.M(q)
        count = (
            self.n_dofs if n_modes is None else min(require_count(n_modes, "n_modes"), self.n_dofs)
        )
        try:
            np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            raise FieldError("q", "mass scalings: M(q) is not positive definite") from None
        try:
            return solve_modes(K, M, count)
        except ValueError as error:
            raise FieldError(
                "p", f"stiffness scalings: K(p) is not positive semi-definite ({error})"
            ) from None

    def scaled(
        self,
        p: npt.ArrayLike | None = None,
        q: npt.ArrayLike | None = None,
        r: npt.ArrayLike | None = None,
    ) -> SubstructureModel:
        """The same parameterisation with the blocks multiplied by ``p, q, r`` (new nominal)."""
        ps = self.check_scalings(p, self.n_stiffness, "p")
        qs = self.check_scalings(q, self.n_mass, "q")
        rs = self.check_scalings(r, self.n_damping, "r")
        return SubstructureModel(
            [a * B for a, B in zip(ps, self.K_blocks)],
            [a * B for a, B in zip(qs, self.M_blocks)],
            [a * B for a, B in zip(rs, self.C_blocks)],
            self.K0,
            self.M0,
            self.C0,
            self.names,
        )


def _fixed(part: FloatArray | None) -> FloatArray:
    """A fixed part K0, M0 or C0 of a model: zeros when not given (``__post_init__``)."""
    assert part is not None  # __post_init__ replaces None by zeros
    return part


def _combination(fixed: FloatArray, scale: FloatArray, blocks: list[FloatArray]) -> FloatArray:
    """``fixed + sum_k scale_k blocks_k``."""
    return fixed + sum((a * B for a, B in zip(scale, blocks)), np.zeros_like(fixed))


def substructures_from_builder(
    build: Callable[[FloatArray, FloatArray], Any],
    n_stiffness: int,
    n_mass: int | None = None,
    C_blocks: Sequence[Matrix] = (),
    names: Sequence[str] = (),
) -> SubstructureModel:
    """Blocks of a linear FE model from a builder of scaled assemblies.

    ``build(stiffness_factors, mass_factors)`` must return an object with ``K`` and ``M`` (e.g. a
    :class:`flexsat.structures.fem.Assembly`) for the structure whose substructure ``k`` has its
    stiffness (e.g. ``E``) multiplied by ``stiffness_factors[k]`` and its mass (``rho``, lumped
    masses) by ``mass_factors[k]``.  The blocks are the exact differences ``K(e_k + 1) - K(1)``
    (assembly is linear in the factors without preloads) and the fixed parts ``K0 = K(1) -
    sum K_k``: members outside every substructure.
    """
    if not callable(build):
        raise FieldError("build", f"must be a function of (stiffness, mass) factors, got {build!r}")
    n_stiffness = require_count(n_stiffness, "n_stiffness")
    if n_mass is None:
        n_mass = n_stiffness
    elif not (limits.is_integral(n_mass) and n_mass >= 0):
        raise FieldError(
            "n_mass", f"must be an integer >= 0 (0: the whole mass fixed, in M0), got {n_mass!r}"
        )
    n_mass = int(n_mass)
    # each block is a dense n x n matrix: bounded before the builder runs n_stiffness times
    limits.check_count(
        n_stiffness + n_mass,
        limits.MAX_ELEMENTS,
        "n_stiffness",
        "substructures (n_stiffness + n_mass)",
        "a substructure groups elements, there are at most as many as elements",
    )
    one_k, one_m = np.ones(n_stiffness), np.ones(n_mass)

    def assembly(k_factors: FloatArray, m_factors: FloatArray) -> tuple[FloatArray, FloatArray]:
        built = build(k_factors, m_factors)
        if not (hasattr(built, "K") and hasattr(built, "M")):
            raise FieldError(
                "build",
                "must return an object with K and M (e.g. an Assembly), got "
                f"{type(built).__name__}",
            )
        K = check_matrix(built.K, "build().K")
        return K, check_matrix(built.M, "build().M", K.shape[0])

    K1, M1 = assembly(one_k, one_m)
    n = K1.shape[0]
    limits.check_memory(
        8 * (n_stiffness + n_mass + 2) * n * n, "n_stiffness", "the substructure blocks"
    )
    Kb, Mb = [], []
    for k in range(n_stiffness):
        f = one_k.copy()
        f[k] = 2.0
        Kb.append(check_matrix(assembly(f, one_m)[0], "build().K", n) - K1)
    for k in range(n_mass):
        f = one_m.copy()
        f[k] = 2.0
        Mb.append(check_matrix(assembly(one_k, f)[1], "build().M", n) - M1)
    K0 = K1 - sum(Kb, np.zeros_like(K1))
    M0 = M1 - sum(Mb, np.zeros_like(M1))
    scale_k, scale_m = np.abs(K1).max(), np.abs(M1).max()
    K0[np.abs(K0) < 1e-12 * scale_k] = 0.0
    M0[np.abs(M0) < 1e-12 * scale_m] = 0.0
    Cb = check_blocks(C_blocks, "C_blocks", n)
    return SubstructureModel(Kb, Mb, Cb, K0, M0, names=tuple(names))


def modal_energy_distribution(
    K_blocks: Sequence[Matrix],
    M_blocks: Sequence[Matrix],
    shapes: npt.ArrayLike,
    omegas: npt.ArrayLike | None = None,
) -> dict[str, FloatArray]:
    """Att. 7 Table 1: share of each substructure in the kinetic and strain energy of each mode.

    ``kinetic[i, g] = phi_i^T M_g phi_i`` and ``strain[i, g] = phi_i^T K_g phi_i / w_i^2``,
    each normalised to sum 1 over the given substructures (for mass-normalised modes of the full
    model and blocks that add up to it, the sums are 1 already; ``omegas`` only rescales the
    strain energy and may be omitted).  Substructures with a small share in the measured modes
    cannot be identified from them (choose the groups from this table).

    Returns
    -------
    dict with ``kinetic`` and ``strain``: arrays (n_modes, n_substructures), fractions.
    """
    Kb = check_blocks(K_blocks, "K_blocks")
    if not Kb:
        raise FieldError("K_blocks", "give at least one stiffness block")
    n = Kb[0].shape[0]
    Mb = check_blocks(M_blocks, "M_blocks", n)
    if not Mb:
        raise FieldError("M_blocks", "give at least one mass block")
    phi = check_shapes(shapes, "shapes", n)
    ke = np.array([np.einsum("ij,ik,kj->j", phi, Mg, phi) for Mg in Mb]).T
    pe = np.array([np.einsum("ij,ik,kj->j", phi, Kg, phi) for Kg in Kb]).T
    if omegas is not None:
        w = require_nonneg(omegas, "omegas", "rad/s")
        if w.shape != (phi.shape[1],):
            raise FieldError("omegas", f"must have {phi.shape[1]} entries (one per mode)")
        pe = pe / np.where(w > 0, w**2, 1.0)[:, None]

    def frac(e: FloatArray, what: str) -> FloatArray:
        tot = e.sum(axis=1, keepdims=True)
        if np.any(np.abs(tot) <= 0):
            raise FieldError("shapes", f"a mode has no {what} energy in the given blocks")
        return e / tot

    return dict(kinetic=frac(ke, "kinetic"), strain=frac(pe, "strain"))
