"""Structural identification of substructure scalings of M, K, C: Creamer–Junkins (Att. 7).

The model is parameterised by substructure scalings (Att. 7 Eqs. 8, 23)::

    K(p) = K0 + sum_k p_k K_k,   M(q) = M0 + sum_k q_k M_k,   C(r) = C0 + sum_k r_k C_k

(``p = q = r = 1`` is the nominal model; ``K0, M0, C0`` are fixed parts, e.g. members carrying no
modal energy that are left out of the identification, Att. 7 Example 2).  The paper writes the
same thing as corrections ``gamma = q - 1``, ``beta = p - 1`` to a nominal model.

Undamped identification (:func:`identify_undamped`, Att. 7 Eqs. 1–9)
    1. Measured frequencies ``wbar_r`` and mode shapes ``psibar_r`` (measured, or approximated
       by the current model's modes).  The shapes have an unknown scale: ``phi_r =
       sqrt(alpha_r) psibar_r`` (Eq. 4).
    2. Mass scalings from a few measured FRF elements (Eqs. 5–6 with Eq. 9a): the normalisation
       factors are written through the mass, ``alpha_r = 1 / psibar_r^T M(q) psibar_r`` (Eq.
       7a, i = j), and Eq. 5 is fitted in ``q`` by Gauss-Newton, together with the optional
       rigid-body term ``a1/w^2`` and residual ``a2``; the current model's prediction of the
       unmeasured modes is subtracted from the FRF first (the iteration of Att. 7
       "Identification of Undamped Structures").
    3. Stiffness scalings from Eq. 9b, ``psibar_i^T K psibar_j = delta_ij wbar_j^2/alpha_j``,
       linear least squares; with the current model's shapes the diagonal rows are exactly the
       Gauss-Newton step on the eigenvalues, since ``d(lambda_i)/dp_k = phi_i^T K_k phi_i`` and
       ``d(lambda_i)/dq_k = -lambda_i phi_i^T M_k phi_i`` (closed-form sensitivities of
       mass-normalised modes).  The model is re-solved and the steps repeated.

    Scale constraint.  Frequencies and shapes alone are unchanged by ``(K, M) -> c (K, M)``, so
    only the stiffness-to-mass ratio is identifiable from them.  The absolute scale enters only
    through the modal normalisation ``alpha`` (Eq. 4), which the FRF supplies (Eqs. 5–6; Att. 7
    advantage 1: "the FRF gives a unique scaling").  Without an FRF the mass scalings are held
    at their start values (``alpha_i = 1 / psibar_i^T M(q) psibar_i``: the mass is the known
    scale) and only the stiffness scalings are identified.

    Departures from the paper's sequence, both found necessary on the Example 1 arm (model
    shapes, 4 mass groups): (a) the paper fits each ``alpha_r`` separately (Eq. 6) and then
    ``q`` from them (Eq. 9a); a weakly participating mode then gets a wrong, even negative,
    ``alpha_r`` that the mass rows take at full weight, and the iteration diverged.  Fitting
    ``q`` directly weights each mode by its real share of the FRF.  (b) With model-predicted
    shapes a mass change also moves the shapes, the unmeasured modes and, through Eq. 9b, the
    stiffness; the mass step differentiates all of these (Nelson mode derivatives), otherwise
    it diverged even from 0.01 % off the true model.  ``a2`` is off by default: with the
    unmeasured modes predicted by the model it only absorbs the scale information of
    quasi-static FRF points.

    Off-diagonal rows of Eq. 9 carry information only when the shapes are measured; with
    model-predicted shapes they are identities of the current model that would wrongly freeze the
    mode shapes, so they are used only with ``measured_shapes`` (override:
    ``off_diagonal``).

Damping (:func:`identify_damping`, Att. 7 Eqs. 10–24)
    First-order perturbation of the state-space eigenproblem about the undamped model gives
    ``lambda_r ~= i w_0r - (1/2) phi_0r^T C phi_0r`` with mass-normalised ``phi_0r`` (Eq. 23): the
    measured real parts ``sigmabar_r`` give the linear least-squares problem (Eq. 24)
    ``sum_k r_k phi_0r^T C_k phi_0r = -2 sigmabar_r - phi_0r^T C0 phi_0r`` in configuration
    space (no 2n-dimensional eigenproblem).  The blocks ``C_k`` need only the right coupling
    pattern; their magnitudes may be off by orders of magnitude (the scalings absorb them).

The differential correction of Att. 6 (free and forced response together) is in
:mod:`flexsat.identify.differential_correction`.

All matrices may be dense arrays or scipy sparse matrices; the eigen-solves are dense (models up
to a few thousand dofs).  Errors are ``ValueError`` naming the field.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeAlias, cast

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from flexsat import limits
from flexsat.analysis.sensitivity import modal_derivatives
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_numeric,
    require_scalar,
)
from flexsat.structures.modal_solve import Matrix
from flexsat.units import FloatArray

__all__ = [
    "SubstructureModel",
    "UndampedIdentification",
    "DampingIdentification",
    "UpdatedModel",
    "substructures_from_builder",
    "modal_energy_distribution",
    "fit_modal_normalization",
    "identify_undamped",
    "identify_damping",
    "update_model",
    "damped_eigenvalues",
    "check_iterations",
]

IntArray: TypeAlias = npt.NDArray[np.intp]
ComplexArray: TypeAlias = npt.NDArray[np.complex128]
#: one FRF element as given: (output dof, input dof, omegas rad/s, receptance values)
FrfElement: TypeAlias = tuple[int, int, npt.ArrayLike, npt.ArrayLike]
#: one FRF element checked (:func:`_check_frf`)
FrfItem: TypeAlias = tuple[int, int, FloatArray, FloatArray]
#: per FRF element: values (N,) and two gradients (N, ...) (:func:`_model_frf`, :func:`_eq5`)
FrfRows: TypeAlias = tuple[FloatArray, FloatArray, FloatArray]


# ------------------------------------------------------------------------------------------------
def _array_like(A: Matrix) -> npt.ArrayLike:
    """A dense or sparse matrix as an array_like (sparse ones densified)."""
    return cast(Any, A).toarray() if sp.issparse(A) else A


def _dense(A: Matrix, field_name: str, n: int | None = None) -> FloatArray:
    A = require_numeric(_array_like(A), field_name, "matrix")
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.size == 0:
        raise FieldError(field_name, f"must be a non-empty square matrix, got shape {A.shape}")
    if n is not None and A.shape[0] != n:
        raise FieldError(field_name, f"must be {n}x{n} like the other blocks, got {A.shape}")
    if np.abs(A - A.T).max() > 1e-9 * max(np.abs(A).max(), 1e-300):
        raise FieldError(field_name, "must be symmetric")
    return (A + A.T) / 2.0


def _block_list(blocks: object, name: str) -> list[Matrix]:
    """``blocks`` as a list of the matrices it holds (unchecked); None is no block."""
    if blocks is None:
        return []
    if sp.issparse(blocks) or isinstance(blocks, (np.ndarray, str, bytes)):
        # an array is one matrix (or a stack), not the list of one matrix per substructure
        raise FieldError(name, "must be a list of matrices (one per substructure)")
    if not isinstance(blocks, Sequence):
        raise FieldError(
            name, f"must be a list of matrices (one per substructure), got {type(blocks).__name__}"
        )
    return list(blocks)


def _blocks(blocks: object, name: str, n: int | None = None) -> list[FloatArray]:
    """The blocks checked: symmetric, all n x n (the first one's size when ``n`` is None)."""
    out: list[FloatArray] = []
    for k, B in enumerate(_block_list(blocks, name)):
        out.append(_dense(B, f"{name}[{k}]", n))
        n = out[0].shape[0]
    return out


def _shape_matrix(shapes: npt.ArrayLike, field_name: str, n: int | None = None) -> FloatArray:
    """Mode shapes (n, m) (a vector is one shape), each with a nonzero entry."""
    phi = require_numeric(shapes, field_name, "matrix")
    if phi.ndim == 1:
        phi = phi[:, None]
    if phi.ndim != 2 or phi.size == 0:
        raise FieldError(field_name, f"must be a (dofs, modes) matrix, got shape {phi.shape}")
    if n is not None and phi.shape[0] != n:
        raise FieldError(field_name, f"must have one row per dof ({n}), got {phi.shape[0]}")
    if np.any(np.all(phi == 0, axis=0)):
        raise FieldError(field_name, "each shape must have a nonzero entry")
    return phi


def _model(model: object) -> SubstructureModel:
    """``model`` when it is a :class:`SubstructureModel`."""
    if not isinstance(model, SubstructureModel):
        raise FieldError("model", f"must be a SubstructureModel, got {type(model).__name__}")
    return model


def _indices(value: object, count: int, field_name: str) -> IntArray:
    """Indices of blocks held fixed: integers in [0, count) (none: an empty list)."""
    if isinstance(value, (str, bytes)):
        raise FieldError(field_name, f"must be indices in [0, {count}), got {value!r}")
    try:
        idx = np.asarray(value).ravel()
    except ValueError:
        raise FieldError(field_name, f"must be indices in [0, {count})") from None
    if idx.size and (idx.dtype.kind not in "iu" or idx.min() < 0 or idx.max() >= count):
        raise FieldError(field_name, f"must be integer indices in [0, {count}), got {value!r}")
    return idx.astype(int)


def _mode_indices(value: npt.ArrayLike | None, count: int, n_modes: int) -> IntArray | None:
    """``mode_indices``: ``count`` distinct model mode numbers in [0, n_modes), or None."""
    if value is None:
        return None
    idx = _indices(value, n_modes, "mode_indices")
    if idx.size != count:
        raise FieldError(
            "mode_indices", f"must give one model mode per measured mode ({count}), got {idx.size}"
        )
    if np.unique(idx).size != idx.size:
        raise FieldError("mode_indices", "each model mode at most once")
    return idx


def _scalings(
    model: SubstructureModel, values: npt.ArrayLike | None, count: int, name: str
) -> FloatArray:
    """Start scalings of stiffness or mass: ``count`` numbers > 0 (default 1), a copy."""
    v = model._params(values, count, name).copy()
    if np.any(v <= 0):
        raise FieldError(
            name, f"must be > 0 (a substructure's stiffness or mass is scaled), got {v}"
        )
    return v


def check_iterations(n_iter: int, tol: float) -> tuple[int, float]:
    """``n_iter`` (a count up to :data:`flexsat.limits.MAX_FIT_ITERATIONS`) and ``tol`` (>= 0)
    of an iterated fit, checked."""
    count = require_count(n_iter, "n_iter")
    limits.check_count(
        count,
        limits.MAX_FIT_ITERATIONS,
        "n_iter",
        "passes asked",
        "a fit that has not converged by then will not (fix parameters or add data)",
    )
    step = require_scalar(tol, "tol")
    if step < 0:
        raise FieldError("tol", f"must be >= 0, got {tol!r}")
    return count, step


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
        stiffness = _block_list(self.K_blocks, "K_blocks")
        if not stiffness and self.K0 is None:
            raise FieldError("K_blocks", "give at least one stiffness block (or K0)")
        first = _dense(stiffness[0], "K_blocks[0]") if stiffness else _dense(self.K0, "K0")
        n = first.shape[0]
        object.__setattr__(self, "K_blocks", _blocks(stiffness, "K_blocks", n))
        object.__setattr__(self, "M_blocks", _blocks(self.M_blocks, "M_blocks", n))
        object.__setattr__(self, "C_blocks", _blocks(self.C_blocks, "C_blocks", n))
        if not self.M_blocks and self.M0 is None:
            raise FieldError("M_blocks", "give at least one mass block (or M0)")
        for name in ("K0", "M0", "C0"):
            value = getattr(self, name)
            object.__setattr__(
                self, name, np.zeros((n, n)) if value is None else _dense(value, name, n)
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

    def _params(self, values: npt.ArrayLike | None, count: int, name: str) -> FloatArray:
        if values is None:
            return np.ones(count)
        v = require_numeric(values, name, "vector").ravel()
        if v.shape != (count,):
            raise FieldError(name, f"must have {count} entries (one per block), got {v.size}")
        return v

    def K(self, p: npt.ArrayLike | None = None) -> FloatArray:
        scale = self._params(p, self.n_stiffness, "p")
        return _combination(_fixed(self.K0), scale, self.K_blocks)

    def M(self, q: npt.ArrayLike | None = None) -> FloatArray:
        scale = self._params(q, self.n_mass, "q")
        return _combination(_fixed(self.M0), scale, self.M_blocks)

    def C(self, r: npt.ArrayLike | None = None) -> FloatArray:
        scale = self._params(r, self.n_damping, "r")
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
        ps = self._params(p, self.n_stiffness, "p")
        qs = self._params(q, self.n_mass, "q")
        rs = self._params(r, self.n_damping, "r")
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
        K = _dense(built.K, "build().K")
        return K, _dense(built.M, "build().M", K.shape[0])

    K1, M1 = assembly(one_k, one_m)
    n = K1.shape[0]
    limits.check_memory(
        8 * (n_stiffness + n_mass + 2) * n * n, "n_stiffness", "the substructure blocks"
    )
    Kb, Mb = [], []
    for k in range(n_stiffness):
        f = one_k.copy()
        f[k] = 2.0
        Kb.append(_dense(assembly(f, one_m)[0], "build().K", n) - K1)
    for k in range(n_mass):
        f = one_m.copy()
        f[k] = 2.0
        Mb.append(_dense(assembly(one_k, f)[1], "build().M", n) - M1)
    K0 = K1 - sum(Kb, np.zeros_like(K1))
    M0 = M1 - sum(Mb, np.zeros_like(M1))
    scale_k, scale_m = np.abs(K1).max(), np.abs(M1).max()
    K0[np.abs(K0) < 1e-12 * scale_k] = 0.0
    M0[np.abs(M0) < 1e-12 * scale_m] = 0.0
    Cb = _blocks(C_blocks, "C_blocks", n)
    return SubstructureModel(Kb, Mb, Cb, K0, M0, names=tuple(names))


# ------------------------------------------------------------------------------------------------
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
    Kb = _blocks(K_blocks, "K_blocks")
    if not Kb:
        raise FieldError("K_blocks", "give at least one stiffness block")
    n = Kb[0].shape[0]
    Mb = _blocks(M_blocks, "M_blocks", n)
    if not Mb:
        raise FieldError("M_blocks", "give at least one mass block")
    phi = _shape_matrix(shapes, "shapes", n)
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


# ------------------------------------------------------------------------------------------------
def _check_frf(frf: FrfElement | Sequence[FrfElement] | None, n: int) -> list[FrfItem]:
    """Normalise FRF input to a list of (j, k, omegas, values)."""
    if frf is None:
        return []
    entries: Any = frf  # user data, checked item by item
    if isinstance(entries, tuple) and len(entries) == 4 and np.ndim(entries[2]) == 1:
        entries = [entries]
    if not isinstance(entries, Sequence) or isinstance(entries, (str, bytes)):
        raise FieldError(
            "frf", f"must be (output_dof, input_dof, omegas, values) or a list of them, got {frf!r}"
        )
    out = []
    for i, item in enumerate(entries):
        try:
            j, k, w, h = item
        except (TypeError, ValueError):
            raise FieldError(
                f"frf[{i}]", "must be (output_dof, input_dof, omegas, values)"
            ) from None
        for name, d in (("output_dof", j), ("input_dof", k)):
            if isinstance(d, bool) or not isinstance(d, (int, np.integer)) or not 0 <= d < n:
                raise FieldError(f"frf[{i}].{name}", f"must be a dof index in [0, {n}), got {d!r}")
        w = require_finite(w, f"frf[{i}].omegas", "rad/s").ravel()
        h = require_numeric(h, f"frf[{i}].values", "vector").ravel()
        if w.shape != h.shape or w.size == 0:
            raise FieldError(
                f"frf[{i}]", "omegas and values must be equal-length non-empty vectors"
            )
        if np.any(w <= 0):
            raise FieldError(f"frf[{i}].omegas", "must be > 0 rad/s")
        out.append((int(j), int(k), w, h))
    return out


def fit_modal_normalization(
    frf: FrfElement | Sequence[FrfElement],
    shapes: npt.ArrayLike,
    omegas: npt.ArrayLike,
    rigid_body: bool = False,
    residual: bool = True,
    known_part: Sequence[FloatArray] | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Linear least-squares fit of the modal normalisation factors (Att. 7 Eqs. 5–6).

    ``h_jk(w) ~= a1/w^2 + sum_r alpha_r psi_jr psi_kr / (w_r^2 - w^2) + a2`` (real FRF
    receptance, undamped or taken away from resonances), stacked over the FRF elements; each
    point weighted by ``1/|h|`` (relative errors: the FRF spans decades).

    Parameters
    ----------
    frf : (j, k, omegas, values) or a list of them
    shapes : (n, m) unscaled shapes ``psibar``; omegas : (m,) measured frequencies, rad/s.
    rigid_body : fit the ``a1/w^2`` term of a free structure.  residual : fit ``a2``.
    known_part : optional list (one per FRF element) of arrays subtracted from the values first
        (the current model's prediction of the unmeasured modes).

    Returns
    -------
    alpha : (m,), a1 (per FRF element), a2 (per FRF element).
    """
    psi = _shape_matrix(shapes, "shapes")
    w_r = require_finite(omegas, "omegas", "rad/s")
    if w_r.shape != (psi.shape[1],) or np.any(w_r <= 0):
        raise FieldError(
            "omegas", f"must be {psi.shape[1]} values > 0 rad/s (one per shape), got {omegas!r}"
        )
    items = _check_frf(frf, psi.shape[0])
    if not items:
        raise FieldError("frf", "at least one FRF element is needed")
    if known_part is not None:
        if not isinstance(known_part, Sequence) or len(known_part) != len(items):
            raise FieldError("known_part", f"must be a list of {len(items)} arrays (one per FRF)")
        known_part = [
            require_numeric(part, f"known_part[{i}]", "vector") for i, part in enumerate(known_part)
        ]
        for i, (part, (*_, h)) in enumerate(zip(known_part, items)):
            if part.shape != h.shape:
                raise FieldError(
                    f"known_part[{i}]", f"must have {h.size} values (one per FRF point)"
                )
    m, nf = psi.shape[1], len(items)
    n_extra = (int(rigid_body) + int(residual)) * nf
    rows, rhs = [], []
    for i, (j, k, w, h) in enumerate(items):
        h_meas = h
        if known_part is not None:
            h = h - known_part[i]
        denom = w_r[None, :] ** 2 - w[:, None] ** 2
        if np.any(np.abs(denom) < 1e-9 * w_r.max() ** 2):
            raise FieldError(f"frf[{i}].omegas", "a point coincides with a natural frequency")
        L = psi[j] * psi[k] / denom
        extra = np.zeros((w.size, n_extra))
        col = 0
        if rigid_body:
            extra[:, i] = 1.0 / w**2
            col = nf
        if residual:
            extra[:, col + i] = 1.0
        # relative weighting (noise SD proportional to |h|, Att. 7 Example 2)
        wgt = 1.0 / np.maximum(np.abs(h_meas), 1e-12 * np.abs(h_meas).max())
        rows.append(np.hstack([L, extra]) * wgt[:, None])
        rhs.append(h * wgt)
    A, b = np.vstack(rows), np.concatenate(rhs)
    if A.shape[0] < A.shape[1]:
        raise FieldError(
            "frf",
            f"{A.shape[0]} FRF points for {A.shape[1]} unknowns "
            "(normalisation factors and rigid/residual terms): need more points",
        )
    scale = np.abs(A).max(axis=0)
    scale[scale == 0] = 1.0
    x = np.linalg.lstsq(A / scale, b, rcond=None)[0] / scale
    alpha = x[:m]
    if np.any(alpha <= 0):
        raise FieldError(
            "frf",
            "fitted modal normalisation factors must be > 0 (FRF does not "
            f"observe a measured mode, or shapes inconsistent): {alpha}",
        )
    a1 = x[m : m + nf] if rigid_body else np.zeros(nf)
    a2 = x[m + (nf if rigid_body else 0) :] if residual else np.zeros(nf)
    return alpha, a1, a2


def _model_frf(
    K: FloatArray,
    M: FloatArray,
    items: Sequence[FrfItem],
    K_blocks: Sequence[FloatArray] = (),
    M_blocks: Sequence[FloatArray] = (),
) -> list[FrfRows]:
    """Receptance elements of a model at the FRF points (direct solve), with gradients.

    ``h = e_j^T Z^-1 e_k`` with ``Z = K - w^2 M``; ``dh/dp_g = -u^T K_g v`` and ``dh/dq_g = w^2
    u^T M_g v`` with ``u = Z^-1 e_j``, ``v = Z^-1 e_k`` (``dZ^-1 = -Z^-1 dZ Z^-1``).  Returns a
    list of (values (N,), dh/dp (N, len(K_blocks)), dh/dq (N, len(M_blocks))).
    """
    out = []
    for j, k, w, _ in items:
        h = np.empty(w.size)
        hp, hq = np.empty((w.size, len(K_blocks))), np.empty((w.size, len(M_blocks)))
        for i, wi in enumerate(w):
            E = np.zeros((K.shape[0], 2))
            E[j, 0] = E[k, 1] = 1.0
            u, v = np.linalg.solve(K - wi**2 * M, E).T
            h[i] = u[k]
            hp[i] = [-(u @ Kg @ v) for Kg in K_blocks]
            hq[i] = [wi**2 * (u @ Mg @ v) for Mg in M_blocks]
        out.append((h, hp, hq))
    return out


# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class UndampedIdentification:
    """Result of :func:`identify_undamped`.

    Attributes
    ----------
    p, q : identified stiffness and mass scalings.
    covariance : ((P+Q), (P+Q)) covariance of ``(p, q)`` (zeros for held parameters).
    frequencies : (m,) model frequencies of the measured modes after identification, rad/s.
    alpha : (m,) modal normalisation factors of the last pass.
    iterations : passes made; history : list of (p, q) per pass; converged : bool.
    """

    p: FloatArray
    q: FloatArray
    covariance: FloatArray
    frequencies: FloatArray
    alpha: FloatArray
    iterations: int
    converged: bool
    history: list[tuple[FloatArray, FloatArray]]


def _solve_ls(
    A: FloatArray, b: FloatArray, weights: FloatArray, name: str
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    if A.shape[0] < A.shape[1]:
        raise FieldError(
            name,
            f"{A.shape[0]} equations for {A.shape[1]} parameters: more "
            "parameters than data (measure more modes, add FRFs, or fix parameters)",
        )
    Aw, bw = A * weights[:, None], b * weights
    scale = np.linalg.norm(Aw, axis=0)
    if np.any(scale == 0):
        bad = np.nonzero(scale == 0)[0].tolist()
        raise FieldError(
            name,
            f"parameters {bad} do not affect the measured modes (no modal "
            "energy; see modal_energy_distribution): fix them",
        )
    As = Aw / scale
    s = np.linalg.svd(As, compute_uv=False)
    if s[-1] < 1e-10 * s[0]:
        raise FieldError(
            name,
            "parameters not identifiable from the data (condition number "
            f"{s[0] / max(s[-1], 1e-300):.3g}); fix some or add data",
        )
    x = np.linalg.lstsq(As, bw, rcond=None)[0]
    res = bw - As @ x
    dof = A.shape[0] - A.shape[1]
    cov_s = np.linalg.inv(As.T @ As)
    return x / scale, cov_s / np.outer(scale, scale), res, dof


def _pair_modes(
    omega_model: FloatArray,
    phi_model: FloatArray,
    measured_w: FloatArray,
    measured_shapes: FloatArray | None,
    mode_indices: npt.ArrayLike | None,
) -> IntArray:
    if mode_indices is not None:
        return np.asarray(mode_indices, int)
    if measured_shapes is None:
        return np.arange(measured_w.size)
    # match each measured shape to the model mode of largest MAC
    num = (measured_shapes.T @ phi_model) ** 2
    den = np.outer(np.sum(measured_shapes**2, 0), np.sum(phi_model**2, 0))
    idx = np.argmax(num / den, axis=1)
    if len(set(idx.tolist())) != idx.size:
        return np.arange(measured_w.size)
    return idx


def _eq5(
    model: SubstructureModel,
    p: FloatArray,
    q: FloatArray,
    wbar: FloatArray,
    items: Sequence[FrfItem],
    idx: IntArray,
    psi_meas: FloatArray | None,
    free_p: IntArray,
    free_q: IntArray,
) -> list[FrfRows]:
    """Right side of Eq. 5 for the current model, with its gradients.

    ``known + sum_r psibar_jr psibar_kr / (mu_r (wbar_r^2 - w^2))`` where ``known = h_model -
    sum_r phi_jr phi_kr / (lambda_r - w^2)`` is the current model's prediction of the unmeasured
    modes (the iteration of Att. 7 "Identification of Undamped Structures"),
    ``mu_r = psibar_r^T M(q) psibar_r = 1/alpha_r`` (Eq. 7a,
    i = j) and ``psibar`` the measured shapes (fixed) or the model's ``phi`` (``mu = 1``).
    The gradient with respect to the free ``(p, q)`` is exact: model FRF gradient (see
    :func:`_model_frf`) and the measured modes' ``d lambda``, ``d phi`` by Nelson's method.

    Returns, per FRF element: value (N,), gradient (N, Pf + Qf), d value / d wbar (N, m).
    """
    K, M = model.K(p), model.M(q)
    n = model.n_dofs
    Kb = [model.K_blocks[g] for g in free_p]
    Mb = [model.M_blocks[g] for g in free_q]
    zeros = [np.zeros((n, n))]
    md = modal_derivatives(
        K, M, np.array(Kb + zeros * len(Mb)), np.array(zeros * len(Kb) + Mb), modes=idx
    )
    lam, phi, dlam, dphi = md.eigenvalues, md.modes, md.eigenvalue_gradient, md.mode_gradient
    psi = phi if psi_meas is None else psi_meas
    mu = np.einsum("ij,ik,kj->j", psi, M, psi)
    E = np.array([np.einsum("ij,ik,kj->j", psi, Mg, psi) for Mg in Mb]).T
    out = []
    for i, ((j, k, w, _), (hm, hp, hq)) in enumerate(zip(items, _model_frf(K, M, items, Kb, Mb))):
        d_meas = wbar[None, :] ** 2 - w[:, None] ** 2
        if np.any(np.abs(d_meas) < 1e-9 * wbar.max() ** 2):
            raise FieldError(f"frf[{i}].omegas", "a point coincides with a natural frequency")
        d_model = lam[None, :] - w[:, None] ** 2
        pp = phi[j] * phi[k]
        dpp = dphi[:, j, :] * phi[k] + phi[j] * dphi[:, k, :]
        grad = np.hstack([hp, hq]) - (1.0 / d_model) @ dpp.T + (pp / d_model**2) @ dlam.T
        qq = psi[j] * psi[k] / mu
        value = hm - (pp / d_model).sum(axis=1) + (qq / d_meas).sum(axis=1)
        if psi_meas is None:
            grad += (1.0 / d_meas) @ dpp.T
        else:
            grad[:, len(Kb) :] -= (qq / mu / d_meas) @ E
        out.append((value, grad, -qq * 2.0 * wbar[None, :] / d_meas**2))
    return out


def _mass_step(
    model: SubstructureModel,
    psi: FloatArray,
    items: Sequence[FrfItem],
    rows_eq5: Sequence[FrfRows],
    q: FloatArray,
    free_q: IntArray,
    q_prior: FloatArray,
    prior_sd: float | None,
    frf_sd: float,
    pairs_off: Sequence[tuple[int, int]],
    rigid_body: bool,
    residual: bool,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, int]:
    """One Gauss-Newton step of the joint Eq. 5-6 / 9a fit of the mass scalings.

    ``rows_eq5`` holds per FRF element the residual of Eq. 5 (see :func:`_eq5`), its gradient
    with respect to the free mass scalings and that of the residual with respect to ``wbar``;
    the FRF rows are fitted together with ``a1, a2`` (Eq. 6), the Eq. 9a rows ``i != j``
    (``pairs_off``) and the prior rows.  Returns the step on ``free_q``; its gains with respect
    to the data (frequencies, FRF values, prior values); the relative FRF residuals and their
    degrees of freedom.
    """
    Mq = model.M(q)
    mu = np.einsum("ij,ik,kj->j", psi, Mq, psi)
    nf, Qf = len(items), free_q.size
    n_extra = (int(rigid_body) + int(residual)) * nf
    rows, rhs, sd_rows, r_wbar = [], [], [], []
    for i, ((_, _, w, h), (r, J, dr_dw)) in enumerate(zip(items, rows_eq5)):
        extra = np.zeros((w.size, n_extra))
        if rigid_body:
            extra[:, i] = 1.0 / w**2
        if residual:
            extra[:, (nf if rigid_body else 0) + i] = 1.0
        rows.append(np.hstack([J, extra]))
        rhs.append(r)
        sd_rows.append(frf_sd * np.maximum(np.abs(h), 1e-12 * np.abs(h).max()))
        r_wbar.append(dr_dw)
    n_frf = sum(r.size for r in rhs)
    if pairs_off:
        # Eq. 9a, i != j, in the normalised form psi_i^T M psi_j sqrt(alpha_i alpha_j) = 0,
        # counted like a relative FRF error (as Eq. 9b's rows count like relative w^2 errors)
        s = np.array([1.0 / np.sqrt(mu[i] * mu[j]) for i, j in pairs_off])
        A_off = (
            np.array(
                [[psi[:, i] @ model.M_blocks[g] @ psi[:, j] for g in free_q] for i, j in pairs_off]
            )
            * s[:, None]
        )
        rows.append(np.hstack([A_off, np.zeros((len(pairs_off), n_extra))]))
        rhs.append(-np.array([psi[:, i] @ Mq @ psi[:, j] for i, j in pairs_off]) * s)
        sd_rows.append(np.full(len(pairs_off), frf_sd))
    if prior_sd is not None:
        # Tikhonov rows: the a-priori scalings as pseudo-measurements (Att. 6 Eq. 12, 0_p)
        rows.append(np.hstack([np.eye(Qf), np.zeros((Qf, n_extra))]))
        rhs.append(q_prior[free_q] - q[free_q])
        sd_rows.append(np.full(Qf, prior_sd))
    A, b, sd = np.vstack(rows), np.concatenate(rhs), np.concatenate(sd_rows)
    x, cov, res, _ = _solve_ls(A, b, 1.0 / sd, "mass scalings")
    gain = (cov @ (A.T / sd**2))[:Qf]  # d(step)/d(right side)
    g_w = gain[:, :n_frf] @ np.vstack(r_wbar)
    g_prior = gain[:, A.shape[0] - Qf :] if prior_sd is not None else np.zeros((Qf, 0))
    return (
        x[:Qf],
        g_w,
        gain[:, :n_frf],
        g_prior,
        res[:n_frf] * frf_sd,
        max(n_frf - Qf - n_extra, 0),
    )


def identify_undamped(
    model: SubstructureModel,
    measured_frequencies: npt.ArrayLike,
    measured_shapes: npt.ArrayLike | None = None,
    frf: FrfElement | Sequence[FrfElement] | None = None,
    p0: npt.ArrayLike | None = None,
    q0: npt.ArrayLike | None = None,
    fixed_stiffness: npt.ArrayLike = (),
    fixed_mass: npt.ArrayLike = (),
    frequency_sigma: float | npt.ArrayLike | None = None,
    frf_sigma: float | None = None,
    mass_prior_sigma: float | None = None,
    mode_indices: npt.ArrayLike | None = None,
    off_diagonal: bool | None = None,
    rigid_body: bool = False,
    residual: bool = False,
    n_iter: int = 30,
    tol: float = 1e-10,
    identify_mass: bool | None = None,
) -> UndampedIdentification:
    """Iterated least-squares identification of the stiffness and mass scalings (Eqs. 1–9).

    What identifies what: frequencies and shapes fix only the stiffness-to-mass ratio, since
    ``(K, M) -> c (K, M)`` leaves them unchanged; the FRF fixes the absolute scale through the
    modal normalisation ``alpha_r`` (Eqs. 4–5).  Each pass, with ``psibar`` the measured shapes
    or the current model's modes:

    1. Mass scalings (Eqs. 5–6 and 9a jointly): one Gauss-Newton step of the FRF fit with
       ``alpha_r(q) = 1 / psibar_r^T M(q) psibar_r`` (Eq. 7a, i = j, put into Eq. 5), together
       with ``a1, a2`` and, with measured shapes, the Eq. 9a rows ``i != j``.  A mode counts
       with its actual share of the FRF; ``alpha`` of a weakly participating mode is never
       estimated on its own (the separate Eq. 6 fit, :func:`fit_modal_normalization`, can give
       such a mode a wildly wrong or negative ``alpha``, and Eq. 9a then diverges).  With
       model-predicted shapes the step also differentiates what a mass change does to the shapes
       and to the unmeasured modes, along the path on which Eq. 9b re-fits the stiffness to the
       measured frequencies (``dp/dq`` from the linearised Eq. 9b; the FRF gradient
       ``dh/dx = -u^T (dZ/dx) v``).  Without that term the iteration is unstable for a mass
       group the FRF sees mainly through the mode shapes (the Example 1 tip inertia: it
       diverged even from 0.01 % off the true model).
    2. Stiffness scalings (Eq. 9b) with ``alpha_r = alpha_r(q)`` of the new mass, i.e.
       ``psibar_i^T K(p) psibar_i = wbar_i^2 psibar_i^T M(q) psibar_i``.

    Without an FRF the mass scalings are held (the mass is the known scale).  With
    ``mass_prior_sigma`` the start mass scalings enter as pseudo-measurements (Tikhonov
    regularisation, Att. 6 Eq. 12 ``0_p``) for mass groups the FRF observes weakly.

    Parameters
    ----------
    model : SubstructureModel
    measured_frequencies : (m,) rad/s, > 0, of the lowest modes (or of ``mode_indices``).
    measured_shapes : (n, m), optional
        Measured shapes on all dofs (any scale).  Default: the current model's modes, refreshed
        every pass (Att. 7 Examples 1–2).
    frf : (j, k, omegas, values) or list, optional
        Measured receptance elements (real, away from resonance).  Needed to identify the mass
        scalings; without it they are held.
    p0, q0 : start scalings (default 1).  fixed_stiffness, fixed_mass : indices held at start.
    frequency_sigma : (m,) or scalar, optional
        Standard deviation of the measured frequencies, rad/s.
    frf_sigma : float, optional
        Relative standard deviation of the FRF values (e.g. 0.005 for 0.5 %).
    mass_prior_sigma : float, optional
        Standard deviation of the mass scalings about ``q0``; needs ``frf_sigma`` (the prior is
        weighted against it).
    mode_indices : model mode numbers (0-based) of the measured modes; default by order (or by
        MAC with measured shapes).
    off_diagonal : use the i != j rows of Eq. 9 (default: only with measured shapes).
    rigid_body, residual : FRF fit terms ``a1/w^2`` and ``a2`` (Eq. 5); ``a2`` is off by
        default (see the module notes).
    identify_mass : default: True when an FRF is given.

    Returns
    -------
    UndampedIdentification
        ``covariance`` propagates the frequency, FRF and prior standard deviations linearly
        through the last pass (shapes counted exact); a standard deviation not given is
        estimated from the residual scatter (zero covariance for an exact fit).
    """
    model = _model(model)
    P, Q, n = model.n_stiffness, model.n_mass, model.n_dofs
    wbar = require_finite(measured_frequencies, "measured_frequencies", "rad/s")
    if wbar.ndim > 1 or wbar.size == 0 or np.any(wbar <= 0):
        raise FieldError("measured_frequencies", "must be a non-empty vector of values > 0 rad/s")
    wbar = wbar.ravel()
    m = wbar.size
    if m > n:
        raise FieldError("measured_frequencies", f"{m} modes but the model has {n} dofs")
    n_iter, tol = check_iterations(n_iter, tol)
    mode_indices = _mode_indices(mode_indices, m, n)
    psi_meas = None
    if measured_shapes is not None:
        psi_meas = _shape_matrix(measured_shapes, "measured_shapes")
        if psi_meas.shape != (n, m):
            raise FieldError("measured_shapes", f"must have shape ({n}, {m}), got {psi_meas.shape}")
    items = _check_frf(frf, n)
    identify_mass = bool(items) if identify_mass is None else bool(identify_mass)
    if identify_mass and not items:
        raise FieldError(
            "identify_mass",
            "the mass scalings need an FRF (the absolute scale; "
            "frequencies and shapes are unchanged by scaling K and M together)",
        )
    if off_diagonal is None:
        off_diagonal = psi_meas is not None
    p = _scalings(model, p0, P, "p0")
    q = _scalings(model, q0, Q, "q0")
    q_prior = q.copy()
    free_p = np.setdiff1d(np.arange(P), _indices(fixed_stiffness, P, "fixed_stiffness"))
    held_q = _indices(fixed_mass, Q, "fixed_mass")
    free_q = np.setdiff1d(np.arange(Q), held_q) if identify_mass else np.array([], int)
    if free_p.size == 0 and free_q.size == 0:
        raise FieldError(
            "fixed_stiffness",
            "every parameter is fixed (with fixed_mass, or the mass held without an FRF)",
        )
    sig_w = None
    if frequency_sigma is not None:
        sig = require_finite(frequency_sigma, "frequency_sigma", "rad/s")
        if sig.ndim > 1 or (sig.ndim == 1 and sig.size != m):
            raise FieldError(
                "frequency_sigma", f"must be a scalar or {m} values (one per mode), got {sig.shape}"
            )
        sig_w = np.broadcast_to(sig, (m,)).astype(float)
        if np.any(sig_w <= 0):
            raise FieldError("frequency_sigma", "must be > 0")
    for name, value in (("frf_sigma", frf_sigma), ("mass_prior_sigma", mass_prior_sigma)):
        if value is not None and (np.ndim(value) != 0 or float(require_numeric(value, name)) <= 0):
            raise FieldError(name, "must be a scalar > 0")
    if mass_prior_sigma is not None and frf_sigma is None:
        raise FieldError(
            "mass_prior_sigma",
            "needs frf_sigma (the prior is weighted against the FRF's standard deviation)",
        )
    pairs = [(i, i) for i in range(m)]
    pairs_off = [(i, j) for i in range(m) for j in range(i + 1, m)] if off_diagonal else []
    pairs += pairs_off
    n_rows = len(pairs)
    limits = [("stiffness", free_p.size)]
    if mass_prior_sigma is None:
        limits.append(("mass", free_q.size))
    for name, count in limits:
        if count > n_rows:
            raise FieldError(
                "measured_frequencies",
                f"{n_rows} equations for {count} {name} parameters: "
                "more parameters than data (Att. 7 needs m(m+1)/2 > parameters with measured "
                "shapes, m >= parameters without): measure more modes or fix parameters",
            )
    ii = np.array([i for i, _ in pairs])
    jj = np.array([j for _, j in pairs])
    rel = np.ones(m) if sig_w is None else 2.0 * sig_w / wbar
    frf_sd = 1.0 if frf_sigma is None else float(frf_sigma)

    history, converged = [(p.copy(), q.copy())], False
    for it in range(1, n_iter + 1):  # noqa: B007 - the last count is reported
        K = model.K(p)
        w_model, phi_model = model.modes(p, q)
        idx = _pair_modes(w_model, phi_model, wbar, psi_meas, mode_indices)
        psi = psi_meas if psi_meas is not None else phi_model[:, idx]
        mu = np.einsum("ij,ik,kj->j", psi, model.M(q), psi)
        # --- Eq. 9b system: rows, weights and the gain d(p)/d(right side) -----------------
        # row weights: relative residuals (a low mode counts as much as a high one); with
        # frequency_sigma, 1/SD of the right side (row i=i: wbar^2/alpha, SD 2 wbar sigma/alpha)
        weights_k = (
            np.sqrt(1.0 / (mu[ii] * mu[jj])) / (wbar[ii] * wbar[jj]) / np.sqrt(rel[ii] * rel[jj])
        )
        A_k = np.array(
            [[psi[:, i] @ model.K_blocks[g] @ psi[:, j] for g in free_p] for i, j in pairs]
        ).reshape(n_rows, free_p.size)
        Kfix = K - sum((p[g] * model.K_blocks[g] for g in free_p), np.zeros((n, n)))
        kfix = np.array([psi[:, i] @ Kfix @ psi[:, j] for i, j in pairs])
        gain_k = np.zeros((free_p.size, n_rows))
        if free_p.size:
            # (A^T W A)^-1 and the identifiability checks now; the right side needs the new q
            _, c_k, _, dof_k = _solve_ls(A_k, -kfix, weights_k, "stiffness scalings")
            gain_k = c_k @ (A_k.T * weights_k**2)
        db_dw = np.zeros((n_rows, m))  # right side of Eq. 9b: wbar_i^2 mu_i(q) - ...
        db_dw[np.arange(m), np.arange(m)] = 2.0 * wbar * mu
        E = np.array(
            [np.einsum("ij,ik,kj->j", psi, model.M_blocks[g], psi) for g in free_q]
        ).T.reshape(m, free_q.size)
        db_dq = np.zeros((n_rows, free_q.size))
        db_dq[:m] = wbar[:, None] ** 2 * E
        # --- Eqs. 5-6 and 9a jointly: mass scalings ------------------------------------------
        q_new = q.copy()
        if free_q.size:
            # gradients along the path on which Eq. 9b keeps the measured frequencies:
            # dp = D dq with D = d(p)/d(q) of the linearised Eq. 9b
            D, G_w = gain_k @ db_dq, gain_k @ db_dw
            rows_eq5 = [
                (
                    h - value,
                    grad[:, : free_p.size] @ D + grad[:, free_p.size :],
                    -d_wbar - grad[:, : free_p.size] @ G_w,
                )
                for (*_, h), (value, grad, d_wbar) in zip(
                    items, _eq5(model, p, q, wbar, items, idx, psi_meas, free_p, free_q)
                )
            ]
            dq, g_qw, g_qh, g_qprior, rel_frf, dof_frf = _mass_step(
                model,
                psi,
                items,
                rows_eq5,
                q,
                free_q,
                q_prior,
                mass_prior_sigma,
                frf_sd,
                pairs_off,
                rigid_body,
                residual,
            )
            q_new[free_q] += dq
        # --- Eq. 9b: stiffness scalings, alpha_i = 1 / psibar_i^T M(q_new) psibar_i ---------
        p_new = p.copy()
        if free_p.size:
            b = -kfix + db_dq @ (q_new - q)[free_q] if free_q.size else -kfix.copy()
            b[:m] += wbar**2 * mu
            p_new[free_p] = gain_k @ b
            res_k = (b - A_k @ p_new[free_p]) * weights_k
        # scalings must stay positive (K, M definite): shorten a step that leaves them
        dp, dq_all, t = p_new - p, q_new - q, 1.0
        while t > 1e-6 and (np.any(p + t * dp <= 0) or np.any(q + t * dq_all <= 0)):
            t *= 0.5
        if t <= 1e-6:
            raise ValueError(
                "identification diverged: the least-squares step makes a scaling "
                f"non-positive (p={p_new}, q={q_new}); fix weakly observed "
                "parameters (see modal_energy_distribution)"
            )
        p_new, q_new = p + t * dp, q + t * dq_all
        step = max(np.abs(p_new - p).max(), np.abs(q_new - q).max() if Q else 0.0)
        p, q = p_new, q_new
        history.append((p.copy(), q.copy()))
        if step < tol:
            converged = True
            break

    # --- covariance: the last pass's estimates as linear functions of the data -------------
    # data d = (wbar, FRF values, prior values); S = d(p, q)/d(d); cov = S diag(sd_d^2) S^T
    n_h = sum(h.size for *_, h in items) if free_q.size else 0
    n_pr = free_q.size if mass_prior_sigma is not None else 0
    S = np.zeros((P + Q, m + n_h + n_pr))
    sd = np.zeros(m + n_h + n_pr)
    if free_q.size:
        S[np.ix_(P + free_q, np.arange(m))] = g_qw
        S[np.ix_(P + free_q, m + np.arange(n_h))] = g_qh
        if n_pr:
            S[np.ix_(P + free_q, m + n_h + np.arange(n_pr))] = g_qprior
            sd[m + n_h :] = mass_prior_sigma
        s_h = (
            frf_sigma
            if frf_sigma is not None
            else (np.sqrt(rel_frf @ rel_frf / dof_frf) if dof_frf > 0 else 0.0)
        )
        sd[m : m + n_h] = s_h * np.concatenate([np.abs(h) for *_, h in items])
    if free_p.size:
        # Eq. 9b's right side depends on wbar directly and through the new q
        S[np.ix_(free_p, np.arange(m))] = gain_k @ db_dw
        if free_q.size:
            S[free_p] += gain_k @ db_dq @ S[P + free_q]
        if sig_w is not None:
            sd[:m] = sig_w
        elif dof_k > 0:
            # weighted rows are relative eigenvalue errors: SD(w)/w = SD(w^2) / (2 w^2)
            sd[:m] = 0.5 * wbar * np.sqrt(res_k @ res_k / dof_k)
    cov = (S * sd**2) @ S.T
    w_final, phi_final = model.modes(p, q)
    idx = _pair_modes(w_final, phi_final, wbar, psi_meas, mode_indices)
    return UndampedIdentification(p, q, cov, w_final[idx], 1.0 / mu, it, converged, history)


# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DampingIdentification:
    """Result of :func:`identify_damping`.

    Attributes
    ----------
    r : (R,) damping scalings; covariance : (R, R).
    predicted_real_parts : (m,) first-order ``-(1/2) phi^T C(r) phi`` of the measured modes.
    eigenvalues : (m,) complex eigenvalues of the identified damped model (exact state-space
        solve, for checking the first-order theory).
    mode_indices : (m,) model mode paired with each measured eigenvalue.
    """

    r: FloatArray
    covariance: FloatArray
    predicted_real_parts: FloatArray
    eigenvalues: ComplexArray
    mode_indices: IntArray


def damped_eigenvalues(K: Matrix, M: Matrix, C: Matrix, n_modes: int | None = None) -> ComplexArray:
    """Eigenvalues of ``M x'' + C x' + K x = 0`` with positive imaginary part, by frequency."""
    Kd = require_numeric(_array_like(K), "K", "matrix")
    if Kd.ndim != 2 or Kd.shape[0] != Kd.shape[1] or Kd.size == 0:
        raise FieldError("K", f"must be a non-empty square matrix, got shape {Kd.shape}")
    n = Kd.shape[0]
    Md, Cd = (require_numeric(_array_like(A), name, "matrix") for A, name in ((M, "M"), (C, "C")))
    for A, name in ((Md, "M"), (Cd, "C")):
        if A.shape != (n, n):
            raise FieldError(name, f"must be {n}x{n} like K, got shape {A.shape}")
    try:
        np.linalg.cholesky((Md + Md.T) / 2.0)
    except np.linalg.LinAlgError:
        raise FieldError("M", "must be positive definite (a mass on every dof)") from None
    count = None if n_modes is None else require_count(n_modes, "n_modes")
    Minv = np.linalg.inv(Md)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kd, -Minv @ Cd]])
    lam = np.linalg.eigvals(A).astype(complex)
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(lam.imag)]
    return lam if count is None else lam[:count]


