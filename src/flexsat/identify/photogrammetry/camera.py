"""Collinearity camera model of stereo photogrammetry: projection, Euler attitudes, simulated
centroids.

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
``tests/identify/test_camera.py``).  With ``fx != fy`` our
``r^2 = fx^2 x'^2 + fy^2 y'^2`` is not a multiple of OpenCV's ``x'^2 + y'^2`` and no
distortion coefficients reproduce it; without distortion the camera matrix
``diag(s fx, s fy, 1)`` (plus the principal point) still does.  The printed Att. 6 form has no
OpenCV counterpart.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

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
    "FIELD_SIZE_PX",
    "FIELD_RATE_HZ",
    "CAMERA_PARAMETERS",
    "Camera",
    "rotation_matrix",
    "euler_angles",
    "look_at",
    "project",
    "project_vector",
    "check_cameras",
    "simulate_centroids",
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


def project_vector(
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
    uv, depth = project_vector(
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
    cams = check_cameras(cameras)
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


def check_cameras(
    cameras: Camera | Sequence[Camera], field_name: str = "cameras", minimum: int = 1
) -> list[Camera]:
    """``cameras`` as a list of at least ``minimum`` :class:`Camera` (one camera: a list of one)."""
    if isinstance(cameras, Camera):
        cameras = [cameras]
    cams = list(cameras)
    if len(cams) < minimum:
        raise FieldError(field_name, f"at least {minimum} cameras are needed, got {len(cams)}")
    for j, cam in enumerate(cams):
        if not isinstance(cam, Camera):
            raise FieldError(f"{field_name}[{j}]", f"must be a Camera, got {type(cam).__name__}")
    return cams
