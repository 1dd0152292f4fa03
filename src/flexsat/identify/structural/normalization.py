"""Modal normalisation factors from measured FRF elements by linear least squares
(Creamer-Junkins, Att. 7 Eqs. 5-6 of Junkins, Pollock & Rahman 1990)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from flexsat.identify.structural.validation import (
    FrfElement,
    check_frf,
    check_shapes,
)
from flexsat.input_checks import (
    FieldError,
    require_finite,
    require_numeric,
)
from flexsat.units import FloatArray

__all__ = [
    "fit_modal_normalization",
]


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
    psi = check_shapes(shapes, "shapes")
    w_r = require_finite(omegas, "omegas", "rad/s")
    if w_r.shape != (psi.shape[1],) or np.any(w_r <= 0):
        raise FieldError(
            "omegas", f"must be {psi.shape[1]} values > 0 rad/s (one per shape), got {omegas!r}"
        )
    items = check_frf(frf, psi.shape[0])
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
