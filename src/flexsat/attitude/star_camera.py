r"""Pinhole star camera on the photogrammetry camera model (Junkins, Pollock & Rahman
1990, §2.3.4): which catalogue stars a camera sees at an attitude, and their noisy
centroids.

Stars lie at infinity, so the collinearity equations of :mod:`flexsat.identify.photogrammetry`
(Att. 6 eqs. 22–24 with the "+f" sign) apply with the camera at the origin and the star's unit
direction r as the object point: with :math:`d = C_{cn} r = C_{cb} C_{bn} r`,

.. math::

    u = f\,\frac{d_1}{d_3}, \qquad v = f\,\frac{d_2}{d_3}

(focal-plane metres, :func:`~flexsat.identify.photogrammetry.project`), where C_bn is the
spacecraft attitude (inertial to body, the plant's β) and C_cb the camera's mounting (body to
camera, 3-2-1 Euler angles as :func:`~flexsat.identify.photogrammetry.rotation_matrix`). The
pixel is ``p = (u, v)/pitch + n/2`` (origin at the detector corner) and a centroid carries
Gaussian noise of ``centroid_noise`` pixels per axis. The measured direction inverts the
pinhole, ``d̂ ∝ (u, v, f)``.

The focal length follows from the full field of view across the square detector,
``f = (n/2) pitch / tan(FOV/2)``; one pixel subtends ``pitch/f`` rad at the boresight, so a
centroid noise of σ_px pixels is a direction noise of σ_px·pitch/f rad per axis
(:attr:`StarCamera.direction_sigma`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from flexsat.attitude.star_catalog import StarCatalog
from flexsat.identify.photogrammetry import Camera, euler_angles, project, rotation_matrix
from flexsat.input_checks import FieldError, require_count, require_positive_scalar
from flexsat.units import FloatArray, QuantityArrayLike, QuantityLike, to_si_array

__all__ = ["MIN_PIXEL_PITCH", "StarCamera", "StarFrame"]

#: smallest pixel pitch, m: below any detector (diffraction makes pixels under half a
#: wavelength pointless), and far enough from the float range that the focal length and the
#: image coordinates keep their digits
MIN_PIXEL_PITCH = 1e-7


@dataclass(frozen=True)
class StarFrame:
    """One camera's measured stars, in random order.

    Attributes
    ----------
    camera : int
        Index of the camera in its tracker.
    pixels : ndarray (k, 2)
        Noisy centroids, pixels from the detector corner.
    vectors : ndarray (k, 3)
        Measured unit directions in camera axes.
    truth : ndarray (k,)
        Catalogue row of each star, −1 for a false star (for scoring only; the identification
        never reads it).
    magnitudes : ndarray (k,)
        Catalogue magnitude (a false star gets one drawn from the same distribution).
    """

    camera: int
    pixels: FloatArray
    vectors: FloatArray
    truth: npt.NDArray[np.int_]
    magnitudes: FloatArray

    def __len__(self) -> int:
        return self.truth.size


@dataclass(frozen=True)
class StarCamera:
    """Square-detector pinhole star camera.

    Parameters
    ----------
    field_of_view : float, str or Quantity
        Full angle across a side of the detector (default 12°).
    n_pixels : int
        Pixels per side (default 4096: 10.5″ per pixel at 12°).
    pixel_pitch : float, str or Quantity
        Pixel size (default 5.5 µm); with the field of view it sets the focal length.
    centroid_noise : float
        1σ centroid noise per axis, pixels (default 0.1).
    magnitude_limit : float
        Faintest visual magnitude detected (default 6.5).
    mounting : sequence of 3 angles, str or Quantity
        3-2-1 Euler angles (φ, θ, ψ) of the camera axes relative to the body axes, rad
        (:func:`~flexsat.identify.photogrammetry.rotation_matrix`); the boresight is the camera
        z axis.
    """

    # the fields hold SI floats; the defaults are quantities that __post_init__ converts
    field_of_view: float = "12 deg"  # type: ignore[assignment]
    n_pixels: int = 4096
    pixel_pitch: float = "5.5 um"  # type: ignore[assignment]
    centroid_noise: float = 0.1
    magnitude_limit: float = 6.5
    mounting: tuple[float, float, float] = (0.0, 0.0, 0.0)
    _matrix: FloatArray = field(init=False, repr=False, compare=False)

    if TYPE_CHECKING:
        # what the constructor accepts (the generated __init__ at run time): quantities
        def __init__(
            self,
            field_of_view: QuantityLike = ...,
            n_pixels: int = ...,
            pixel_pitch: QuantityLike = ...,
            centroid_noise: float = ...,
            magnitude_limit: float = ...,
            mounting: QuantityArrayLike = ...,
        ) -> None: ...

    def __post_init__(self) -> None:
        fov = require_positive_scalar(self.field_of_view, "field_of_view", "rad")
        if fov >= np.radians(120):
            raise FieldError(
                "field_of_view",
                f"a pinhole star camera needs a full angle below 120°, got {np.degrees(fov):.4g}°",
            )
        object.__setattr__(self, "field_of_view", fov)
        n = require_count(self.n_pixels, "n_pixels")
        if n < 2:
            raise FieldError("n_pixels", f"must be >= 2, got {n}")
        object.__setattr__(self, "n_pixels", n)
        pitch = require_positive_scalar(self.pixel_pitch, "pixel_pitch", "m")
        if pitch < MIN_PIXEL_PITCH:
            raise FieldError(
                "pixel_pitch",
                f"{pitch:.3g} m is below {MIN_PIXEL_PITCH:g} m, smaller than any detector's "
                "pixel (visible light's wavelength is 0.4-0.7 µm)",
            )
        object.__setattr__(self, "pixel_pitch", pitch)
        noise = to_si_array(self.centroid_noise, "", "centroid_noise")
        if noise.ndim != 0 or not np.isfinite(noise) or noise < 0:
            raise FieldError(
                "centroid_noise",
                f"must be one finite number >= 0 (pixels), got {self.centroid_noise!r}",
            )
        object.__setattr__(self, "centroid_noise", float(noise))
        lim = to_si_array(self.magnitude_limit, "", "magnitude_limit")
        if lim.ndim != 0 or not np.isfinite(lim):
            raise FieldError(
                "magnitude_limit", f"must be one finite number, got {self.magnitude_limit!r}"
            )
        object.__setattr__(self, "magnitude_limit", float(lim))
        ang = to_si_array(self.mounting, "rad", "mounting")
        if ang.shape != (3,) or not np.all(np.isfinite(ang)):
            raise FieldError(
                "mounting", f"must be 3 finite 3-2-1 Euler angles, got {self.mounting!r}"
            )
        object.__setattr__(self, "mounting", tuple(float(a) for a in ang))
        object.__setattr__(self, "_matrix", rotation_matrix(ang, "321"))

    @property
    def mounting_matrix(self) -> FloatArray:
        """C_cb, body to camera axes."""
        return self._matrix

    @property
    def boresight(self) -> FloatArray:
        """The camera z axis in body axes (third row of C_cb)."""
        return self._matrix[2].copy()

    @property
    def focal_length(self) -> float:
        """f = (n/2) pitch / tan(FOV/2), m."""
        return 0.5 * self.n_pixels * self.pixel_pitch / np.tan(0.5 * self.field_of_view)

    @property
    def pixel_angle(self) -> float:
        """Angle one pixel subtends at the boresight, pitch/f (rad)."""
        return self.pixel_pitch / self.focal_length

    @property
    def direction_sigma(self) -> float:
        """1σ direction noise per axis of a measured star at the boresight, rad."""
        return self.centroid_noise * self.pixel_angle

    @property
    def max_pair_angle(self) -> float:
        """Largest angle between two stars on the detector (corner to corner), rad."""
        return 2.0 * np.arctan(np.sqrt(2.0) * np.tan(0.5 * self.field_of_view))

    def camera_model(self, attitude: npt.ArrayLike) -> Camera:
        """The photogrammetry :class:`~flexsat.identify.photogrammetry.Camera` at the origin
        with C_cn = C_cb C_bn, square pixels f, "+f" sign (module docstring)."""
        c_cn = self._matrix @ np.asarray(attitude, float)
        return Camera(
            position=(0.0, 0.0, 0.0),
            angles=euler_angles(c_cn, "321"),
            f=self.focal_length,
            focal_sign=1,
        )

    def directions(self, pixels: npt.ArrayLike) -> FloatArray:
        """Unit directions in camera axes of centroids (k, 2) in pixels (inverse pinhole)."""
        p = np.asarray(pixels, float)
        uv = (p - 0.5 * self.n_pixels) * self.pixel_pitch
        d = np.concatenate([uv, np.full(p.shape[:-1] + (1,), self.focal_length)], -1)
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def observe(
        self,
        attitude: npt.ArrayLike,
        catalog: StarCatalog,
        rng: np.random.Generator,
        index: int = 0,
        false_stars: int = 0,
        missing_fraction: float = 0.0,
    ) -> StarFrame:
        """The stars this camera measures at attitude C_bn (3, 3), inertial to body.

        Parameters
        ----------
        catalog : StarCatalog
            The sky (stars fainter than :attr:`magnitude_limit` are not detected).
        rng : numpy.random.Generator
            Source of centroid noise, dropped and false stars.
        index : int
            This camera's index in its tracker (stored in the frame).
        false_stars : int
            Spurious centroids (hot pixels, planets, debris) uniform on the detector.
        missing_fraction : float
            Fraction of the visible stars dropped at random (rounded to the nearest count).
        """
        n_false = require_count(false_stars, "false_stars") if false_stars else 0
        miss = float(missing_fraction)
        if not 0.0 <= miss < 1.0:
            raise FieldError("missing_fraction", f"must lie in [0, 1), got {missing_fraction!r}")
        c_cn = self._matrix @ np.asarray(attitude, float)
        bright = catalog.magnitudes <= self.magnitude_limit
        depth = catalog.vectors @ c_cn[2]
        # only stars within the detector's corner cone can image: a cheap cut before projecting
        near = np.flatnonzero(bright & (depth > np.cos(0.5 * self.max_pair_angle) - 1e-9))
        uv = project(self.camera_model(attitude), catalog.vectors[near])
        px = uv / self.pixel_pitch + 0.5 * self.n_pixels
        px = px + rng.normal(0.0, self.centroid_noise, px.shape)
        inside = np.all((px >= 0) & (px < self.n_pixels), axis=1)
        rows, px = near[inside], px[inside]
        n_miss = int(np.floor(miss * rows.size + 0.5))
        if n_miss:
            keep = np.sort(rng.permutation(rows.size)[n_miss:])
            rows, px = rows[keep], px[keep]
        truth = rows
        mags = catalog.magnitudes[rows]
        if n_false:
            fp = rng.uniform(0.0, self.n_pixels, (n_false, 2))
            fm = self.magnitude_limit + 2.0 * np.log10(1.0 - rng.uniform(0.0, 1.0, n_false))
            px = np.vstack([px, fp])
            truth = np.concatenate([truth, np.full(n_false, -1)])
            mags = np.concatenate([mags, fm])
        order = rng.permutation(truth.size)
        px, truth, mags = px[order], truth[order], mags[order]
        return StarFrame(index, px, self.directions(px), truth, mags)
