"""Creamer–Junkins structural identification (Attachment 7): substructure scalings of M, K, C.

The model is parameterised by substructure scalings (Att. 7 Eqs. 8, 23)::

    K(p) = K0 + sum_k p_k K_k,   M(q) = M0 + sum_k q_k M_k,   C(r) = C0 + sum_k r_k C_k

(``p = q = r = 1`` is the nominal model; ``K0, M0, C0`` are fixed parts, e.g. members carrying no
modal energy that are left out of the identification, Att. 7 Example 2).  The paper writes the
same thing as corrections ``gamma = q - 1``, ``beta = p - 1`` to a nominal model.

Undamped identification (:func:`identify_undamped`, Att. 7 Eqs. 1–9)
    1. Measured frequencies ``wbar_r`` and mode shapes ``psibar_r`` (measured, or approximated
       by the current model's modes).  The shapes have an unknown scale: ``phi_r =
       sqrt(alpha_r) psibar_r`` (Eq. 4).
    2. The normalisation factors ``alpha_r`` are fitted by *linear* least squares to a few
       measured FRF elements (Eqs. 5–6), with a rigid-body term ``a1/w^2`` (free structures) and
       a constant residual ``a2``; from the second pass on, the current model's prediction of the
       unmeasured modes is subtracted from the FRF first (the iteration of L2845).
    3. Orthogonality ``psibar_i^T M psibar_j = delta_ij/alpha_j`` and ``psibar_i^T K psibar_j =
       delta_ij wbar_j^2/alpha_j`` (Eq. 7) are linear in ``q`` and ``p`` (Eq. 9), solved by least
       squares; with the current model's shapes the diagonal rows are exactly the Gauss-Newton
       step on the eigenvalues, since ``d(lambda_i)/dp_k = phi_i^T K_k phi_i`` and
       ``d(lambda_i)/dq_k = -lambda_i phi_i^T M_k phi_i`` (closed-form sensitivities of
       mass-normalised modes).  The model is re-solved and the steps repeated.

    Scale constraint.  Frequencies and shapes alone are unchanged by ``(K, M) -> c (K, M)``, so
    only the stiffness-to-mass ratio is identifiable from them.  The absolute scale enters only
    through the modal normalisation ``alpha`` (Eq. 4), which the FRF supplies (Eqs. 5–6; Att. 7
    advantage 1: "the FRF gives a unique scaling").  Without an FRF the mass scalings are held
    at their start values (``alpha_i = 1 / psibar_i^T M(q) psibar_i``: the mass is the known
    scale) and only the stiffness scalings are identified.

    Status of the FRF (mass) path: exact for exact shapes and complete modal data (tested);
    on a 4-mass-group arm with model-predicted shapes the Eq. 9a mass problem proved
    ill-conditioned (a poorly observed mode's alpha spoils the others) and did not converge,
    so the Example 1/2 tests use the frequency path with the mass as held scale.

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

All matrices may be dense arrays or scipy sparse matrices; the eigen-solves are dense (models up
to a few thousand dofs).  Errors are ``ValueError`` naming the field.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from flexsat.validation import require_numeric

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
]


# ------------------------------------------------------------------------------------------------
def _dense(A, field_name, n=None) -> np.ndarray:
    if sp.issparse(A):
        A = A.toarray()
    A = require_numeric(A, field_name, "matrix")
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"{field_name}: must be a square matrix, got shape {A.shape}")
    if n is not None and A.shape[0] != n:
        raise ValueError(f"{field_name}: must be {n}x{n} like the other blocks, got {A.shape}")
    if np.abs(A - A.T).max() > 1e-9 * max(np.abs(A).max(), 1e-300):
        raise ValueError(f"{field_name}: must be symmetric")
    return (A + A.T) / 2.0


def _blocks(blocks, name, n):
    if blocks is None:
        return []
    if sp.issparse(blocks) or (isinstance(blocks, np.ndarray) and blocks.ndim == 2):
        raise ValueError(f"{name}: must be a list of matrices (one per substructure)")
    return [_dense(B, f"{name}[{k}]", n) for k, B in enumerate(blocks)]


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

    K_blocks: list
    M_blocks: list
    C_blocks: list = field(default_factory=list)
    K0: np.ndarray | None = None
    M0: np.ndarray | None = None
    C0: np.ndarray | None = None
    names: tuple = ()

    def __post_init__(self):
        if not self.K_blocks and self.K0 is None:
            raise ValueError("K_blocks: give at least one stiffness block (or K0)")
        first = self.K_blocks[0] if self.K_blocks else self.K0
        n = first.shape[0] if hasattr(first, "shape") else np.asarray(first).shape[0]
        object.__setattr__(self, "K_blocks", _blocks(self.K_blocks, "K_blocks", n))
        object.__setattr__(self, "M_blocks", _blocks(self.M_blocks, "M_blocks", n))
        object.__setattr__(self, "C_blocks", _blocks(self.C_blocks, "C_blocks", n))
        if not self.M_blocks and self.M0 is None:
            raise ValueError("M_blocks: give at least one mass block (or M0)")
        for name in ("K0", "M0", "C0"):
            value = getattr(self, name)
            object.__setattr__(self, name, np.zeros((n, n)) if value is None
                               else _dense(value, name, n))
        object.__setattr__(self, "names", tuple(self.names))

    @property
    def n_dofs(self) -> int:
        return self.K0.shape[0]

    @property
    def n_stiffness(self) -> int:
        return len(self.K_blocks)

    @property
    def n_mass(self) -> int:
        return len(self.M_blocks)

    @property
    def n_damping(self) -> int:
        return len(self.C_blocks)

    def _params(self, values, count, name):
        if values is None:
            return np.ones(count)
        v = require_numeric(values, name, "vector").ravel()
        if v.shape != (count,):
            raise ValueError(f"{name}: must have {count} entries (one per block), got {v.size}")
        return v

    def K(self, p=None) -> np.ndarray:
        p = self._params(p, self.n_stiffness, "p")
        return self.K0 + sum((pk * Kk for pk, Kk in zip(p, self.K_blocks)), np.zeros_like(self.K0))

    def M(self, q=None) -> np.ndarray:
        q = self._params(q, self.n_mass, "q")
        return self.M0 + sum((qk * Mk for qk, Mk in zip(q, self.M_blocks)), np.zeros_like(self.M0))

    def C(self, r=None) -> np.ndarray:
        r = self._params(r, self.n_damping, "r")
        return self.C0 + sum((rk * Ck for rk, Ck in zip(r, self.C_blocks)), np.zeros_like(self.C0))

    def modes(self, p=None, q=None, n_modes=None):
        """Natural frequencies (rad/s, ascending) and mass-normalised shapes (n, n_modes)."""
        K, M = self.K(p), self.M(q)
        try:
            lam, phi = sla.eigh(K, M, subset_by_index=None if n_modes is None
                                else [0, min(n_modes, self.n_dofs) - 1])
        except np.linalg.LinAlgError:
            raise ValueError("mass scalings: M(q) is not positive definite") from None
        if lam.min() < -1e-8 * max(abs(lam).max(), 1.0):
            raise ValueError("stiffness scalings: K(p) is not positive semi-definite")
        return np.sqrt(np.clip(lam, 0.0, None)), phi

    def scaled(self, p=None, q=None, r=None) -> "SubstructureModel":
        """The same parameterisation with the blocks multiplied by ``p, q, r`` (new nominal)."""
        p = self._params(p, self.n_stiffness, "p")
        q = self._params(q, self.n_mass, "q")
        r = self._params(r, self.n_damping, "r")
        return SubstructureModel([a * B for a, B in zip(p, self.K_blocks)],
                                 [a * B for a, B in zip(q, self.M_blocks)],
                                 [a * B for a, B in zip(r, self.C_blocks)],
                                 self.K0, self.M0, self.C0, self.names)


def substructures_from_builder(build, n_stiffness, n_mass=None, C_blocks=(), names=()):
    """Blocks of a linear FE model from a builder of scaled assemblies.

    ``build(stiffness_factors, mass_factors)`` must return an object with ``K`` and ``M`` (e.g. a
    :class:`flexsat.structures.fem.Assembly`) for the structure whose substructure ``k`` has its
    stiffness (e.g. ``E``) multiplied by ``stiffness_factors[k]`` and its mass (``rho``, lumped
    masses) by ``mass_factors[k]``.  The blocks are the exact differences ``K(e_k + 1) - K(1)``
    (assembly is linear in the factors without preloads) and the fixed parts ``K0 = K(1) -
    sum K_k``: members outside every substructure.
    """
    n_mass = n_stiffness if n_mass is None else n_mass
    one_k, one_m = np.ones(n_stiffness), np.ones(n_mass)
    base = build(one_k, one_m)
    K1, M1 = _dense(base.K, "build().K"), _dense(base.M, "build().M")
    Kb, Mb = [], []
    for k in range(n_stiffness):
        f = one_k.copy()
        f[k] = 2.0
        Kb.append(_dense(build(f, one_m).K, "build().K") - K1)
    for k in range(n_mass):
        f = one_m.copy()
        f[k] = 2.0
        Mb.append(_dense(build(one_k, f).M, "build().M") - M1)
    K0 = K1 - sum(Kb, np.zeros_like(K1))
    M0 = M1 - sum(Mb, np.zeros_like(M1))
    scale_k, scale_m = np.abs(K1).max(), np.abs(M1).max()
    K0[np.abs(K0) < 1e-12 * scale_k] = 0.0
    M0[np.abs(M0) < 1e-12 * scale_m] = 0.0
    return SubstructureModel(Kb, Mb, list(C_blocks), K0, M0, names=names)


# ------------------------------------------------------------------------------------------------
def modal_energy_distribution(K_blocks, M_blocks, shapes, omegas=None) -> dict:
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
    phi = require_numeric(shapes, "shapes", "matrix")
    if phi.ndim == 1:
        phi = phi[:, None]
    n = phi.shape[0]
    Kb, Mb = _blocks(K_blocks, "K_blocks", n), _blocks(M_blocks, "M_blocks", n)
    if not Kb or not Mb:
        raise ValueError("K_blocks, M_blocks: need at least one block each")
    ke = np.array([np.einsum("ij,ik,kj->j", phi, Mg, phi) for Mg in Mb]).T
    pe = np.array([np.einsum("ij,ik,kj->j", phi, Kg, phi) for Kg in Kb]).T
    if omegas is not None:
        w = require_numeric(omegas, "omegas", "vector").ravel()
        if w.shape != (phi.shape[1],):
            raise ValueError(f"omegas: must have {phi.shape[1]} entries (one per mode)")
        pe = pe / np.where(w > 0, w**2, 1.0)[:, None]

    def frac(e, what):
        tot = e.sum(axis=1, keepdims=True)
        if np.any(np.abs(tot) <= 0):
            raise ValueError(f"shapes: a mode has no {what} energy in the given blocks")
        return e / tot

    return dict(kinetic=frac(ke, "kinetic"), strain=frac(pe, "strain"))


# ------------------------------------------------------------------------------------------------
def _check_frf(frf, n):
    """Normalise FRF input to a list of (j, k, omegas, values)."""
    if frf is None:
        return []
    if isinstance(frf, tuple) and len(frf) == 4 and np.ndim(frf[2]) == 1:
        frf = [frf]
    out = []
    for i, item in enumerate(frf):
        try:
            j, k, w, h = item
        except (TypeError, ValueError):
            raise ValueError(f"frf[{i}]: must be (output_dof, input_dof, omegas, values)") from None
        for name, d in (("output_dof", j), ("input_dof", k)):
            if isinstance(d, bool) or not isinstance(d, (int, np.integer)) or not 0 <= d < n:
                raise ValueError(f"frf[{i}].{name}: must be a dof index in [0, {n}), got {d!r}")
        w = require_numeric(w, f"frf[{i}].omegas", "vector").ravel()
        h = require_numeric(h, f"frf[{i}].values", "vector").ravel()
        if w.shape != h.shape or w.size == 0:
            raise ValueError(f"frf[{i}]: omegas and values must be equal-length non-empty vectors")
        if np.any(w <= 0):
            raise ValueError(f"frf[{i}].omegas: must be > 0 rad/s")
        out.append((int(j), int(k), w, h))
    return out


def fit_modal_normalization(frf, shapes, omegas, rigid_body=False, residual=True,
                            known_part=None):
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
    psi = np.asarray(shapes, float)
    w_r = np.asarray(omegas, float)
    items = _check_frf(frf, psi.shape[0])
    if not items:
        raise ValueError("frf: at least one FRF element is needed")
    m, nf = psi.shape[1], len(items)
    n_extra = (int(rigid_body) + int(residual)) * nf
    rows, rhs = [], []
    for i, (j, k, w, h) in enumerate(items):
        h_meas = h
        if known_part is not None:
            h = h - known_part[i]
        denom = w_r[None, :] ** 2 - w[:, None] ** 2
        if np.any(np.abs(denom) < 1e-9 * w_r.max() ** 2):
            raise ValueError(f"frf[{i}].omegas: a point coincides with a natural frequency")
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
        raise ValueError(f"frf: {A.shape[0]} FRF points for {A.shape[1]} unknowns "
                         "(normalisation factors and rigid/residual terms): need more points")
    scale = np.abs(A).max(axis=0)
    scale[scale == 0] = 1.0
    x = np.linalg.lstsq(A / scale, b, rcond=None)[0] / scale
    alpha = x[:m]
    if np.any(alpha <= 0):
        raise ValueError("frf: fitted modal normalisation factors must be > 0 (FRF does not "
                         f"observe a measured mode, or shapes inconsistent): {alpha}")
    a1 = x[m:m + nf] if rigid_body else np.zeros(nf)
    a2 = x[m + (nf if rigid_body else 0):] if residual else np.zeros(nf)
    return alpha, a1, a2


def _model_frf(K, M, items):
    """Receptance elements of the current model at the FRF points (direct solve)."""
    out = []
    for j, k, w, _ in items:
        h = np.empty(w.size)
        for i, wi in enumerate(w):
            e = np.zeros(K.shape[0])
            e[k] = 1.0
            h[i] = np.linalg.solve(K - wi**2 * M, e)[j]
        out.append(h)
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

    p: np.ndarray
    q: np.ndarray
    covariance: np.ndarray
    frequencies: np.ndarray
    alpha: np.ndarray
    iterations: int
    converged: bool
    history: list


def _solve_ls(A, b, weights, name):
    if A.shape[0] < A.shape[1]:
        raise ValueError(f"{name}: {A.shape[0]} equations for {A.shape[1]} parameters: more "
                         "parameters than data (measure more modes, add FRFs, or fix parameters)")
    Aw, bw = A * weights[:, None], b * weights
    scale = np.linalg.norm(Aw, axis=0)
    if np.any(scale == 0):
        bad = np.nonzero(scale == 0)[0].tolist()
        raise ValueError(f"{name}: parameters {bad} do not affect the measured modes (no modal "
                         "energy; see modal_energy_distribution): fix them")
    As = Aw / scale
    s = np.linalg.svd(As, compute_uv=False)
    if s[-1] < 1e-10 * s[0]:
        raise ValueError(f"{name}: parameters not identifiable from the data (condition number "
                         f"{s[0] / max(s[-1], 1e-300):.3g}); fix some or add data")
    x = np.linalg.lstsq(As, bw, rcond=None)[0]
    res = bw - As @ x
    dof = A.shape[0] - A.shape[1]
    cov_s = np.linalg.inv(As.T @ As)
    return x / scale, cov_s / np.outer(scale, scale), res, dof


def _pair_modes(omega_model, phi_model, measured_w, measured_shapes, mode_indices):
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


def identify_undamped(model: SubstructureModel, measured_frequencies, measured_shapes=None,
                      frf=None, p0=None, q0=None, fixed_stiffness=(), fixed_mass=(),
                      frequency_sigma=None, mode_indices=None, off_diagonal=None,
                      rigid_body=False, residual=True, n_iter=30, tol=1e-10,
                      identify_mass=None) -> UndampedIdentification:
    """Iterated least-squares identification of the stiffness and mass scalings (Eqs. 1–9).

    Parameters
    ----------
    model : SubstructureModel
    measured_frequencies : (m,) rad/s, > 0, of the lowest modes (or of ``mode_indices``).
    measured_shapes : (n, m), optional
        Measured shapes on all dofs (any scale).  Default: the current model's modes, refreshed
        every pass (Att. 7 Examples 1–2).
    frf : (j, k, omegas, values) or list, optional
        Measured receptance elements (real, away from resonance).  Needed to identify the mass
        scalings (absolute scale, Eqs. 5–6); without it the mass scalings are held.
    p0, q0 : start scalings (default 1).  fixed_stiffness, fixed_mass : indices held at start.
    frequency_sigma : (m,) or scalar, optional
        Standard deviation of the measured frequencies (rad/s): weights the rows and scales the
        covariance; default: covariance from the residual scatter (zero for an exact fit).
    mode_indices : model mode numbers (0-based) of the measured modes; default by order (or by
        MAC with measured shapes).
    off_diagonal : use the i != j rows of Eq. 9 (default: only with measured shapes).
    rigid_body, residual : FRF fit terms ``a1/w^2`` and ``a2`` (Eq. 5).
    identify_mass : default: True when an FRF is given.

    Returns
    -------
    UndampedIdentification
    """
    P, Q, n = model.n_stiffness, model.n_mass, model.n_dofs
    wbar = require_numeric(measured_frequencies, "measured_frequencies", "vector").ravel()
    if wbar.size == 0 or np.any(wbar <= 0):
        raise ValueError("measured_frequencies: must be a non-empty vector of values > 0 rad/s")
    m = wbar.size
    if m > n:
        raise ValueError(f"measured_frequencies: {m} modes but the model has {n} dofs")
    psi_meas = None
    if measured_shapes is not None:
        psi_meas = require_numeric(measured_shapes, "measured_shapes", "matrix")
        if psi_meas.ndim == 1:
            psi_meas = psi_meas[:, None]
        if psi_meas.shape != (n, m):
            raise ValueError(f"measured_shapes: must have shape ({n}, {m}), got {psi_meas.shape}")
    items = _check_frf(frf, n)
    identify_mass = bool(items) if identify_mass is None else bool(identify_mass)
    if identify_mass and not items:
        raise ValueError("identify_mass: the mass scalings need an FRF (the absolute scale; "
                         "frequencies and shapes are unchanged by scaling K and M together)")
    if off_diagonal is None:
        off_diagonal = psi_meas is not None
    p = model._params(p0, P, "p0").copy()
    q = model._params(q0, Q, "q0").copy()
    free_p = np.setdiff1d(np.arange(P), np.asarray(fixed_stiffness, int))
    free_q = np.setdiff1d(np.arange(Q), np.asarray(fixed_mass, int)) if identify_mass \
        else np.array([], int)
    if free_p.size == 0 and free_q.size == 0:
        raise ValueError("fixed_stiffness, fixed_mass: every parameter is fixed")
    if frequency_sigma is None:
        sig_w = None
    else:
        sig_w = np.broadcast_to(require_numeric(frequency_sigma, "frequency_sigma"),
                                (m,)).astype(float)
        if np.any(sig_w <= 0):
            raise ValueError("frequency_sigma: must be > 0")
    pairs = [(i, i) for i in range(m)]
    if off_diagonal:
        pairs += [(i, j) for i in range(m) for j in range(i + 1, m)]
    n_rows = len(pairs)
    for name, free in (("stiffness", free_p), ("mass", free_q)):
        if free.size > n_rows:
            raise ValueError(
                f"measured_frequencies: {n_rows} equations for {free.size} {name} parameters: "
                "more parameters than data (Att. 7 needs m(m+1)/2 > parameters with measured "
                "shapes, m >= parameters without): measure more modes or fix parameters")

    history, converged, steps = [(p.copy(), q.copy())], False, []
    alpha = np.ones(m)
    cov = np.zeros((P + Q, P + Q))
    for it in range(1, n_iter + 1):
        K, Mq = model.K(p), model.M(q)
        w_model, phi_model = model.modes(p, q)
        idx = _pair_modes(w_model, phi_model, wbar, psi_meas, mode_indices)
        psi = psi_meas if psi_meas is not None else phi_model[:, idx]
        # --- normalisation factors alpha (Eqs. 5-6) -----------------------------------------
        if identify_mass:
            # current model's contribution of the unmeasured modes (iteration of L2845)
            h_model = _model_frf(K, Mq, items)
            known = []
            for (j, k, w, _), hm in zip(items, h_model):
                meas = phi_model[j, idx] * phi_model[k, idx] / (w_model[idx][None, :]**2
                                                                 - w[:, None]**2)
                known.append(hm - meas.sum(axis=1))
            alpha, _, _ = fit_modal_normalization(items, psi, wbar, rigid_body=rigid_body,
                                                  residual=residual, known_part=known)
        else:
            alpha = 1.0 / np.einsum("ij,ik,kj->j", psi, Mq, psi)
        # --- Eq. 9a: mass scalings -------------------------------------------------------------
        q_new, p_new = q.copy(), p.copy()
        # row weights: relative residuals (a low mode counts as much as a high one); with
        # frequency_sigma, 1/SD of the right side (row i=i: wbar^2/alpha, SD 2 wbar sigma/alpha)
        ii = np.array([i for i, _ in pairs])
        jj = np.array([j for _, j in pairs])
        rel = np.ones(m) if sig_w is None else 2.0 * sig_w / wbar
        weights_k = np.sqrt(alpha[ii] * alpha[jj]) / (wbar[ii] * wbar[jj]) \
            / np.sqrt(rel[ii] * rel[jj])
        weights_m = np.sqrt(alpha[ii] * alpha[jj])
        cov = np.zeros((P + Q, P + Q))
        if free_q.size:
            A = np.array([[psi[:, i] @ model.M_blocks[g] @ psi[:, j] for g in free_q]
                          for i, j in pairs])
            Mfix = Mq - sum((q[g] * model.M_blocks[g] for g in free_q), np.zeros((n, n)))
            b = np.array([(1.0 / alpha[i] if i == j else 0.0) - psi[:, i] @ Mfix @ psi[:, j]
                          for i, j in pairs])
            x, c, res, dof = _solve_ls(A, b, weights_m, "mass scalings")
            q_new[free_q] = x
            s2 = (res @ res / dof) if dof > 0 else 0.0
            cov[np.ix_(P + free_q, P + free_q)] = c * s2
        # --- Eq. 9b: stiffness scalings --------------------------------------------------------
        if free_p.size:
            A = np.array([[psi[:, i] @ model.K_blocks[g] @ psi[:, j] for g in free_p]
                          for i, j in pairs])
            Kfix = K - sum((p[g] * model.K_blocks[g] for g in free_p), np.zeros((n, n)))
            b = np.array([(wbar[i] ** 2 / alpha[i] if i == j else 0.0)
                          - psi[:, i] @ Kfix @ psi[:, j] for i, j in pairs])
            x, c, res, dof = _solve_ls(A, b, weights_k, "stiffness scalings")
            p_new[free_p] = x
            s2 = 1.0 if sig_w is not None else ((res @ res / dof) if dof > 0 else 0.0)
            cov[np.ix_(free_p, free_p)] = c * s2
        # scalings must stay positive (K, M definite): shorten a step that leaves them
        dp, dq, t = p_new - p, q_new - q, 1.0
        while t > 1e-6 and (np.any(p + t * dp <= 0) or np.any(q + t * dq <= 0)):
            t *= 0.5
        if t <= 1e-6:
            raise ValueError("identification diverged: the least-squares step makes a scaling "
                             f"non-positive (p={p_new}, q={q_new}); fix weakly observed "
                             "parameters (see modal_energy_distribution)")
        steps.append(t)
        p_new, q_new = p + t * dp, q + t * dq
        step = max(np.abs(p_new - p).max(), np.abs(q_new - q).max() if Q else 0.0)
        p, q = p_new, q_new
        history.append((p.copy(), q.copy()))
        if step < tol:
            converged = True
            break
    w_final, phi_final = model.modes(p, q)
    idx = _pair_modes(w_final, phi_final, wbar, psi_meas, mode_indices)
    return UndampedIdentification(p, q, cov, w_final[idx], alpha, it, converged, history)


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
    """

    r: np.ndarray
    covariance: np.ndarray
    predicted_real_parts: np.ndarray
    eigenvalues: np.ndarray


