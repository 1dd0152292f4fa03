"""Controllability and stabilizability of linear systems (python-control conventions).

Every function takes numpy arrays ``A`` (n x n) and ``B`` (n x m, a 1-D ``B`` of length n is one
input column), as :func:`control.ctrb` does, and refuses bad shapes and non-finite entries with a
message that starts with the field name.

Tests provided (Bainum & Reddy 1979, NASA CR-158684, Ch. II):

- :func:`controllability_rank`: rank of the Kalman matrix ``[B, AB, ..., A^(n-1) B]`` by SVD;
- :func:`pbh_test`: the Popov-Belevitch-Hautus test, ``rank [λI - A, B] = n`` at every
  eigenvalue λ of A, returning the uncontrollable eigenvalues;
- :func:`repeated_frequency_test`: the block test of Balas (1978) used in Ch. II §3 (Bainum & Reddy
  1979) for an undamped modal system ``ẍ + diag(κ) x = B u``: the pair is
  controllable iff, for every distinct κ, the rows of B of the modes sharing it have rank equal
  to their number (the multiplicity);
- :func:`is_stabilizable`: PBH restricted to eigenvalues with Re λ >= 0.

The regulators of Ch. III / Ch. V use :func:`flexsat.control.lqr`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.linalg

from flexsat.input_checks import FieldError, require_numeric
from flexsat.units import FloatArray

_EPS = np.finfo(float).eps


# -- input checks ------------------------------------------------------------------------------
def _array(value: npt.ArrayLike, field: str) -> FloatArray:
    return require_numeric(value, field, "array")


def _square(value: npt.ArrayLike, field: str) -> FloatArray:
    arr = _array(value, field)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or arr.shape[0] == 0:
        raise FieldError(field, f"must be a non-empty square 2-D array, got shape {arr.shape}")
    return arr


def _input_matrix(value: npt.ArrayLike, n: int, field: str = "B", other: str = "A") -> FloatArray:
    arr = _array(value, field)
    if arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2 or arr.shape[0] != n or arr.shape[1] == 0:
        raise FieldError(
            field,
            f"must have {n} rows ({other} is {n}x{n}) and at least one "
            f"column, got shape {np.shape(value)}",
        )
    return arr


def _pair(A: npt.ArrayLike, B: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    A = _square(A, "A")
    return A, _input_matrix(B, A.shape[0])


def _tol(tol: float | None, field: str = "tol") -> float | None:
    if tol is None:
        return None
    value = float(_array(tol, field))
    if value < 0:
        raise FieldError(field, f"must be >= 0, got {tol!r}")
    return value


def _rank(M: FloatArray, tol: float | None) -> int:
    """Number of singular values above ``tol`` (default max(shape)·ε·σ_max, numpy's rule)."""
    if M.size == 0:
        return 0
    s = np.linalg.svd(M, compute_uv=False)
    if tol is None:
        tol = max(M.shape) * _EPS * (s[0] if s.size else 0.0)
    return int(np.sum(s > tol))


# -- Kalman rank -------------------------------------------------------------------------------
def controllability_matrix(A: npt.ArrayLike, B: npt.ArrayLike) -> FloatArray:
    """The Kalman matrix ``[B, AB, A²B, ..., A^(n-1) B]`` (n x nm), as :func:`control.ctrb`.

    Raises
    ------
    ValueError
        ``A`` not square, ``B`` without n rows, non-finite entries.
    """
    A, B = _pair(A, B)
    blocks = [B]
    for _ in range(A.shape[0] - 1):
        blocks.append(A @ blocks[-1])
    return np.hstack(blocks)


def controllability_rank(A: npt.ArrayLike, B: npt.ArrayLike, tol: float | None = None) -> int:
    """Rank of the Kalman controllability matrix of (A, B).

    The rank is the number of singular values of the column-normalized Kalman matrix above
    ``tol``. Each column of ``[B, AB, ..., A^(n-1) B]`` is divided by its Euclidean norm first
    (zero columns dropped): this does not change the rank, and it keeps the powers of a stiff A
    (Bainum's (ω_n/ω_c)² up to 2.6e5) from swamping the low-frequency columns.

    Parameters
    ----------
    A : (n, n) array_like
    B : (n, m) array_like
        One input per column; a 1-D array is one column.
    tol : float, optional
        Singular-value threshold for the normalized matrix. Default: ``max(n, n m) · ε · σ_max``
        (numpy's ``matrix_rank`` rule; ε = 2.2e-16, σ_max ≤ √(n m) after normalization).

    Returns
    -------
    int
        The rank; the pair is controllable iff it equals n (Kalman).

    Notes
    -----
    The Kalman matrix is badly conditioned for large n or widely spread eigenvalues; prefer
    :func:`pbh_test` (or :func:`repeated_frequency_test` for modal systems) there. Bainum & Reddy
    1979 Ch. III §2 makes the same point by counting the C(36, 12) = 1.25e9 minors a hand
    search would need.

    Examples
    --------
    >>> controllability_rank([[0, 1], [0, 0]], [0, 1])
    2
    """
    tol = _tol(tol)
    C = controllability_matrix(A, B)
    norms = np.linalg.norm(C, axis=0)
    keep = norms > 0
    if not np.any(keep):
        return 0
    return _rank(C[:, keep] / norms[keep], tol)


# -- PBH ---------------------------------------------------------------------------------------
_SQRT_EPS = np.sqrt(_EPS)


def _balanced(A: FloatArray, B: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(D⁻¹AD, D⁻¹B) with D the diagonal balancing of A: a modal model's rows scale as ω² and
    ω, and balancing brings them to ~ω so that its eigenvectors carry errors of ~ε‖A‖/gap with
    the balanced, not the raw, ‖A‖.

    Entries below ε max|A| are set to zero first: they are round-off of A's own scale (a
    linearisation at a nominal rate of 1e-28 rad/s that is zero in exact arithmetic), and
    balancing would otherwise scale them up by as much as it scales the entries down (1e31
    measured), making the balanced matrix meaningless."""
    A = np.where(np.abs(A) <= np.finfo(float).eps * np.abs(A).max(initial=0.0), 0.0, A)
    d = scipy.linalg.matrix_balance(A, permute=False, separate=True)[1][0]
    return A * d[None, :] / d[:, None], B / d[:, None]


def pbh_clusters(
    A: FloatArray,
    B: FloatArray,
    select: Callable[[npt.NDArray[np.complex128], float], npt.NDArray[np.bool_]] | None = None,
    tol: float | None = None,
) -> list[complex]:
    """Eigenvalue clusters of A at which ``[λI − A, B]`` loses rank (PBH), each tested on its
    own scale.

    A single threshold on ``[λI − A, B]`` compares a mode at 1,000 rad/s with one at 0.1 rad/s
    on the scale of the largest: a lightly damped modal model then shows most of its low modes
    "uncontrollable". Here the pair is balanced, the eigenvalues within ``√ε ‖A‖₁`` of each
    other are merged into clusters (a repeated or defective eigenvalue splits by about that),
    and each cluster's left invariant subspace W (k columns, from the reordered Schur form of
    Aᴴ) is tested alone: the cluster is uncontrollable when the k-th singular value of
    ``[(M − λ̄I)/‖M‖, WᴴB/‖B‖]`` (M = Wᴴ-projected A, λ̄ the cluster mean) is at most ``tol``.

    Parameters
    ----------
    A : (n, n) ndarray
    B : (n, m) ndarray
    select : callable, optional
        ``select(eigenvalues, radius) -> mask`` of the eigenvalues to test (e.g. the unstable
        ones); default all.
    tol : float, optional
        Threshold on the normalized singular value; default √ε.

    Returns
    -------
    list of complex
        One value per uncontrollable cluster (its mean, real and imaginary parts below the
        cluster radius set to 0), in the order of the Schur form.
    """
    tol = _SQRT_EPS if tol is None else tol
    A, B = _balanced(A, B)
    n, scale = A.shape[0], max(1.0, float(np.abs(A).sum(axis=0).max(initial=0.0)))
    radius = _SQRT_EPS * scale
    T, Z = scipy.linalg.schur(A.conj().T, output="complex")
    lam = np.conj(np.diag(T))
    chosen = np.ones(n, bool) if select is None else select(lam, radius)
    nb = np.linalg.norm(B, 2)
    out: list[complex] = []
    tested = np.zeros(n, dtype=bool)
    for i in np.flatnonzero(chosen):
        if tested[i]:
            continue
        cluster = np.abs(lam - lam[i]) <= radius
        tested |= cluster
        lc = complex(np.mean(lam[cluster]))
        re, im = (0.0 if abs(x) <= radius else x for x in (lc.real, lc.imag))
        lc = complex(re, im) if im else re
        if nb == 0:
            out.append(lc)
            continue
        Ts, Zs, *_, info = scipy.linalg.lapack.ztrsen(cluster.astype(np.int32), T, Z, job="N")
        if info != 0:
            raise np.linalg.LinAlgError(f"ztrsen: reordering the Schur form failed (info {info})")
        k = int(cluster.sum())
        W, M = Zs[:, :k], Ts[:k, :k].conj().T
        s_lam = max(np.linalg.norm(M, 2), _EPS**0.25 * scale)
        P = np.hstack([(M - lc * np.eye(k)) / s_lam, W.conj().T @ B / nb])
        if np.linalg.svd(P, compute_uv=False)[k - 1] <= tol:
            out.append(lc)
    return out


def _pbh(A: FloatArray, B: FloatArray, tol: float | None) -> npt.NDArray[np.complex128]:
    bad = pbh_clusters(A, B, tol=tol)
    return np.array(sorted(bad, key=lambda z: (z.real, z.imag)), dtype=complex)


def pbh_test(
    A: npt.ArrayLike, B: npt.ArrayLike, tol: float | None = None
) -> npt.NDArray[np.complex128]:
    """Uncontrollable eigenvalues of (A, B) by the Popov-Belevitch-Hautus test.

    λ (an eigenvalue of A) is uncontrollable iff ``rank [λI - A, B] < n``.

    Parameters
    ----------
    A : (n, n) array_like
    B : (n, m) array_like
    tol : float, optional
        Threshold on the normalized singular value of each eigenvalue cluster's PBH matrix,
        default √ε: every cluster is tested on its own scale (:func:`pbh_clusters`), so a
        lightly damped mode at 0.1 rad/s beside one at 1,000 rad/s is judged correctly.

    Returns
    -------
    ndarray of complex
        The distinct uncontrollable eigenvalues, sorted by real then imaginary part; empty iff
        the pair is controllable.

    Examples
    --------
    >>> pbh_test([[-1, 0], [0, -2]], [[1], [0]])
    array([-2.+0.j])
    """
    A, B = _pair(A, B)
    return _pbh(A, B, _tol(tol))


def is_stabilizable(
    A: npt.ArrayLike, B: npt.ArrayLike, tol: float | None = None, margin: float | None = None
) -> bool:
    """True iff every uncontrollable eigenvalue of (A, B) has Re λ < 0 (continuous time).

    Parameters
    ----------
    A, B, tol
        As :func:`pbh_test`.
    margin : float, optional
        An uncontrollable eigenvalue counts as unstable when ``Re λ >= -margin``. Default
        ``√ε · max(1, |λ|)``, so an undamped uncontrollable mode (Re λ = 0 up to rounding) makes
        the pair not stabilizable.
    """
    A, B = _pair(A, B)
    margin = _tol(margin, "margin")
    for lam in _pbh(A, B, _tol(tol)):
        m = np.sqrt(_EPS) * max(1.0, abs(lam)) if margin is None else margin
        if lam.real >= -m:
            return False
    return True


# -- Balas' block test for repeated frequencies -------------------------------------------------
@dataclass(frozen=True)
class FrequencyGroup:
    """Modes sharing one natural frequency (stiffness entry κ = ω²)."""

    omega_sq: float
    modes: tuple[int, ...]  # row indices of the modal input matrix
    rank: int  # rank of those rows of B

    @property
    def multiplicity(self) -> int:
        return len(self.modes)

    @property
    def controllable(self) -> bool:
        return self.rank == self.multiplicity


@dataclass(frozen=True)
class RepeatedFrequencyResult:
    """Outcome of :func:`repeated_frequency_test`: one :class:`FrequencyGroup` per distinct κ."""

    groups: tuple[FrequencyGroup, ...]

    @property
    def controllable(self) -> bool:
        return all(g.controllable for g in self.groups)

    @property
    def deficient(self) -> tuple[FrequencyGroup, ...]:
        """The groups whose rows of B have rank below their multiplicity."""
        return tuple(g for g in self.groups if not g.controllable)


def repeated_frequency_test(
    stiffness: npt.ArrayLike,
    B: npt.ArrayLike,
    tol: float | None = None,
    freq_tol: float | None = None,
) -> RepeatedFrequencyResult:
    """Controllability of the undamped modal system ``ẍ + diag(κ) x = B u`` by blocks.

    The theorem (Balas 1978, applied in Bainum & Reddy 1979 Ch. II §3:
    "these m subsystems with their
    corresponding blocks in the B matrix must each be separately controllable"):
    group the modes by equal κ_k = ω_k². The 2n-state system ``[[0, I], [-diag(κ), 0]]``,
    ``[[0], [B]]`` is controllable iff, for every group, the rows of B of its modes have rank
    equal to the multiplicity. (By PBH: at λ with λ² = -κ_k the rank of
    ``[λ² I + diag(κ), B]`` must be n.) With distinct frequencies this reduces to "no zero row
    of B"; κ may be zero (rigid modes) or negative (unstable modes).

    Parameters
    ----------
    stiffness : (n,) array_like or (n, n) diagonal array_like
        κ = ω², in any consistent unit (for Bainum's beam the nondimensional
        (3, (ω_1/ω_c)², ...)). Only undamped modal (diagonal, unit-mass) systems; use
        :func:`controllability_rank` or :func:`pbh_test` on the first-order model otherwise
        (Bainum & Reddy 1979 Ch. III §2).
    B : (n, m) array_like
        Modal input matrix; a 1-D array is one column.
    tol : float, optional
        Singular-value threshold for each block of rows. Default: numpy's
        ``max(shape) · ε · σ_max`` of the block.
    freq_tol : float, optional
        Two κ are the same frequency when they differ by at most ``freq_tol``. Default
        ``1e-9 · max|κ|``.

    Returns
    -------
    RepeatedFrequencyResult
        ``.controllable``, ``.groups`` (κ, mode indices, rank), ``.deficient``.

    Examples
    --------
    Bainum & Reddy 1979 Ch. II Case 4 with ω_2 = √3 ω_c (pitch and mode 2 share κ = 3):

    >>> r = repeated_frequency_test([3, 3200, 3], [[59.52, -59.52, 0], [20, 20, -12.16],
    ...                                            [20, -20, 0]])
    >>> r.controllable, r.deficient[0].modes, r.deficient[0].rank
    (False, (0, 2), 1)
    """
    k = _array(stiffness, "stiffness")
    if k.ndim == 2:
        if k.shape[0] != k.shape[1] or np.any(k - np.diag(np.diag(k))):
            raise FieldError(
                "stiffness",
                "must be a 1-D array or a diagonal (modal) matrix, got "
                f"a non-diagonal array of shape {k.shape}",
            )
        k = np.diag(k).copy()
    if k.ndim != 1 or k.size == 0:
        raise FieldError(
            "stiffness", f"must be a non-empty 1-D array or a diagonal matrix, got shape {k.shape}"
        )
    n = k.size
    B = _input_matrix(B, n, "B", "stiffness")
    tol = _tol(tol)
    ftol = _tol(freq_tol, "freq_tol")
    if ftol is None:
        ftol = 1e-9 * float(np.max(np.abs(k)))
    unused = np.ones(n, bool)
    groups = []
    for i in np.argsort(k, kind="stable"):
        if not unused[i]:
            continue
        members = np.flatnonzero(unused & (np.abs(k - k[i]) <= ftol))
        unused[members] = False
        groups.append(
            FrequencyGroup(
                float(np.mean(k[members])), tuple(int(j) for j in members), _rank(B[members], tol)
            )
        )
    return RepeatedFrequencyResult(tuple(groups))


__all__ = [
    "FrequencyGroup",
    "RepeatedFrequencyResult",
    "controllability_matrix",
    "controllability_rank",
    "is_stabilizable",
    "pbh_test",
    "repeated_frequency_test",
]