def identify_damping(
    model: SubstructureModel,
    measured_eigenvalues: npt.ArrayLike,
    p: npt.ArrayLike | None = None,
    q: npt.ArrayLike | None = None,
    mode_indices: npt.ArrayLike | None = None,
    fixed: npt.ArrayLike = (),
    r0: npt.ArrayLike | None = None,
) -> DampingIdentification:
    """Damping scalings from measured eigenvalue real parts by first-order perturbation.

    Att. 7 Eq. 24: ``sum_k r_k phi_0r^T C_k phi_0r = -2 sigmabar_r - phi_0r^T C0 phi_0r`` with
    ``phi_0r`` the mass-normalised modes of the undamped model ``K(p), M(q)`` (the identified
    one).  The first-order theory predicts no frequency shift, so only the real parts are used.

    Parameters
    ----------
    model : SubstructureModel with ``C_blocks``.
    measured_eigenvalues : (m,) complex (``sigma + i w``, ``w != 0``) or real parts only
        (sigma < 0). Complex eigenvalues, in any order, are paired with the model modes by
        natural frequency ``|lambda|``: each with the nearest elastic model mode in
        ``|ln(|lambda| / w_model)|``, which must be at most half as far as the second nearest
        (else the pairing is ambiguous: an error), one eigenvalue per mode. Real parts carry
        no frequency and are paired in order with ``mode_indices``.
    p, q : undamped scalings (e.g. from :func:`identify_undamped`).
    mode_indices : model modes of the measured eigenvalues, in their order (default: matched by
        frequency, or the lowest m for real parts); refused when the frequencies clearly
        contradict it.
    fixed : damping blocks held at ``r0`` (default 1).
    """
    model = _model(model)
    R = model.n_damping
    if R == 0:
        raise FieldError("C_blocks", "the model has no damping blocks")
    lam = np.asarray(measured_eigenvalues)
    if isinstance(measured_eigenvalues, (str, bytes)) or lam.dtype.kind not in "biufc":
        raise FieldError("measured_eigenvalues", "must be a numeric (complex) vector")
    lam = lam.ravel().astype(complex)
    if lam.size == 0 or not np.all(np.isfinite(lam)):
        raise FieldError(
            "measured_eigenvalues", "must be a non-empty finite vector (no NaN or inf)"
        )
    sigma = lam.real
    if np.any(sigma >= 0):
        raise FieldError(
            "measured_eigenvalues", "real parts must be < 0 (a damped, stable structure)"
        )
    m = sigma.size
    r = model._params(r0, R, "r0").copy()
    free = np.setdiff1d(np.arange(R), _indices(fixed, R, "fixed"))
    if free.size == 0:
        raise FieldError("fixed", "every damping parameter is fixed")
    if free.size > m:
        raise FieldError(
            "measured_eigenvalues",
            f"{m} eigenvalues for {free.size} damping "
            "parameters: more parameters than data (Att. 7 needs m > R)",
        )
    w0, phi = model.modes(
        _scalings(model, p, model.n_stiffness, "p"), _scalings(model, q, model.n_mass, "q")
    )
    given = _mode_indices(mode_indices, m, phi.shape[1])
    if np.all(lam.imag == 0):  # real parts carry no frequency: paired in order
        idx = np.arange(m) if given is None else given
        if idx.max() >= phi.shape[1]:
            raise FieldError("mode_indices", "must give one model mode per measured eigenvalue")
    elif np.any(lam.imag == 0):
        raise FieldError(
            "measured_eigenvalues",
            "give every eigenvalue as sigma + i w with w != 0 "
            "(matched to the model frequencies) or every one as its real part "
            "sigma (paired in order)",
        )
    else:
        idx = _match_modes(w0, np.abs(lam), given)
    phi = phi[:, idx]
    Cfix = model.C(r) - sum((r[g] * model.C_blocks[g] for g in free), np.zeros_like(model.C0))
    A = np.array([[phi[:, i] @ model.C_blocks[g] @ phi[:, i] for g in free] for i in range(m)])
    b = np.array([-2.0 * sigma[i] - phi[:, i] @ Cfix @ phi[:, i] for i in range(m)])
    x, c, res, dof = _solve_ls(A, b, np.ones(m), "damping scalings")
    r[free] = x
    cov = np.zeros((R, R))
    cov[np.ix_(free, free)] = c * ((res @ res / dof) if dof > 0 else 0.0)
    C = model.C(r)
    predicted = -0.5 * np.einsum("ij,ik,kj->j", phi, C, phi)
    eig = damped_eigenvalues(model.K(p), model.M(q), C)
    # pair exact eigenvalues with the undamped modes by frequency
    eig = eig[[int(np.argmin(np.abs(eig.imag - w0[i]))) for i in idx]]
    return DampingIdentification(r, cov, predicted, eig, idx)