def damped_eigenvalues(K, M, C, n_modes=None) -> np.ndarray:
    """Eigenvalues of ``M x'' + C x' + K x = 0`` with positive imaginary part, by frequency."""
    K, M, C = (np.asarray(A.toarray() if sp.issparse(A) else A, float) for A in (K, M, C))
    n = K.shape[0]
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(lam.imag)]
    return lam if n_modes is None else lam[:n_modes]


def identify_damping(model: SubstructureModel, measured_eigenvalues, p=None, q=None,
                     mode_indices=None, fixed=(), r0=None) -> DampingIdentification:
    """Damping scalings from measured eigenvalue real parts by first-order perturbation.

    Att. 7 Eq. 24: ``sum_k r_k phi_0r^T C_k phi_0r = -2 sigmabar_r - phi_0r^T C0 phi_0r`` with
    ``phi_0r`` the mass-normalised modes of the undamped model ``K(p), M(q)`` (the identified
    one).  The first-order theory predicts no frequency shift, so only the real parts are used.

    Parameters
    ----------
    model : SubstructureModel with ``C_blocks``.
    measured_eigenvalues : (m,) complex (``sigma + i w``) or real parts only (sigma < 0).
    p, q : undamped scalings (e.g. from :func:`identify_undamped`).
    mode_indices : model modes of the measured eigenvalues (default: the lowest m).
    fixed : damping blocks held at ``r0`` (default 1).
    """
    R = model.n_damping
    if R == 0:
        raise ValueError("C_blocks: the model has no damping blocks")
    lam = np.asarray(measured_eigenvalues)
    if isinstance(measured_eigenvalues, (str, bytes)) or lam.dtype.kind not in "biufc":
        raise ValueError("measured_eigenvalues: must be a numeric (complex) vector")
    lam = lam.ravel().astype(complex)
    if lam.size == 0 or not np.all(np.isfinite(lam)):
        raise ValueError("measured_eigenvalues: must be a non-empty finite vector "
                         "(no NaN or inf)")
    sigma = lam.real
    if np.any(sigma >= 0):
        raise ValueError("measured_eigenvalues: real parts must be < 0 (a damped, stable "
                         "structure)")
    m = sigma.size
    r = model._params(r0, R, "r0").copy()
    free = np.setdiff1d(np.arange(R), np.asarray(fixed, int))
    if free.size == 0:
        raise ValueError("fixed: every damping parameter is fixed")
    if free.size > m:
        raise ValueError(f"measured_eigenvalues: {m} eigenvalues for {free.size} damping "
                         "parameters: more parameters than data (Att. 7 needs m > R)")
    w0, phi = model.modes(p, q)
    idx = np.arange(m) if mode_indices is None else np.asarray(mode_indices, int)
    if idx.size != m or idx.max() >= phi.shape[1]:
        raise ValueError("mode_indices: must give one model mode per measured eigenvalue")
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
    return DampingIdentification(r, cov, predicted, eig)


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
    p: np.ndarray
    q: np.ndarray
    r: np.ndarray
    covariance: np.ndarray
    undamped: UndampedIdentification
    damping: DampingIdentification | None


def update_model(model: SubstructureModel, measured_frequencies, measured_eigenvalues=None,
                 damping_kwargs=None, **kwargs) -> UpdatedModel:
    """Identify ``p, q`` (and ``r`` from ``measured_eigenvalues``) and return the scaled model.

    ``kwargs`` go to :func:`identify_undamped`, ``damping_kwargs`` to :func:`identify_damping`.
    """
    und = identify_undamped(model, measured_frequencies, **kwargs)
    dmp = None
    R = model.n_damping
    r = np.ones(R)
    cov = np.zeros((model.n_stiffness + model.n_mass + R,) * 2)
    P_Q = model.n_stiffness + model.n_mass
    cov[:P_Q, :P_Q] = und.covariance
    if measured_eigenvalues is not None:
        dmp = identify_damping(model, measured_eigenvalues, und.p, und.q,
                               **(damping_kwargs or {}))
        r = dmp.r
        cov[P_Q:, P_Q:] = dmp.covariance
    return UpdatedModel(model.scaled(und.p, und.q, r), und.p, und.q, r, cov, und, dmp)
