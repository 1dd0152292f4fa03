"""Stereo photogrammetry: collinearity camera model, static calibration, dynamic triangulation.

Sources (Att. 6 and 8 of Junkins, Pollock & Rahman 1990):

* Att. 6 (James & Junkins 1989), eqs. (22)–(29): ``u = u0 + du + f_u (C1.d)/(C3.d)`` with a
  (1,2,3) Euler matrix ``C = R3(t3) R2(t2) R1(t1)``, separate ``f_u, f_v`` and Brown distortion.
* Att. 8 (Junkins & James 1988), eq. (1): ``x = x0 - f (C1.d)/(C3.d)`` with the 3-2-1 matrix
  ``C = R1(psi) R2(theta) R3(phi)``, angles stored in the order ``(phi, theta, psi)``.

Both conventions are supported through ``Camera.euler`` (``"321"`` or ``"123"``) and
``Camera.focal_sign`` (``-1`` as in Att. 8, ``+1`` as in Att. 6).  ``d = C (p - c)`` is the
object point in camera axes.

Distortion is Brown's first-order model (the printed eqs. (25)–(26) are garbled),
evaluated on the *ideal* centred image coordinates ``ub = s fx d1/d3``, ``vb = s fy d2/d3``:

    du = ub (k1 r^2 + k2 r^4) + p1 (r^2 + 2 ub^2) + 2 p2 ub vb
    dv = vb (k1 r^2 + k2 r^4) + 2 p1 ub vb + p2 (r^2 + 2 vb^2)

``Camera(distortion="printed")`` switches to the as-printed Att. 6 form.  All image quantities
(x0, y0, fx, fy, centroids, sigmas) are in one length unit of the focal plane (e.g. metres);
``simulate_centroids`` converts to pixels only to quantize.

OpenCV (``cv2.projectPoints``) applies the same Brown model to the normalised coordinates
``x' = d1/d3, y' = d2/d3`` before the camera matrix, so for square pixels (``fx = fy = f``,
sign ``s``) the two agree exactly with camera matrix ``[[s f, 0, x0], [0, s f, y0], [0, 0, 1]]``,
``distCoeffs = (k1 f^2, k2 f^4, s p2 f, s p1 f, 0)`` (in the u equation OpenCV's p1
multiplies ``2 x'y'`` and ours ``r^2 + 2 ub^2``: the decentering pair is swapped),
``rvec = Rodrigues(C)`` and ``tvec = -C c``; a negative ``s f`` is accepted, and the Att. 8
"-f" camera has its points at negative depth (checked against OpenCV 5.0 in
``tests/identify/test_photogrammetry.py``).  With ``fx != fy`` our
``r^2 = fx^2 x'^2 + fy^2 y'^2`` is not a multiple of OpenCV's ``x'^2 + y'^2`` and no
distortion coefficients reproduce it; without distortion the camera matrix
``diag(s fx, s fy, 1)`` (plus the principal point) still does.  The printed Att. 6 form has no
OpenCV counterpart.

Calibration (resection) follows Att. 8's counting: with the datum of §3.3 (point ``i0`` at the
origin, point ``i1`` on the X axis, point ``i2`` in the XY plane) the unknowns are
``3N - 6 + p M`` (``p`` free parameters per camera, ``M`` cameras) against ``2 M N`` image
equations, i.e. ``4N`` equations and ``3N + 12`` unknowns for two 9-parameter cameras, so
``N >= 12``.  The scale left free by the datum is fixed by a known distance (``scale``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix

from flexsat.input_checks import (
    FieldError,
    require_finite,
    require_numeric,
    require_positive,
    require_positive_scalar,
    require_scalar,
)
from flexsat.units import FloatArray

__all__ = [
    "look_at",
    "Camera",
    "CalibrationResult",
    "CAMERA_PARAMETERS",
    "DEFAULT_FREE",
    "FIELD_SIZE_PX",
    "FIELD_RATE_HZ",
    "rotation_matrix",
    "euler_angles",
    "project",
    "simulate_centroids",
    "calibration_counts",
    "calibrate",
    "triangulate",
]

#: Video field of the TAMU sensor (Att. 6/8/10): 320 x 244 pixels at 200 fields per second.
FIELD_SIZE_PX = (320, 244)
FIELD_RATE_HZ = 200.0

#: Order of a camera's parameter vector.
CAMERA_PARAMETERS = (
    "xc",
    "yc",
    "zc",
    "a1",
    "a2",
    "a3",
    "x0",
    "y0",
    "fx",
    "fy",
    "k1",
    "k2",
    "p1",
    "p2",
)
#: Att. 8's nine calibration unknowns per camera (``"f"`` ties ``fx = fy``).
DEFAULT_FREE = ("xc", "yc", "zc", "a1", "a2", "a3", "x0", "y0", "f")
_FREE_NAMES = set(CAMERA_PARAMETERS) | {"f"}


# ----------------------------------------------------------------------------------------------
# rotations
# ----------------------------------------------------------------------------------------------
def _r1(a: float) -> FloatArray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])


def _r2(a: float) -> FloatArray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def _r3(a: float) -> FloatArray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def _check_euler(euler: str, field_name: str = "euler") -> str:
    if euler not in ("321", "123"):
        raise FieldError(
            field_name,
            "must be '321' (Att. 8: C = R1(psi) R2(theta) R3(phi), "
            f"angles (phi, theta, psi)) or '123' (Att. 6: C = R3(t3) R2(t2) R1(t1), "
            f"angles (t1, t2, t3)), got {euler!r}",
        )
    return euler


def rotation_matrix(angles: npt.ArrayLike, euler: str = "321") -> FloatArray:
    """World-to-camera direction cosine matrix ``C`` (passive rotations, radians).

    ``"321"``: ``angles = (phi, theta, psi)``, ``C = R1(psi) R2(theta) R3(phi)`` (Att. 8).
    ``"123"``: ``angles = (t1, t2, t3)``, ``C = R3(t3) R2(t2) R1(t1)`` (Att. 6).
    """
    _check_euler(euler)
    a = require_finite(angles, "angles").reshape(-1)
    if a.size != 3:
        raise FieldError("angles", f"must hold 3 Euler angles, got {a.size}")
    if euler == "321":
        return _r1(a[2]) @ _r2(a[1]) @ _r3(a[0])
    return _r3(a[2]) @ _r2(a[1]) @ _r1(a[0])


def euler_angles(matrix: npt.ArrayLike, euler: str = "321") -> FloatArray:
    """Inverse of :func:`rotation_matrix` (middle angle in [-pi/2, pi/2])."""
    _check_euler(euler)
    c = require_finite(matrix, "matrix")
    if c.shape != (3, 3):
        raise FieldError("matrix", f"must be 3x3, got shape {c.shape}")
    if not np.allclose(c @ c.T, np.eye(3), atol=1e-8) or np.linalg.det(c) <= 0:
        raise FieldError("matrix", "must be a proper rotation (orthonormal, det +1)")
    if euler == "321":
        theta = -math.asin(float(np.clip(c[0, 2], -1.0, 1.0)))
        phi = math.atan2(c[0, 1], c[0, 0])
        psi = math.atan2(c[1, 2], c[2, 2])
        return np.array([phi, theta, psi])
    t2 = math.asin(float(np.clip(c[2, 0], -1.0, 1.0)))
    t1 = math.atan2(-c[2, 1], c[2, 2])
    t3 = math.atan2(-c[1, 0], c[0, 0])
    return np.array([t1, t2, t3])


def look_at(
    position: npt.ArrayLike, target: npt.ArrayLike, euler: str = "321", focal_sign: int = -1
) -> FloatArray:
    """Euler angles of a camera at ``position`` whose optical axis passes through ``target``,
    image x axis horizontal (normal to the world Y axis, which must not be the line of sight).

    The camera z axis points at the scene for ``focal_sign = +1`` (Att. 6, "+f") and away from
    it for ``-1`` (Att. 8, "-f").
    """
    pos = require_finite(position, "position").reshape(-1)
    z = require_finite(target, "target").reshape(-1) - pos
    if pos.size != 3 or z.size != 3 or np.linalg.norm(z) == 0:
        raise FieldError("target", "position and target must be distinct 3-vectors")
    z = z / np.linalg.norm(z) * (1 if focal_sign > 0 else -1)
    x = np.cross([0.0, 1.0, 0.0], z)
    if np.linalg.norm(x) < 1e-9:
        raise FieldError(
            "target",
            "the line of sight is along the world Y axis (the image x axis "
            "is taken normal to Y); aim the camera off the vertical",
        )
    x /= np.linalg.norm(x)
    return euler_angles(np.vstack([x, np.cross(z, x), z]), euler)


# ----------------------------------------------------------------------------------------------
# camera
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Camera:
    """Exterior (position, Euler attitude) and interior (x0, y0, fx, fy, Brown k1, k2, p1, p2)
    orientation of one camera.  Give ``f`` for square pixels or ``fx`` and ``fy``."""

    position: Sequence[float] | FloatArray  # stored as a tuple of 3 floats
    angles: Sequence[float] | FloatArray  # stored as a tuple of 3 floats
    f: float | None = None
    fx: float | None = None
    fy: float | None = None
    x0: float = 0.0
    y0: float = 0.0
    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    euler: str = "321"
    focal_sign: int = -1
    distortion: str = "brown"

    def __post_init__(self) -> None:
        pos = require_finite(self.position, "position").reshape(-1)
        if pos.size != 3:
            raise FieldError("position", f"must hold 3 coordinates, got {pos.size}")
        ang = require_finite(self.angles, "angles").reshape(-1)
        if ang.size != 3:
            raise FieldError("angles", f"must hold 3 Euler angles, got {ang.size}")
        _check_euler(self.euler)
        if self.focal_sign not in (1, -1):
            raise FieldError(
                "focal_sign",
                f"must be +1 (Att. 6, '+f') or -1 (Att. 8, '-f'), got {self.focal_sign!r}",
            )
        if self.distortion not in ("brown", "printed"):
            raise FieldError("distortion", f"must be 'brown' or 'printed', got {self.distortion!r}")
        if self.f is not None:
            if self.fx is not None or self.fy is not None:
                raise FieldError("f", "give either f (square pixels) or fx and fy, not both")
            f = require_positive_scalar(self.f, "f")
            fx = fy = f
        else:
            if self.fx is None or self.fy is None:
                raise FieldError("f", "a focal length is required (f, or both fx and fy)")
            fx = require_positive_scalar(self.fx, "fx")
            fy = require_positive_scalar(self.fy, "fy")
        object.__setattr__(self, "position", tuple(float(v) for v in pos))
        object.__setattr__(self, "angles", tuple(float(v) for v in ang))
        object.__setattr__(self, "f", None)
        object.__setattr__(self, "fx", fx)
        object.__setattr__(self, "fy", fy)
        for name in ("x0", "y0", "k1", "k2", "p1", "p2"):
            object.__setattr__(self, name, require_scalar(getattr(self, name), name))

    @property
    def matrix(self) -> FloatArray:
        return rotation_matrix(self.angles, self.euler)

    def vector(self) -> FloatArray:
        """Parameters in the order of :data:`CAMERA_PARAMETERS`."""
        return np.array(
            [
                *self.position,
                *self.angles,
                self.x0,
                self.y0,
                self.fx,
                self.fy,
                self.k1,
                self.k2,
                self.p1,
                self.p2,
            ]
        )

    def with_vector(self, vec: npt.ArrayLike) -> Camera:
        v = np.asarray(vec, dtype=float)
        return dataclasses.replace(
            self,
            position=v[0:3],
            angles=v[3:6],
            x0=v[6],
            y0=v[7],
            f=None,
            fx=v[8],
            fy=v[9],
            k1=v[10],
            k2=v[11],
            p1=v[12],
            p2=v[13],
        )


def _project_vec(
    vec: FloatArray, euler: str, sign: float, form: str, pts: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Projection from a raw parameter vector (no validation); pts (K, 3) -> (K, 2)."""
    c = rotation_matrix(vec[3:6], euler)
    d = (pts - vec[0:3]) @ c.T
    depth = d[:, 2]
    ub = sign * vec[8] * d[:, 0] / depth
    vb = sign * vec[9] * d[:, 1] / depth
    k1, k2, p1, p2 = vec[10:14]
    r2 = ub * ub + vb * vb
    if form == "brown":
        radial = k1 * r2 + k2 * r2 * r2
        du = ub * radial + p1 * (r2 + 2 * ub * ub) + 2 * p2 * ub * vb
        dv = vb * radial + 2 * p1 * ub * vb + p2 * (r2 + 2 * vb * vb)
    else:  # Att. 6 eqs. (25)-(26) as printed
        du = ub * k1 * r2 + p1 * (r2 + 2 * ub * ub * vb)
        dv = vb * k1 * r2 + p1 * (2 * ub * ub * vb) + p2 * (r2 + 2 * vb * vb)
    return np.stack([vec[6] + ub + du, vec[7] + vb + dv], axis=-1), depth


