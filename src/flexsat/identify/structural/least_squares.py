"""Weighted linear least squares for substructure scalings, with the identifiability checks
of the structural identification (a parameter without modal energy, an ill-conditioned
system) as errors naming the field."""

from __future__ import annotations

import numpy as np

from flexsat.input_checks import (
    FieldError,
)
from flexsat.units import FloatArray

__all__ = [
    "solve_scalings",
]


def solve_scalings(
    A: FloatArray, b: FloatArray, weights: FloatArray, name: str
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    r"""Weighted least squares ``min ||W (A x - b)||``, ``W = diag(weights)``, for the scalings
    named ``name``; the columns of ``W A`` are equilibrated (unit 2-norm) before the solve.

    Returns ``x``; ``(A^T W^2 A)^{-1}`` (the covariance of ``x`` for unit-variance weighted rows:
    multiply by the residual variance ``r^T r / dof`` when the weights are only relative);
    the weighted residuals ``W (b - A x)``;
    and the degrees of freedom ``rows - columns``.  Refused by name: fewer rows than
    parameters, a parameter whose column is zero (it has no modal energy in the data), or
    condition number of the equilibrated ``W A`` above 1e10 (not identifiable).
    """
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