def _match_modes(
    w_model: FloatArray, w_meas: FloatArray, mode_indices: IntArray | None = None
) -> IntArray:
    """Model mode of each measured natural frequency ``|lambda|`` (rad/s).

    Distances are ``|ln(w_meas / w_model)|`` (relative: spectra span decades) to the elastic
    model modes. A measured frequency is matched when its nearest model mode is at most half as
    far as the second nearest; otherwise it lies near the middle between two model modes and
    the pairing is ambiguous (the model may lack the measured mode). Each model mode takes at
    most one measured eigenvalue. Given ``mode_indices`` are used as the pairing, refused only
    where a clear match contradicts them (eigenvalues listed in another order).
    """
    elastic = np.flatnonzero(w_model > 0)
    if elastic.size == 0:
        raise FieldError("measured_eigenvalues", "the model has no elastic mode to match them to")
    d = np.abs(np.log(w_meas[:, None] / w_model[None, elastic]))
    order = np.argsort(d, axis=1)
    near = elastic[order[:, 0]]
    rows = np.arange(w_meas.size)
    d1 = d[rows, order[:, 0]]
    d2 = d[rows, order[:, 1]] if elastic.size > 1 else np.full(w_meas.size, np.inf)
    clear = d1 <= 0.5 * d2
    if mode_indices is not None:
        wrong = np.flatnonzero(clear & (near != mode_indices))
        if wrong.size:
            i = wrong[0]
            raise FieldError(
                "mode_indices",
                f"measured_eigenvalues[{i}] (natural frequency {w_meas[i]:.6g} "
                f"rad/s) is nearest model mode {near[i]} ({w_model[near[i]]:.6g} rad/s) but "
                f"mode_indices pairs it with mode {mode_indices[i]} "
                f"({w_model[mode_indices[i]]:.6g} rad/s): list the eigenvalues in the order of "
                "mode_indices",
            )
        return np.asarray(mode_indices, int)
    unclear = np.flatnonzero(~clear)
    if unclear.size:
        i = unclear[0]
        a, b = sorted(elastic[order[i, :2]])
        raise FieldError(
            f"measured_eigenvalues[{i}]",
            f"natural frequency {w_meas[i]:.6g} rad/s has no clearly "
            f"nearest model mode (modes {a} at {w_model[a]:.6g} and {b} at {w_model[b]:.6g} "
            "rad/s are comparably close): the model may lack this mode; give mode_indices",
        )
    k, count = np.unique(near, return_counts=True)
    if np.any(count > 1):
        k = k[count > 1][0]
        i, j = np.flatnonzero(near == k)[:2]
        raise ValueError(
            f"measured_eigenvalues[{i}] and [{j}] are both nearest model mode {k} "
            f"({w_model[k]:.6g} rad/s): one measured eigenvalue per model mode; the model "
            "may lack a mode, give mode_indices"
        )
    return near


# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class UpdatedModel:
    """Result of :func:`update_model`.

    Attributes
    ----------
    model : SubstructureModel whose blocks are scaled by the identified parameters (its nominal
        ``p = q = r = 1`` is the updated model).
    p, q, r : identified scalings.
    covariance : covariance of ``(p, q, r)`` stacked.
    undamped : UndampedIdentification; damping : DampingIdentification or None.
    """

    model: SubstructureModel
    p: FloatArray
    q: FloatArray
    r: FloatArray
    covariance: FloatArray
    undamped: UndampedIdentification
    damping: DampingIdentification | None


def update_model(
    model: SubstructureModel,
    measured_frequencies: npt.ArrayLike,
    measured_eigenvalues: npt.ArrayLike | None = None,
    damping_kwargs: dict[str, Any] | None = None,
    **kwargs: Any,
) -> UpdatedModel:
    """Identify ``p, q`` (and ``r`` from ``measured_eigenvalues``) and return the scaled model.

    ``kwargs`` go to :func:`identify_undamped`, ``damping_kwargs`` to :func:`identify_damping`.
    """
    if damping_kwargs is not None and not isinstance(damping_kwargs, Mapping):
        raise FieldError("damping_kwargs", f"must be a mapping, got {damping_kwargs!r}")
    und = identify_undamped(model, measured_frequencies, **kwargs)
    dmp = None
    R = model.n_damping
    r = np.ones(R)
    cov = np.zeros((model.n_stiffness + model.n_mass + R,) * 2)
    P_Q = model.n_stiffness + model.n_mass
    cov[:P_Q, :P_Q] = und.covariance
    if measured_eigenvalues is not None:
        dmp = identify_damping(model, measured_eigenvalues, und.p, und.q, **(damping_kwargs or {}))
        r = dmp.r
        cov[P_Q:, P_Q:] = dmp.covariance
    return UpdatedModel(model.scaled(und.p, und.q, r), und.p, und.q, r, cov, und, dmp)