def _check_points(points: npt.ArrayLike, field_name: str = "points") -> FloatArray:
    p = require_numeric(points, field_name)
    if p.ndim == 0 or p.shape[-1] != 3:
        raise FieldError(field_name, f"last axis must hold (x, y, z), got shape {p.shape}")
    return p


def project(camera: Camera, points: npt.ArrayLike) -> FloatArray:
    """Image coordinates ``(u, v)`` of object points, shape ``(..., 3) -> (..., 2)``."""
    if not isinstance(camera, Camera):
        raise FieldError("camera", f"must be a Camera, got {type(camera).__name__}")
    p = _check_points(points)
    flat = p.reshape(-1, 3)
    uv, depth = _project_vec(
        camera.vector(), camera.euler, camera.focal_sign, camera.distortion, flat
    )
    if np.any(np.abs(depth) < 1e-12):
        raise FieldError("points", "a point lies in the camera's focal plane (zero depth)")
    return uv.reshape(p.shape[:-1] + (2,))


# ----------------------------------------------------------------------------------------------
# simulation
# ----------------------------------------------------------------------------------------------
def simulate_centroids(
    cameras: Sequence[Camera],
    points: npt.ArrayLike,
    pixel_size: npt.ArrayLike,
    noise_px: float = 0.0,
    quantize: bool = True,
    seed: int | np.random.Generator | None = None,
    field_px: tuple[float, float] | None = FIELD_SIZE_PX,
) -> FloatArray:
    """Simulated image centroids, shape ``(M, ..., 2)`` for ``M`` cameras and points ``(..., 3)``.

    Gaussian noise of ``noise_px`` pixels (standard deviation) is added, then, with
    ``quantize``, each centroid is snapped to the centre of the pixel it falls in (pixel edges at
    integer multiples of ``pixel_size`` from the detector centre).  Centroids outside the
    ``field_px = (width, height)`` detector (default 320 x 244, centred) are NaN; pass
    ``field_px=None`` for an unbounded detector.  A time history of points ``(T, N, 3)`` sampled
    at :data:`FIELD_RATE_HZ` gives one field per time step.
    """
    cams = _check_cameras(cameras)
    p = _check_points(points)
    size = require_positive(pixel_size, "pixel_size").reshape(-1)
    if size.size not in (1, 2):
        raise FieldError("pixel_size", f"must be a scalar or (sx, sy), got {size.size} values")
    size = np.broadcast_to(size, (2,))
    noise = require_scalar(noise_px, "noise_px")
    if noise < 0:
        raise FieldError("noise_px", f"must be >= 0, got {noise_px!r}")
    rng = np.random.default_rng(seed)
    out = np.stack([project(cam, p) for cam in cams])
    if noise > 0:
        out = out + rng.normal(0.0, noise, out.shape) * size
    if quantize:
        out = (np.floor(out / size) + 0.5) * size
    if field_px is not None:
        fw = require_positive(field_px, "field_px").reshape(-1)
        if fw.size != 2:
            raise FieldError("field_px", f"must be (width, height) in pixels, got {field_px!r}")
        half = 0.5 * fw * size
        outside = np.any(np.abs(out) > half, axis=-1)
        out[outside] = np.nan
    return out


