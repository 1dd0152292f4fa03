"""Dynamic triangulation of targets from calibrated stereo cameras, with the camera
uncertainty of a calibration carried into the point covariance.

Att. 6 (James & Junkins 1989, in Junkins, Pollock & Rahman 1990) eqs. (34)–(37), with the camera
model of :mod:`flexsat.identify.photogrammetry.camera`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from flexsat.identify.photogrammetry.calibration import CalibrationResult
from flexsat.identify.photogrammetry.camera import (
    CAMERA_PARAMETERS,
    Camera,
    check_cameras,
    project_vector,
)
from flexsat.input_checks import (
    FieldError,
    require_numeric,
    require_positive,
)
from flexsat.units import FloatArray

__all__ = [
    "triangulate",
]


def _linear_guess(cams: Sequence[Camera], uv: FloatArray) -> FloatArray:
    """Distortion-free linear triangulation; uv (M, K, 2) -> (K, 3)."""
    k = uv.shape[1]
    a = np.zeros((k, 3, 3))
    b = np.zeros((k, 3))
    for j, cam in enumerate(cams):
        c = cam.matrix
        pos = np.asarray(cam.position)
        s = cam.focal_sign
        fx, fy = cam.fx, cam.fy
        assert fx is not None and fy is not None  # __post_init__ sets both (from f if given)
        for axis, (f, off) in enumerate(((fx, cam.x0), (fy, cam.y0))):
            rows = (uv[j, :, axis] - off)[:, None] * c[2] - s * f * c[axis]  # (K, 3)
            a += rows[:, :, None] * rows[:, None, :]
            b += rows * (rows @ pos)[:, None]
    return np.asarray(np.linalg.solve(a, b[..., None])[..., 0], dtype=float)


def _camera_factor(camera_covariance: CalibrationResult | npt.ArrayLike, m_cam: int) -> FloatArray:
    """``L`` with ``L L^T`` = the ``(14 M, 14 M)`` camera covariance, one column per direction.

    The eigenvectors are taken of the correlation matrix, not of the covariance itself, so the
    rank cut does not depend on the units (metres, radians, 1/m^2 for k1, ...).
    """
    n = len(CAMERA_PARAMETERS) * m_cam
    if isinstance(camera_covariance, CalibrationResult):
        if len(camera_covariance.cameras) != m_cam:
            raise FieldError(
                "camera_covariance",
                "the calibration has "
                f"{len(camera_covariance.cameras)} cameras, triangulate got {m_cam}",
            )
        cov = camera_covariance.full_camera_covariance()
    else:
        cov = require_numeric(camera_covariance, "camera_covariance")
        if cov.shape != (n, n):
            raise FieldError(
                "camera_covariance",
                f"must be a CalibrationResult or a ({n}, {n}) "
                f"matrix over CAMERA_PARAMETERS of each of the {m_cam} cameras, got "
                f"shape {cov.shape}",
            )
    scale = float(np.max(np.abs(cov))) if cov.size else 0.0
    if not np.allclose(cov, cov.T, rtol=0.0, atol=1e-10 * scale):
        raise FieldError("camera_covariance", "must be symmetric")
    if np.any(np.diag(cov) < -1e-12 * scale):
        raise FieldError(
            "camera_covariance",
            f"must be positive semi-definite (diagonal entry {np.min(np.diag(cov)):.3g})",
        )
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    live = np.flatnonzero(std > 0)
    corr = cov[np.ix_(live, live)] / np.outer(std[live], std[live])
    lam, vec = np.linalg.eigh(corr)
    # roundoff leaves eigenvalues of order 1e-15 n of either sign on a singular correlation
    if lam.size and lam[0] < -1e-9 * max(lam[-1], 1.0):
        raise FieldError(
            "camera_covariance",
            f"must be positive semi-definite (correlation eigenvalue {lam[0]:.3g})",
        )
    keep = lam > 1e-12 * max(lam[-1], 1.0) if lam.size else np.zeros(0, bool)
    factor = np.zeros((n, int(np.sum(keep))))
    factor[live] = std[live, None] * vec[:, keep] * np.sqrt(lam[keep])
    return factor


def triangulate(
    cameras: Sequence[Camera],
    centroids: npt.ArrayLike,
    pixel_sigma: npt.ArrayLike,
    iterations: int = 10,
    camera_covariance: CalibrationResult | npt.ArrayLike | None = None,
) -> tuple[FloatArray, FloatArray]:
    r"""Dynamic triangulation with calibrated cameras (Att. 6 eqs. (34)–(37); Att. 8: 4
    equations, 3 unknowns per point for two cameras).

    Parameters
    ----------
    cameras : sequence of Camera
        ``M >= 2`` cameras at their calibrated (nominal) values.
    centroids : array_like (M, ..., 2)
        Image coordinates (e.g. ``(M, T, N, 2)`` for ``T`` video fields of ``N`` targets).
    pixel_sigma : float or array_like (M,)
        Standard deviation of each image coordinate (observation units).
    iterations : int
        Gauss-Newton iterations at most.
    camera_covariance : CalibrationResult or array_like (14 M, 14 M), optional
        Uncertainty of the camera parameters: a :func:`calibrate` result (its
        :meth:`CalibrationResult.full_camera_covariance`) or a covariance over the stacked
        :data:`CAMERA_PARAMETERS` vectors (may be singular: fixed or tied parameters).

    Returns
    -------
    points : ndarray (..., 3)
    covariance : ndarray (..., 3, 3)
        Linearised covariance of each point.

    Notes
    -----
    Without ``camera_covariance`` the cameras are exact: weighted least squares on the 2M
    image equations, covariance :math:`(J_p^T W J_p)^{-1}`, :math:`W = \Sigma_{uv}^{-1}`.

    With it, Att. 6 keeps the camera parameters c as weighted measurements (eqs. (34)–(35):
    observations :math:`\{u, v, c_{meas}\}`, unknowns :math:`\{p, c\}`, final covariance
    :math:`(A^T W A)^{-1}`). Eliminating c from those normal equations (Schur complement and
    the Woodbury identity) leaves least squares on the image equations alone with the
    observation covariance

    .. math:: S = \Sigma_{uv} + J_c \Sigma_c J_c^T ,

    estimate :math:`\hat p = \arg\min r^T S^{-1} r` and covariance
    :math:`(J_p^T S^{-1} J_p)^{-1}`, the p-block of Att. 6's :math:`(A^T W A)^{-1}`
    (``tests/identify/test_triangulation.py`` solves eqs. (34)–(37) directly and compares).
    This form is solved here because it needs 3 unknowns per point instead of 3 + 14 M and
    accepts a singular :math:`\Sigma_c`. It equals the first-order propagation
    :math:`J_p^+ S J_p^{+T}` with the gain :math:`J_p^+ = (J_p^T S^{-1} J_p)^{-1} J_p^T S^{-1}`;
    with the pixel-only gain (weights :math:`\Sigma_{uv}^{-1}`) the same propagation would be
    the covariance of the pixel-weighted estimate, which is no smaller (Gauss-Markov).
    :math:`J_c \Sigma_c J_c^T` is formed as :math:`(J_c L)(J_c L)^T`, :math:`L L^T =
    \Sigma_c`, by central differences of 1e-3 standard deviation along each column of L.

    The propagation is first order. On the two-camera rig of the tests, a calibration with
    x0, y0 held fixed (attitude sigma 7e-4 rad) gives Monte Carlo errors consistent with the
    covariance (mean NEES 3.01 for 3); with Att. 8's nine parameters the two views trade x0
    against attitude (sigma 1e-2 rad) and the errors exceed the prediction by about 15 %
    (mean NEES 3.5; one run of 300 trials, not a test), which vanishes when the same
    covariance is scaled by 0.1.

    The returned covariance is each point's own (marginal). All points and video fields share
    the one camera error, so their errors are correlated: points i, j have cross-covariance
    :math:`G_i J_{c,i} \Sigma_c J_{c,j}^T G_j^T`, :math:`G = J_p^+`. The displacement of a
    target between fields largely cancels the common part, so the marginal covariance
    overstates the uncertainty of displacements.
    """
    cams = check_cameras(cameras, minimum=2)
    m_cam = len(cams)
    uv = require_numeric(centroids, "centroids")
    if uv.ndim < 2 or uv.shape[0] != m_cam or uv.shape[-1] != 2:
        raise FieldError(
            "centroids", f"must have shape (M, ..., 2) with M = {m_cam} cameras, got {uv.shape}"
        )
    sig = require_positive(pixel_sigma, "pixel_sigma").reshape(-1)
    if sig.size not in (1, m_cam):
        raise FieldError("pixel_sigma", f"must be a scalar or one value per camera, got {sig.size}")
    factor = None if camera_covariance is None else _camera_factor(camera_covariance, m_cam)
    var = np.repeat(np.broadcast_to(sig, (m_cam,)) ** 2, 2)  # (2M,)
    lead = uv.shape[1:-1]
    flat = uv.reshape(m_cam, -1, 2)
    pts = _linear_guess(cams, flat)
    n_par = len(CAMERA_PARAMETERS)
    base = np.concatenate([c.vector() for c in cams])

    def model(p: FloatArray, vec: FloatArray = base) -> FloatArray:
        return np.concatenate(
            [
                project_vector(
                    vec[j * n_par : (j + 1) * n_par], c.euler, c.focal_sign, c.distortion, p
                )[0]
                for j, c in enumerate(cams)
            ],
            axis=1,
        )

    obs = np.concatenate([flat[j] for j in range(m_cam)], axis=1)  # (K, 2M)

    def jacobian(p: FloatArray) -> FloatArray:
        h = 1e-6 * np.maximum(1.0, np.abs(p))
        cols = []
        for a in range(3):
            dp = np.zeros_like(p)
            dp[:, a] = h[:, a]
            cols.append((model(p + dp) - model(p - dp)) / (2 * h[:, a : a + 1]))
        return np.stack(cols, axis=-1)  # (K, 2M, 3)

    def weighted(p: FloatArray, jac: FloatArray) -> FloatArray:
        """S^-1 J_p per point (Notes above)."""
        if factor is None or factor.shape[1] == 0:
            return jac / var[None, :, None]
        # a step of 1e-3 standard deviation: the truncation error (~1e-6 of the effect of one
        # standard deviation) and the roundoff (~eps / 1e-3) are both negligible
        h = 1e-3
        jcl = np.stack(
            [(model(p, base + h * col) - model(p, base - h * col)) / (2 * h) for col in factor.T],
            axis=-1,
        )  # (K, 2M, rank)
        cov = np.einsum("kin,kjn->kij", jcl, jcl) + np.diag(var)
        return np.linalg.solve(cov, jac)

    for _ in range(iterations):
        r = obs - model(pts)
        jac = jacobian(pts)
        jw = weighted(pts, jac)
        normal = np.einsum("kra,krb->kab", jw, jac)
        step = np.linalg.solve(normal, np.einsum("kra,kr->ka", jw, r)[..., None])[..., 0]
        pts = pts + step
        if np.max(np.abs(step)) <= 1e-12 * max(1.0, np.max(np.abs(pts))):
            break
    jac = jacobian(pts)
    normal = np.einsum("kra,krb->kab", weighted(pts, jac), jac)
    cond = np.linalg.cond(normal)
    if np.any(cond > 1e14):
        raise FieldError(
            "centroids",
            "the rays are (nearly) parallel for some points; the "
            "triangulation geometry is singular",
        )
    cov = np.linalg.inv(normal)
    return pts.reshape(lead + (3,)), cov.reshape(lead + (3, 3))
