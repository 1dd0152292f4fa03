import numpy as np
import pytest


def _schur_error_bound(S) -> float:
    """Relative error bound of a Riccati solution from the Schur method, and of its residual.

    The method computes an orthonormal basis [U11; U21] of the stable invariant subspace to
    round-off (~ n eps) and returns S = U21 U11^-1: the error is amplified by the condition
    number of U11 (Laub 1979; Petkov, Christov & Konstantinov, "Numerical Methods for Linear
    Control Systems", 1991), which follows from S itself: the basis is [I; S] (I + S^2)^-1/2,
    so kappa(U11) = sqrt(1 + s_max^2) / sqrt(1 + s_min^2).  The relative residual (rho_c, rho_d
    of :mod:`flexsat.control.lqr`) adds its own evaluation round-off, <= 3 n eps of the terms
    (three products of inner length <= n in the quadratic term):
    n eps (kappa(U11) + 3).  This is the spread python-control's solution shows as well.
    """
    s = np.linalg.svd(np.asarray(S, dtype=float), compute_uv=False)
    return len(s) * np.finfo(float).eps * (np.hypot(1.0, s[0]) / np.hypot(1.0, s[-1]) + 3.0)


@pytest.fixture(scope="session")
def schur_error_bound():
    return _schur_error_bound