# ----------------------------------------------------------------------------------------------
# calibration
# ----------------------------------------------------------------------------------------------
def _check_cameras(
    cameras: Camera | Sequence[Camera], field_name: str = "cameras", minimum: int = 1
) -> list[Camera]:
    if isinstance(cameras, Camera):
        cameras = [cameras]
    cams = list(cameras)
    if len(cams) < minimum:
        raise FieldError(field_name, f"at least {minimum} cameras are needed, got {len(cams)}")
    for j, cam in enumerate(cams):
        if not isinstance(cam, Camera):
            raise FieldError(f"{field_name}[{j}]", f"must be a Camera, got {type(cam).__name__}")
    return cams


def calibration_counts(
    n_points: int, n_cameras: int = 2, params_per_camera: int = 9
) -> dict[str, int]:
    """Att. 8 counting: ``2 M N`` image equations, ``3N - 6 + p M`` unknowns after the datum.

    For ``M = 2``, ``p = 9``: 4N equations, 3N + 12 unknowns, ``N >= 12``; ``p = 10``
    (separate fx, fy) gives ``N >= 14``.  The scale constraint is one more equation and is not
    counted towards the minimum (it removes the scale freedom the datum leaves).
    """
    m, p = int(n_cameras), int(params_per_camera)
    if 2 * m - 3 <= 0:
        raise FieldError("n_cameras", f"calibration needs at least 2 cameras, got {n_cameras}")
    n_min = max(3, math.ceil((p * m - 6) / (2 * m - 3)))
    return {
        "equations": 2 * m * int(n_points),
        "unknowns": 3 * int(n_points) - 6 + p * m,
        "min_points": n_min,
    }


