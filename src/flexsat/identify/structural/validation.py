"""Input checks of the Creamer-Junkins structural identification (Junkins, Pollock & Rahman
1990, Att. 7): symmetric matrices and substructure blocks, mode shapes, block and mode
indices, iteration controls and measured FRF elements; each error names the field."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypeAlias, cast

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from flexsat import limits
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_numeric,
    require_scalar,
)
from flexsat.structures.modal_solve import Matrix
from flexsat.units import FloatArray

__all__ = [
    "IntArray",
    "ComplexArray",
    "FrfElement",
    "FrfItem",
    "FrfRows",
    "as_array_like",
    "check_matrix",
    "block_list",
    "check_blocks",
    "check_shapes",
    "check_indices",
    "check_mode_indices",
    "check_iterations",
    "check_frf",
]

IntArray: TypeAlias = npt.NDArray[np.intp]
ComplexArray: TypeAlias = npt.NDArray[np.complex128]
#: one FRF element as given: (output dof, input dof, omegas rad/s, receptance values)
FrfElement: TypeAlias = tuple[int, int, npt.ArrayLike, npt.ArrayLike]
#: one FRF element checked (:func:`check_frf`)
FrfItem: TypeAlias = tuple[int, int, FloatArray, FloatArray]
#: per FRF element: values (N,) and two gradients (N, ...) (:func:`_model_frf`, :func:`_eq5`)
FrfRows: TypeAlias = tuple[FloatArray, FloatArray, FloatArray]


def as_array_like(A: Matrix) -> npt.ArrayLike:
    """A dense or sparse matrix as an array_like (sparse ones densified)."""
    return cast(Any, A).toarray() if sp.issparse(A) else A


def check_matrix(A: Matrix, field_name: str, n: int | None = None) -> FloatArray:
    """``A`` as a dense, non-empty, symmetric (to 1e-9 relative) square matrix, ``n x n`` when
    ``n`` is given; returned exactly symmetric, ``(A + A^T) / 2``."""
    A = require_numeric(as_array_like(A), field_name, "matrix")
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.size == 0:
        raise FieldError(field_name, f"must be a non-empty square matrix, got shape {A.shape}")
    if n is not None and A.shape[0] != n:
        raise FieldError(field_name, f"must be {n}x{n} like the other blocks, got {A.shape}")
    if np.abs(A - A.T).max() > 1e-9 * max(np.abs(A).max(), 1e-300):
        raise FieldError(field_name, "must be symmetric")
    return (A + A.T) / 2.0


def block_list(blocks: object, name: str) -> list[Matrix]:
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


def check_blocks(blocks: object, name: str, n: int | None = None) -> list[FloatArray]:
    """The blocks checked: symmetric, all n x n (the first one's size when ``n`` is None)."""
    out: list[FloatArray] = []
    for k, B in enumerate(block_list(blocks, name)):
        out.append(check_matrix(B, f"{name}[{k}]", n))
        n = out[0].shape[0]
    return out


def check_shapes(shapes: npt.ArrayLike, field_name: str, n: int | None = None) -> FloatArray:
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


def check_indices(value: object, count: int, field_name: str) -> IntArray:
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


def check_mode_indices(value: npt.ArrayLike | None, count: int, n_modes: int) -> IntArray | None:
    """``mode_indices``: ``count`` distinct model mode numbers in [0, n_modes), or None."""
    if value is None:
        return None
    idx = check_indices(value, n_modes, "mode_indices")
    if idx.size != count:
        raise FieldError(
            "mode_indices", f"must give one model mode per measured mode ({count}), got {idx.size}"
        )
    if np.unique(idx).size != idx.size:
        raise FieldError("mode_indices", "each model mode at most once")
    return idx


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


def check_frf(frf: FrfElement | Sequence[FrfElement] | None, n: int) -> list[FrfItem]:
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