@dataclass
class CalibrationResult:
    """Output of :func:`calibrate`."""

    cameras: list[Camera]
    targets: FloatArray
    covariance: FloatArray  # over the unknowns, ordered as ``names``
    names: list[str]  # e.g. "cam0.xc", "target3.y"
    sigma0_squared: float  # residual variance factor (1 if the weights are right)
    counts: dict[str, int]
    residuals_px: FloatArray = field(repr=False)  # image residuals, observation units
    result: Any = field(repr=False, default=None)  # scipy's OptimizeResult

    def std(self, name: str) -> float:
        return float(np.sqrt(self.covariance[self.names.index(name)][self.names.index(name)]))

    def camera_covariance(self, j: int, params: Sequence[str] | None = None) -> FloatArray:
        """Covariance block of camera ``j``'s free parameters (``params`` order if given)."""
        sel = [k for k, n in enumerate(self.names) if n.startswith(f"cam{j}.")]
        if params is not None:
            sel = [self.names.index(f"cam{j}.{p}") for p in params]
        return self.covariance[np.ix_(sel, sel)]

    def full_camera_covariance(self) -> FloatArray:
        """Covariance of the stacked camera vectors, ``(14 M, 14 M)``.

        Camera ``j`` occupies rows ``14 j .. 14 j + 13`` in :data:`CAMERA_PARAMETERS` order (the
        layout :func:`triangulate` takes); a calibrated ``f`` enters both ``fx`` and ``fy``
        (the tie ``fx = fy``), parameters held fixed have zero rows and columns, and the
        correlations between cameras are kept.
        """
        n_par = len(CAMERA_PARAMETERS)
        sel = [k for k, n in enumerate(self.names) if n.startswith("cam")]
        tie = np.zeros((n_par * len(self.cameras), len(sel)))
        for col, k in enumerate(sel):
            cam, name = self.names[k].split(".")
            for target in ("fx", "fy") if name == "f" else (name,):
                tie[int(cam[3:]) * n_par + CAMERA_PARAMETERS.index(target), col] = 1.0
        return tie @ self.covariance[np.ix_(sel, sel)] @ tie.T


def _free_indices(free: Sequence[str]) -> tuple[str, ...]:
    free = tuple(free)
    for name in free:
        if name not in _FREE_NAMES:
            raise FieldError(
                "free", f"unknown camera parameter {name!r}; choose from {sorted(_FREE_NAMES)}"
            )
    if len(set(free)) != len(free):
        raise FieldError("free", f"repeated parameter names in {free}")
    if "f" in free and ("fx" in free or "fy" in free):
        raise FieldError("free", "'f' ties fx = fy; do not combine it with 'fx' or 'fy'")
    return free


def _collinear(pts: FloatArray, tol: float = 1e-9) -> bool:
    centred = pts - pts.mean(axis=0)
    s = np.linalg.svd(centred, compute_uv=False)
    return s[0] == 0 or s[1] <= tol * s[0]


def calibrate(
    observations: npt.ArrayLike,
    initial_cameras: Sequence[Camera],
    target_guess: npt.ArrayLike,
    datum: tuple[int, int, int] | None = (0, 1, 2),
    scale: Sequence[float] | None = None,
    sigma: float = 1.0,
    free: Sequence[str] = DEFAULT_FREE,
    target_sigma: npt.ArrayLike | None = None,
    camera_sigma: Mapping[str, float] | Sequence[Mapping[str, float]] | None = None,
    max_nfev: int | None = None,
) -> CalibrationResult:
    """Static calibration (resection) of ``M >= 2`` cameras and ``N`` targets.

    observations: ``(M, N, 2)`` image centroids; NaN (both coordinates) where a camera does not
        see a target (:func:`simulate_centroids` marks targets outside the field so).  Every
        target must be seen by two cameras (one with ``target_sigma``).
    initial_cameras: ``M`` :class:`Camera` starting values (conventions are kept).
    target_guess: ``(N, 3)`` starting target positions, already in the datum frame.
    datum: ``(i0, i1, i2)``: target ``i0`` fixed at the origin, ``i1`` on the X axis
        (y = z = 0), ``i2`` in the XY plane (z = 0) (Att. 8 §3.3).  The guess must satisfy it.
    scale: ``(i, j, distance)`` or ``(i, j, distance, sigma_distance)``: a known distance
        between targets, a weighted equation (default sigma ``1e-6 * distance``).  Required.
    sigma: standard deviation of each image coordinate (observation units); residuals are
        weighted by ``1/sigma`` and the covariance is ``s0^2 (J^T J)^-1`` with
        ``s0^2 = sum(r^2)/(m - n)``.
    free: calibrated camera parameters (default Att. 8's nine; add "fx", "fy" in place of "f",
        or "k1", "k2", "p1", "p2"); the others stay at their initial values.
    target_sigma: optional a-priori standard deviation of the measured target positions
        (scalar, ``(N,)`` or ``(N, 3)``): ``target_guess`` then enters as weighted measurements
        (Att. 6 eq. (30)), and ``datum``/``scale`` may be ``None``.
    camera_sigma: optional a-priori standard deviations of the camera parameters, a mapping
        ``{parameter: sigma}`` for every camera or a list of such mappings, one per camera
        (parameters among ``free``): ``initial_cameras`` then enter as weighted measurements
        too (Att. 6 eq. (30): with 13 free parameters per camera, 20 targets and two cameras,
        166 measurements for 86 unknowns; ``counts["measurements"]`` and
        ``counts["unknowns_solved"]`` report them).

    Note: the counting rule is necessary, not sufficient.  From image data alone two cameras
    determine only the 7-parameter fundamental matrix plus the structure up to the datum and
    scale, so with Att. 8's nine free parameters per camera (x0, y0 and f both free) two cameras
    leave a residual ambiguity (a projective transformation keeps the images; 15 - 7 datum/scale
    - 2 per metric camera = 4 free directions for M = 2, none only from M = 4); :func:`calibrate`
    then reports a singular normal matrix.  Add a-priori target positions (``target_sigma``, as
    Att. 6 does), fix x0, y0 (``free`` without them; the optical axes must then not intersect,
    or the two focal lengths stay undetermined), or use four or more cameras.

    Solved by :func:`scipy.optimize.least_squares` (trust region, finite differences with the
    block-sparse ``jac_sparsity`` pattern: camera ``j``'s parameters reach only camera ``j``'s
    rows, target ``i``'s coordinates only target ``i``'s rows).
    """
    cams = _check_cameras(initial_cameras, "initial_cameras", minimum=2)
    m_cam = len(cams)
    obs = _observations(observations)
    targets = require_numeric(target_guess, "target_guess")
    if targets.ndim != 2 or targets.shape[1] != 3:
        raise FieldError("target_guess", f"must have shape (N, 3), got {targets.shape}")
    n_pts = targets.shape[0]
    if obs.shape != (m_cam, n_pts, 2):
        raise FieldError(
            "observations",
            f"must have shape (M, N, 2) = ({m_cam}, {n_pts}, 2) "
            f"for {m_cam} cameras and {n_pts} targets, got {obs.shape}",
        )
    free = _free_indices(free)
    sig = require_positive_scalar(sigma, "sigma")
    seen = np.isfinite(obs[..., 0])  # (M, N)
    _check_visibility(seen, target_sigma is not None, len(free))

    counts = calibration_counts(n_pts, m_cam, len(free))
    if n_pts < counts["min_points"]:
        raise FieldError(
            "target_guess",
            f"{n_pts} targets are too few: {m_cam} cameras with {len(free)} free "
            f"parameters each need N >= {counts['min_points']} ({counts['equations']} equations "
            f"2MN < {counts['unknowns']} unknowns 3N - 6 + {len(free)}M; Att. 8: 4N vs 3N + 12, "
            f"N >= 12)",
        )
    if _collinear(targets):
        raise FieldError(
            "target_guess",
            "the targets are collinear; calibration needs targets "
            "spread in at least a plane (better in depth too)",
        )

    if target_sigma is not None:
        tsig = require_positive(target_sigma, "target_sigma")
        try:
            tsig = np.broadcast_to(
                tsig.reshape(tsig.shape + (1,) * (tsig.ndim == 1)), (n_pts, 3)
            ).copy()
        except ValueError:
            raise FieldError(
                "target_sigma",
                f"must be a scalar, (N,) or (N, 3) with N = {n_pts}, "
                f"got shape {np.shape(target_sigma)}",
            ) from None
    else:
        tsig = None
    fixed_mask = np.zeros((n_pts, 3), dtype=bool)
    if datum is None and tsig is None:
        raise FieldError(
            "datum",
            "required (i0, i1, i2) unless target_sigma gives a-priori "
            "target positions that fix the frame",
        )
    if datum is not None:
        i0, i1, i2 = _check_datum(datum, targets, n_pts)
        fixed_mask[i0, :] = True
        fixed_mask[i1, 1:] = True
        fixed_mask[i2, 2] = True

    # scale
    if scale is None and tsig is None:
        raise FieldError(
            "scale",
            "a known distance (i, j, distance) is required; the datum "
            "leaves the overall scale undetermined",
        )
    if scale is not None:
        si, sj, sd, ssig = _check_scale(scale, n_pts)

    # unknown vector layout
    tgt_free = np.flatnonzero(~fixed_mask.ravel())
    cam_prior = _camera_prior(camera_sigma, free, m_cam)  # (M * p_cam,), inf = no prior

    base_vecs = [cam.vector() for cam in cams]
    idx = {n: k for k, n in enumerate(CAMERA_PARAMETERS)}
    p_cam = len(free)
    n_unknown = p_cam * m_cam + tgt_free.size

    names = [f"cam{j}.{n}" for j in range(m_cam) for n in free]
    names += [f"target{k // 3}.{'xyz'[k % 3]}" for k in tgt_free]

    def unpack(x: FloatArray) -> tuple[list[FloatArray], FloatArray]:
        vecs = []
        for j in range(m_cam):
            v = base_vecs[j].copy()
            for k, n in enumerate(free):
                val = x[j * p_cam + k]
                if n == "f":
                    v[idx["fx"]] = v[idx["fy"]] = val
                else:
                    v[idx[n]] = val
            vecs.append(v)
        t = targets.ravel().copy()
        t[tgt_free] = x[p_cam * m_cam :]
        return vecs, t.reshape(n_pts, 3)

    x0 = np.empty(n_unknown)
    for j in range(m_cam):
        for k, n in enumerate(free):
            x0[j * p_cam + k] = base_vecs[j][idx["fx" if n == "f" else n]]
    x0[p_cam * m_cam :] = targets.ravel()[tgt_free]

    # image rows of the targets each camera sees (camera by camera, target by target, u then v)
    visible = np.repeat(seen.reshape(-1), 2)
    obs_flat = obs.reshape(-1)[visible]

    def residuals(x: FloatArray) -> FloatArray:
        vecs, t = unpack(x)
        pred = np.stack(
            [
                _project_vec(vecs[j], cams[j].euler, cams[j].focal_sign, cams[j].distortion, t)[0]
                for j in range(m_cam)
            ]
        )
        parts = [(pred.reshape(-1)[visible] - obs_flat) / sig]
        if scale is not None:
            parts.append([(np.linalg.norm(t[si] - t[sj]) - sd) / ssig])
        if tsig is not None:
            parts.append(((t - targets) / tsig).ravel()[tgt_free])
        if prior_rows.size:
            parts.append((x[prior_rows] - x0[prior_rows]) / cam_prior[prior_rows])
        return np.concatenate(parts)

    prior_rows = np.flatnonzero(np.isfinite(cam_prior))
    n_img = obs_flat.size
    n_tgt = tgt_free.size if tsig is not None else 0
    n_res = n_img + (scale is not None) + n_tgt + prior_rows.size
    full = lil_matrix((2 * m_cam * n_pts, n_unknown), dtype=int)  # all image rows
    for j in range(m_cam):
        full[2 * n_pts * j : 2 * n_pts * (j + 1), j * p_cam : (j + 1) * p_cam] = 1
    for col, entry in enumerate(tgt_free):
        i = int(entry) // 3
        for j in range(m_cam):
            full[2 * n_pts * j + 2 * i : 2 * n_pts * j + 2 * i + 2, p_cam * m_cam + col] = 1
    sparsity = lil_matrix((n_res, n_unknown), dtype=int)
    sparsity[:n_img] = full.tocsr()[np.flatnonzero(visible)]
    for col, entry in enumerate(tgt_free):
        i = int(entry) // 3
        if scale is not None and i in (si, sj):
            sparsity[n_img, p_cam * m_cam + col] = 1
        if tsig is not None:
            sparsity[n_img + (scale is not None) + col, p_cam * m_cam + col] = 1
    for row, column in enumerate(prior_rows):
        sparsity[n_img + (scale is not None) + n_tgt + row, column] = 1

    sol = least_squares(
        residuals,
        x0,
        jac="3-point",
        jac_sparsity=sparsity,
        method="trf",
        x_scale="jac",
        tr_options={"atol": 1e-14, "btol": 1e-14, "regularize": False},
        xtol=1e-10,
        ftol=1e-10,
        gtol=1e-10,
        max_nfev=max_nfev,
    )
    jac = sol.jac.toarray() if hasattr(sol.jac, "toarray") else np.asarray(sol.jac)
    dof = n_res - n_unknown
    s0sq = float(2.0 * sol.cost / dof) if dof > 0 else float("nan")
    cov = _inverse_normal(jac, "target_guess") * (s0sq if dof > 0 else 1.0)
    vecs, t = unpack(sol.x)
    out_cams = [cams[j].with_vector(vecs[j]) for j in range(m_cam)]
    pred = np.stack([project(out_cams[j], t) for j in range(m_cam)])
    pred[~seen] = np.nan
    counts = {**counts, "equations": n_img, "measurements": n_res, "unknowns_solved": n_unknown}
    return CalibrationResult(
        cameras=out_cams,
        targets=t,
        covariance=cov,
        names=names,
        sigma0_squared=s0sq,
        counts=counts,
        residuals_px=pred - obs,
        result=sol,
    )


def _observations(observations: npt.ArrayLike) -> FloatArray:
    """Image centroids; a target a camera does not see is NaN in both coordinates."""
    if isinstance(observations, (str, bytes)):
        raise FieldError("observations", "must be a numeric (M, N, 2) array")
    try:
        obs = np.array(observations, dtype=float)
    except (TypeError, ValueError):
        raise FieldError("observations", "must be a numeric (M, N, 2) array") from None
    if obs.ndim != 3 or obs.shape[-1] != 2:
        raise FieldError("observations", f"must have shape (M, N, 2), got {obs.shape}")
    if np.any(np.isinf(obs)):
        raise FieldError("observations", "must not contain inf (NaN marks an unseen target)")
    if np.any(np.isnan(obs[..., 0]) != np.isnan(obs[..., 1])):
        raise FieldError("observations", "an unseen target must be NaN in both u and v")
    return obs


def _check_visibility(seen: npt.NDArray[np.bool_], priors: bool, p_cam: int) -> None:
    """Every camera must see enough targets for its parameters, every target two cameras (one
    with a-priori target positions)."""
    for j, row in enumerate(seen):
        if 2 * row.sum() < p_cam:
            raise FieldError(
                "observations",
                f"camera {j} sees {int(row.sum())} targets, too few "
                f"for its {p_cam} free parameters",
            )
    need = 1 if priors else 2
    blind = np.flatnonzero(seen.sum(axis=0) < need)
    if blind.size:
        raise FieldError(
            "observations",
            f"targets {blind.tolist()} are seen by fewer than {need} "
            "camera(s); their positions are undetermined (drop them or give "
            "target_sigma)",
        )


def _camera_prior(
    camera_sigma: Mapping[str, float] | Sequence[Mapping[str, float]] | None,
    free: tuple[str, ...],
    m_cam: int,
) -> FloatArray:
    """Per-unknown a-priori standard deviation of the camera parameters (inf: none)."""
    out = np.full(m_cam * len(free), np.inf)
    if camera_sigma is None:
        return out
    per_camera = [camera_sigma] * m_cam if isinstance(camera_sigma, dict) else list(camera_sigma)
    mappings = [d for d in per_camera if isinstance(d, dict)]
    if len(per_camera) != m_cam or len(mappings) != len(per_camera):
        raise FieldError(
            "camera_sigma",
            f"must be a mapping {{parameter: sigma}} or one mapping per camera ({m_cam})",
        )
    for j, sigmas in enumerate(mappings):
        for name, value in sigmas.items():
            if name not in free:
                raise FieldError(
                    "camera_sigma", f"{name!r} is not a free parameter ({', '.join(free)})"
                )
            out[j * len(free) + free.index(name)] = require_positive_scalar(value, "camera_sigma")
    return out


def _check_datum(datum: Sequence[int], targets: FloatArray, n_pts: int) -> tuple[int, int, int]:
    try:
        i0, i1, i2 = (int(v) for v in datum)
    except (TypeError, ValueError):
        raise FieldError(
            "datum", f"must be three target indices (i0, i1, i2), got {datum!r}"
        ) from None
    if len({i0, i1, i2}) != 3 or not all(0 <= i < n_pts for i in (i0, i1, i2)):
        raise FieldError(
            "datum", f"must be three distinct target indices in [0, {n_pts}), got {datum!r}"
        )
    scl = 1e-6 * max(1.0, float(np.max(np.abs(targets))))
    if (
        np.any(np.abs(targets[i0]) > scl)
        or np.any(np.abs(targets[i1, 1:]) > scl)
        or abs(targets[i2, 2]) > scl
    ):
        raise FieldError(
            "target_guess",
            f"must be in the datum frame: target {i0} at the origin, "
            f"target {i1} with y = z = 0, target {i2} with z = 0",
        )
    if _collinear(targets[[i0, i1, i2]]) or abs(targets[i1, 0]) <= scl:
        raise FieldError(
            "datum",
            f"targets {i0}, {i1}, {i2} are collinear (or coincide) and "
            f"cannot define the X axis and the XY plane",
        )
    return i0, i1, i2


def _check_scale(scale: Sequence[float], n_pts: int) -> tuple[int, int, float, float]:
    try:
        si, sj = int(scale[0]), int(scale[1])
        sd = require_positive_scalar(scale[2], "scale distance")
        ssig = require_positive_scalar(scale[3], "scale sigma") if len(scale) > 3 else 1e-6 * sd
    except (TypeError, IndexError):
        raise FieldError("scale", f"must be (i, j, distance[, sigma]), got {scale!r}") from None
    if si == sj or not (0 <= si < n_pts and 0 <= sj < n_pts):
        raise FieldError(
            "scale", f"needs two distinct target indices in [0, {n_pts}), got {scale!r}"
        )
    return si, sj, sd, ssig


def _inverse_normal(jac: FloatArray, field_name: str) -> FloatArray:
    """``(J^T J)^-1`` with column equilibration; a clear error when the geometry is singular."""
    norms = np.linalg.norm(jac, axis=0)
    if np.any(norms == 0):
        raise FieldError(
            field_name, "some unknowns do not affect any observation (singular geometry)"
        )
    js = jac / norms
    s = np.linalg.svd(js, compute_uv=False)
    if s[-1] <= 1e-10 * s[0]:
        raise FieldError(
            field_name,
            "the normal matrix is singular (condition "
            f"{s[0] / max(s[-1], 1e-300):.3g}); the geometry does not determine "
            f"the unknowns (collinear targets or too few views?)",
        )
    inv = np.linalg.inv(js.T @ js)
    return inv / np.outer(norms, norms)


# ----------------------------------------------------------------------------------------------
# triangulation
# ----------------------------------------------------------------------------------------------
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
    (``tests/identify/test_photogrammetry.py`` solves eqs. (34)–(37) directly and compares).
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
    cams = _check_cameras(cameras, minimum=2)
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
                _project_vec(
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
