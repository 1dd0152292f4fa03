r"""Video targets: rendered camera frames of retro-reflective targets, blob extraction and
sub-pixel centroids, feeding stereo triangulation.

Sources: G. H. James and J. L. Junkins, "Novel Sensing and Structural Identification Methods:
Preliminary Analytical and Experimental Results", AAS paper 89-425, 1989 (Att. 6 of Junkins,
Pollock & Rahman 1990: NAC V-14B cameras, 320 × 244 pixels, 200 fields/s; the Motion Analysis
VP-110 processor's grey-scale threshold, boundary digitisation and centroiding); J. L. Junkins
and G. H. James, "A Stereo-Triangulation Approach to Sensing for Structural Identification",
AAS paper 88-015, 1988 (Att. 8: centroids of near-circular boundaries to about 0.5 pixel, an
upgrade aiming at 0.1 pixel).

Where :func:`flexsat.identify.photogrammetry.simulate_centroids` draws centroids directly, this
module makes the frames the hardware saw and measures them:

**Rendering** (:func:`render_frame`). Each target is a spot whose image, through a Gaussian
point-spread function of standard deviation ``s`` pixels, is integrated exactly over each
pixel's area: a target of ``F`` counts at (x, y) puts

.. math::

    \mu_{ij} = F\,[\Phi(\tfrac{j+1-x}{s}) - \Phi(\tfrac{j-x}{s})]\,
                  [\Phi(\tfrac{i+1-y}{s}) - \Phi(\tfrac{i-y}{s})]

into pixel (row i, column j), Φ the standard normal distribution (pixel (i, j) spans
x ∈ [j, j + 1), y ∈ [i, i + 1): pixel centres at half-integers, as the detector of
``simulate_centroids`` whose edges lie at integer pixels from its centre). On top come a
background (a constant, a plane or any image), Gaussian read noise of σ_n counts and, with a
``gain`` (electrons per count), photon noise of variance μ/g;
optionally rounding to an ADC quantum.

**Extraction** (:func:`extract_blobs`). The background level and noise are estimated robustly
(median and 1.4826 × the median absolute deviation of the frame, unless given); pixels above
``level + k σ`` (``k`` = 5 by default) are labelled into 8-connected components by OpenCV
(``cv2.connectedComponentsWithStats``; the optional extra ``flexsat[opencv]``); components
smaller than ``min_area`` pixels are dropped. Each component's sub-pixel centre is then found in
a (2h + 1)² window around its brightest pixel:

* ``method="gaussian"`` (default): maximum likelihood for white Gaussian noise — least squares of
  the pixel-integrated spot above plus a background plane, 7 parameters
  (x, y, F, s, b₀, b_x, b_y), by Levenberg–Marquardt with the analytic Jacobian (weighted by the
  model's noise variance when photon noise is on). Its covariance σ_n² (JᵀJ)⁻¹ is the
  Cramér–Rao bound at the estimate.
* ``method="moment"``: the first moment of the background-subtracted window (the VP-110's
  centroid of the thresholded blob, without the threshold's bias), with the linear-propagation
  variance σ_n² Σ (x_k − x̂)² / F̂² over the window's pixels.

**Predicted scatter.** For a spot of ``F`` counts, PSF σ ``s`` ≫ 1 pixel and read noise σ_n,
the Cramér–Rao bound of either coordinate is (Fisher information Σ (∂μ/∂x)² / σ_n² with
∫∫ (x F e^{-r²/2s²}/(2π s⁴))² dA = F²/(8π s⁴))

.. math::

    \sigma_x^2 \ge \frac{8\pi s^4 \sigma_n^2}{F^2},

the bound of a Gaussian spot in white noise (the location parameter decouples from F, s and
the background by symmetry). :func:`centroid_crb` evaluates the exact bound of the
pixel-integrated spot and the fitted nuisance parameters in a given window; it tends to the
formula as s grows (tested). The moment centroid does worse: every window pixel adds its noise
at its lever arm, σ_x² = σ_n² Σ_k (x_k − x)² / F² = σ_n² n² h(h + 1) / (3 F²) for an n × n
window, n = 2h + 1, centred on the spot — it grows with the window, which is why the VP-110
thresholded the background away and lived with the threshold's bias.

**Into triangulation.** :func:`pixels_to_image` and :func:`image_to_pixels` convert between
pixel coordinates and the focal-plane coordinates of
:mod:`flexsat.identify.photogrammetry` (``u = (x − W/2) p_x``, ``v = (y − H/2) p_y`` for a
W × H detector of pitch p), :func:`render_views` renders what each camera sees of a set of 3-D
targets, and :func:`match_targets` assigns the extracted blobs to the targets by their predicted
image positions (nearest neighbour, one blob per target).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.special import ndtr

from flexsat.identify.photogrammetry import FIELD_SIZE_PX, Camera, project
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_positive,
    require_positive_scalar,
)
from flexsat.units import FloatArray

__all__ = [
    "BlobSet",
    "FrameSpec",
    "centroid_crb",
    "centroid_crb_continuum",
    "extract_blobs",
    "image_to_pixels",
    "match_targets",
    "pixels_to_image",
    "render_frame",
    "render_views",
    "measure_views",
    "spot_model",
    "spot_window",
    "SPOT_PARAMETERS",
]

_SQRT2PI = float(np.sqrt(2 * np.pi))
#: fitted parameters of a spot, in order
SPOT_PARAMETERS = ("x", "y", "flux", "sigma", "b0", "bx", "by")


@dataclass(frozen=True)
class FrameSpec:
    """What a camera frame looks like (pixels and counts).

    Parameters
    ----------
    shape : (int, int)
        Rows, columns (default the NAC V-14B field, 244 × 320).
    sigma_px : float
        Standard deviation of the Gaussian point-spread function, pixels (> 0).
    flux : float
        Counts in one target's image (> 0).
    background : float
        Uniform background, counts (≥ 0); :func:`render_frame` also takes an image.
    noise : float
        Read noise, counts (standard deviation, ≥ 0).
    gain : float or None
        Electrons per count for photon noise (variance μ / gain); None: no photon noise.
    quantum : float or None
        ADC step, counts (the frame is rounded to it); None: not quantized.
    """

    shape: tuple[int, int] = (FIELD_SIZE_PX[1], FIELD_SIZE_PX[0])
    sigma_px: float = 1.0
    flux: float = 2000.0
    background: float = 20.0
    noise: float = 2.0
    gain: float | None = None
    quantum: float | None = None

    def __post_init__(self) -> None:
        shape = tuple(self.shape)
        if len(shape) != 2:
            raise FieldError("shape", f"must be (rows, columns), got {self.shape!r}")
        object.__setattr__(self, "shape", tuple(require_count(n, "shape") for n in shape))
        object.__setattr__(self, "sigma_px", require_positive_scalar(self.sigma_px, "sigma_px"))
        object.__setattr__(self, "flux", require_positive_scalar(self.flux, "flux"))
        for name in ("background", "noise"):
            value = float(require_nonneg(getattr(self, name), name).reshape(-1)[0])
            object.__setattr__(self, name, value)
        for name in ("gain", "quantum"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, require_positive_scalar(getattr(self, name), name))


def spot_model(
    x: npt.ArrayLike, y: npt.ArrayLike, flux: npt.ArrayLike, sigma: npt.ArrayLike, shape: Any
) -> FloatArray:
    """The noise-free image (rows, columns) of Gaussian spots integrated over each pixel
    (module docstring), no background."""
    rows, cols = (require_count(n, "shape") for n in shape)
    xs = require_finite(x, "x").reshape(-1)
    ys = require_finite(y, "y").reshape(-1)
    f = np.broadcast_to(require_finite(flux, "flux"), xs.shape)
    s = np.broadcast_to(require_positive(sigma, "sigma"), xs.shape)
    if ys.shape != xs.shape:
        raise FieldError("y", f"one y per x: got {ys.size} for {xs.size}")
    image = np.zeros((rows, cols))
    half = np.ceil(6 * s).astype(int) + 1
    for xi, yi, fi, si, h in zip(xs, ys, f, s, half):
        c0, r0 = max(int(np.floor(xi)) - h, 0), max(int(np.floor(yi)) - h, 0)
        c1, r1 = min(int(np.floor(xi)) + h + 1, cols), min(int(np.floor(yi)) + h + 1, rows)
        if c1 <= c0 or r1 <= r0:
            continue
        ex = np.diff(ndtr((np.arange(c0, c1 + 1) - xi) / si))
        ey = np.diff(ndtr((np.arange(r0, r1 + 1) - yi) / si))
        image[r0:r1, c0:c1] += fi * np.outer(ey, ex)
    return image


def render_frame(
    centres: npt.ArrayLike,
    spec: FrameSpec | None = None,
    seed: int | np.random.Generator | None = None,
    background: npt.ArrayLike | None = None,
    flux: npt.ArrayLike | None = None,
) -> FloatArray:
    """One camera frame (rows, columns, counts) with targets at ``centres`` (N, 2) = (x, y)
    pixels; ``background`` (an image of the frame's shape, or a scalar) and ``flux`` (one per
    target) override the ``spec``'s. Targets outside the frame leave only their tails in it."""
    sp = spec or FrameSpec()
    c = require_finite(centres, "centres").reshape(-1, 2) if np.size(centres) else np.zeros((0, 2))
    f = sp.flux if flux is None else require_positive(flux, "flux")
    image = spot_model(c[:, 0], c[:, 1], f, sp.sigma_px, sp.shape)
    bg = sp.background if background is None else require_finite(background, "background")
    if np.ndim(bg) and np.shape(bg) != sp.shape:
        raise FieldError("background", f"must be a scalar or a {sp.shape} image")
    mean = image + bg
    rng = np.random.default_rng(seed)
    var = np.full(sp.shape, sp.noise**2)
    if sp.gain is not None:
        var = var + np.clip(mean, 0.0, None) / sp.gain
    frame = mean + rng.standard_normal(sp.shape) * np.sqrt(var)
    if sp.quantum is not None:
        frame = np.round(frame / sp.quantum) * sp.quantum
    return np.asarray(frame, dtype=float)


# ----------------------------------------------------------------------------------------------
# the spot fit
# ----------------------------------------------------------------------------------------------
def spot_window(
    theta: FloatArray, c0: FloatArray, r0: FloatArray, size: int
) -> tuple[FloatArray, FloatArray]:
    """Model μ (N, size, size) and its Jacobian (N, size, size, 7) of spots with parameters
    ``theta`` (N, 7) in the order of :data:`SPOT_PARAMETERS` — (x, y) pixels, flux, PSF σ and the
    background plane b₀ + b_x Δx + b_y Δy about the window centre — in windows whose first
    column and row are ``c0``, ``r0`` (N,)."""
    x, y, f, s = theta[:, 0], theta[:, 1], theta[:, 2], theta[:, 3]
    ax = (c0[:, None] + np.arange(size + 1) - x[:, None]) / s[:, None]  # (N, size+1)
    ay = (r0[:, None] + np.arange(size + 1) - y[:, None]) / s[:, None]
    px, py = ndtr(ax), ndtr(ay)
    gx, gy = np.exp(-0.5 * ax**2) / _SQRT2PI, np.exp(-0.5 * ay**2) / _SQRT2PI
    ex, ey = np.diff(px, axis=1), np.diff(py, axis=1)  # (N, size)
    dex_dx = -np.diff(gx, axis=1) / s[:, None]
    dey_dy = -np.diff(gy, axis=1) / s[:, None]
    dex_ds = -np.diff(gx * ax, axis=1) / s[:, None]
    dey_ds = -np.diff(gy * ay, axis=1) / s[:, None]
    off = np.arange(size) + 0.5 - size / 2  # pixel centres relative to the window centre
    spot = ey[:, :, None] * ex[:, None, :]  # (N, rows, cols)
    mu = (
        f[:, None, None] * spot
        + theta[:, 4, None, None]
        + theta[:, 5, None, None] * off[None, None, :]
        + theta[:, 6, None, None] * off[None, :, None]
    )
    jac = np.stack(
        [
            f[:, None, None] * ey[:, :, None] * dex_dx[:, None, :],
            f[:, None, None] * dey_dy[:, :, None] * ex[:, None, :],
            spot,
            f[:, None, None]
            * (dey_ds[:, :, None] * ex[:, None, :] + ey[:, :, None] * dex_ds[:, None, :]),
            np.ones_like(spot),
            np.broadcast_to(off[None, None, :], spot.shape),
            np.broadcast_to(off[None, :, None], spot.shape),
        ],
        axis=-1,
    )
    return mu, jac


def _fit_spots(
    windows: FloatArray,
    theta: FloatArray,
    c0: FloatArray,
    r0: FloatArray,
    noise: float,
    gain: float | None,
    iterations: int = 50,
) -> tuple[FloatArray, FloatArray, npt.NDArray[np.bool_]]:
    """Levenberg–Marquardt on all windows at once; returns θ, covariance (N, 7, 7), converged."""
    size = windows.shape[1]
    lam = np.full(theta.shape[0], 1e-3)
    done = np.zeros(theta.shape[0], bool)

    def weights(mu: FloatArray) -> FloatArray:
        var = np.full(mu.shape, noise**2)
        if gain is not None:
            var = var + np.clip(mu, 0.0, None) / gain
        return 1.0 / var

    mu, jac = spot_window(theta, c0, r0, size)
    w = weights(mu)
    cost = np.sum(w * (windows - mu) ** 2, axis=(1, 2))
    for _ in range(iterations):
        jr = jac.reshape(jac.shape[0], -1, 7)
        wr = w.reshape(w.shape[0], -1)
        res = (windows - mu).reshape(w.shape[0], -1)
        normal = np.einsum("nka,nk,nkb->nab", jr, wr, jr)
        grad = np.einsum("nka,nk,nk->na", jr, wr, res)
        diag = np.einsum("nii->ni", normal)
        diag = np.maximum(diag, 1e-12 * diag.max(axis=1, keepdims=True))
        damped = normal + (lam[:, None] * diag)[:, :, None] * np.eye(7)
        step = np.linalg.solve(damped, grad[..., None])[..., 0]
        trial = theta + step
        trial[:, 3] = np.maximum(trial[:, 3], 0.05)
        mu_t, jac_t = spot_window(trial, c0, r0, size)
        w_t = weights(mu_t)
        cost_t = np.sum(w_t * (windows - mu_t) ** 2, axis=(1, 2))
        better = cost_t <= cost
        theta = np.where(better[:, None], trial, theta)
        mu = np.where(better[:, None, None], mu_t, mu)
        jac = np.where(better[:, None, None, None], jac_t, jac)
        w = np.where(better[:, None, None], w_t, w)
        small = np.max(np.abs(step[:, :2]), axis=1) < 1e-9
        done |= better & small
        cost = np.where(better, cost_t, cost)
        lam = np.where(better, lam / 10, lam * 10)
        if np.all(done):
            break
    jr = jac.reshape(jac.shape[0], -1, 7)
    normal = np.einsum("nka,nk,nkb->nab", jr, w.reshape(w.shape[0], -1), jr)
    ok = np.isfinite(theta).all(axis=1) & (theta[:, 2] > 0)
    cov = np.full(normal.shape, np.nan)
    cov[ok] = np.linalg.inv(normal[ok])
    return theta, cov, done & ok


# ----------------------------------------------------------------------------------------------
# extraction
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BlobSet:
    """Blobs extracted from one frame (pixels, counts).

    Attributes
    ----------
    centres : ndarray (N, 2)
        Sub-pixel (x, y) of each blob.
    covariance : ndarray (N, 2, 2)
        Predicted covariance of each centre (module docstring: the fit's Cramér–Rao bound at
        the estimate, or the moment centroid's propagated noise).
    flux, sigma : ndarray (N,)
        Fitted counts and PSF σ (``moment``: summed counts and the second-moment width).
    area : ndarray (N,)
        Pixels above the threshold in each component.
    converged : ndarray (N,) of bool
        The fit's step fell below 1e-9 px (always True for ``moment``).
    level, noise, threshold : float
        Background level (median of the background map) and noise used, and the threshold
        (level + k σ; the frame is thresholded k σ above the map itself).
    method : str
        "gaussian" or "moment".
    binary_centres : ndarray (N, 2)
        The area centroid of each thresholded component (OpenCV's), the VP-110's kind of
        measurement: every pixel above the threshold counts once. No first-order prediction
        comes with it (it quantizes); docs/identification.md reports its measured scatter.
    """

    centres: FloatArray
    covariance: FloatArray
    flux: FloatArray
    sigma: FloatArray
    area: npt.NDArray[np.int_]
    converged: npt.NDArray[np.bool_]
    level: float
    noise: float
    threshold: float
    method: str
    binary_centres: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))

    def __len__(self) -> int:
        return int(self.centres.shape[0])


def _cv2() -> Any:
    """OpenCV, or an ImportError that says how to install it."""
    try:
        import cv2
    except ImportError as exc:  # pragma: no cover - the extra is in dev
        raise ImportError(
            "blob extraction uses OpenCV (connected components, dilation): "
            "pip install 'flexsat[opencv]' (opencv-python-headless)"
        ) from exc
    return cv2


def _components(
    mask: npt.NDArray[np.bool_],
) -> tuple[int, npt.NDArray[np.int32], FloatArray, FloatArray]:
    """8-connected components by OpenCV: (count incl. background, labels, stats, centroids in
    this module's pixel coordinates)."""
    cv2 = _cv2()
    n, labels, stats, cents = cv2.connectedComponentsWithStats(
        mask.astype(np.uint8), connectivity=8, ltype=cv2.CV_32S
    )
    # OpenCV puts pixel (i, j) at (x, y) = (j, i); here its centre is at (j + ½, i + ½)
    return (
        int(n),
        np.asarray(labels, dtype=np.int32),
        np.asarray(stats, dtype=float),
        np.asarray(cents, dtype=float) + 0.5,
    )


def _tile_medians(img: FloatArray, keep: npt.NDArray[np.bool_], tile: int) -> FloatArray:
    """Median of the kept pixels of each tile × tile block, bilinearly interpolated between
    the tile centres (linear extrapolation at the edges); a tile with fewer than a quarter of
    its pixels kept takes the median of all kept pixels."""
    from scipy.interpolate import RegularGridInterpolator

    rows, cols = img.shape
    nr, nc = max(1, rows // tile), max(1, cols // tile)
    re = np.linspace(0, rows, nr + 1).astype(int)
    ce = np.linspace(0, cols, nc + 1).astype(int)
    overall = float(np.median(img[keep]))
    grid = np.full((nr, nc), overall)
    for i in range(nr):
        for j in range(nc):
            blk, ok = (
                img[re[i] : re[i + 1], ce[j] : ce[j + 1]],
                keep[re[i] : re[i + 1], ce[j] : ce[j + 1]],
            )
            if ok.sum() >= 0.25 * ok.size:
                grid[i, j] = float(np.median(blk[ok]))
    if nr == 1 or nc == 1:
        return np.full(img.shape, float(np.median(grid)))
    interp = RegularGridInterpolator(
        (0.5 * (re[:-1] + re[1:]), 0.5 * (ce[:-1] + ce[1:])),
        grid,
        bounds_error=False,
        fill_value=None,
    )
    rr, cc = np.meshgrid(np.arange(rows) + 0.5, np.arange(cols) + 0.5, indexing="ij")
    out: FloatArray = interp(np.column_stack([rr.ravel(), cc.ravel()])).reshape(img.shape)
    return out


def _background(img: FloatArray, s0: float, tile: int) -> tuple[FloatArray, float]:
    """Background map and read noise from the pixels away from the targets: tile medians
    (:func:`_tile_medians`) and 1.4826 × the median absolute deviation about them; the pixels
    3 σ above the map, grown by ⌈3 σ_px⌉ pixels (cv2.dilate), are left out and the estimate
    repeated (3 times)."""
    import cv2

    keep = np.ones(img.shape, bool)
    g = int(np.ceil(3 * s0))
    kernel = np.ones((2 * g + 1, 2 * g + 1), np.uint8)
    level = np.full(img.shape, float(np.median(img)))
    sig = 0.0
    for _ in range(3):
        level = _tile_medians(img, keep, tile)
        resid = (img - level)[keep]
        sig = 1.4826 * float(np.median(np.abs(resid - np.median(resid))))
        if not sig > 0:
            break
        keep = cv2.dilate((img - level > 3 * sig).astype(np.uint8), kernel) == 0
        if keep.sum() < 0.05 * img.size:
            raise FieldError("frame", "targets cover most of the frame; give level and noise")
    return level, sig


def extract_blobs(
    frame: npt.ArrayLike,
    sigma_px: float = 1.0,
    k: float = 5.0,
    level: float | None = None,
    noise: float | None = None,
    min_area: int = 3,
    half_window: int | None = None,
    method: str = "gaussian",
    gain: float | None = None,
    tile: int = 32,
) -> BlobSet:
    """Targets in ``frame`` (rows, columns): threshold, connected components, sub-pixel centres.

    Parameters
    ----------
    frame : array_like (rows, columns)
        Counts.
    sigma_px : float
        Expected PSF σ, pixels: the fit's start and the default window.
    k : float
        Threshold in noise units above the background level.
    level, noise : float, optional
        Background level and read noise (counts); default a background map — the median of
        each ``tile`` × ``tile`` block of pixels away from the targets, bilinearly interpolated —
        and 1.4826 × the median absolute deviation about it (the pixels 3 σ above the map,
        grown by ⌈3 σ_px⌉ pixels, are left out; repeated three times). The threshold is
        ``k`` σ above the map, so a smooth background gradient does not make blobs.
    min_area : int
        Components with fewer pixels above the threshold are dropped (noise peaks).
    half_window : int, optional
        h of the (2h + 1)² window around each component's brightest pixel; default
        ⌈4 σ_px⌉ + 1. Components whose window leaves the frame are dropped.
    method : str
        "gaussian" (maximum likelihood, default) or "moment" (module docstring).
    gain : float, optional
        Electrons per count: the fit then weights each pixel by its photon + read noise
        (``noise`` is then the read noise alone; the threshold uses the frame's measured σ).
    tile : int
        Block size of the background map, pixels (several PSF widths and target spacings).
    """
    img = require_finite(frame, "frame")
    if img.ndim != 2:
        raise FieldError("frame", f"must be an image (rows, columns), got shape {img.shape}")
    if method not in ("gaussian", "moment"):
        raise FieldError("method", f"must be 'gaussian' or 'moment', got {method!r}")
    s0 = require_positive_scalar(sigma_px, "sigma_px")
    kk = require_positive_scalar(k, "k")
    h = (
        int(np.ceil(4 * s0)) + 1
        if half_window is None
        else require_count(half_window, "half_window")
    )
    bg, sig = _background(img, s0, require_count(tile, "tile"))
    if level is not None:
        bg = np.full(img.shape, float(require_finite(level, "level")))
    lev = float(np.median(bg))
    if noise is not None and gain is None:
        sig = require_positive_scalar(noise, "noise")
    if not sig > 0:
        raise FieldError("noise", "the frame has no noise to estimate; give noise > 0")
    read = sig
    if gain is not None:
        g_e = require_positive_scalar(gain, "gain")
        # the measured σ holds the background's photon noise: the read noise is the rest
        read = (
            require_positive_scalar(noise, "noise")
            if noise is not None
            else float(np.sqrt(max(sig**2 - max(float(np.median(bg)), 0.0) / g_e, 1e-6 * sig**2)))
        )
    threshold = lev + kk * sig
    n, labels, stats, binary = _components(img - bg > kk * sig)
    rows, cols = img.shape
    peaks, areas, kept = [], [], []
    cv2 = _cv2()

    for lab in range(1, n):
        area = int(stats[lab, cv2.CC_STAT_AREA])
        if area < require_count(min_area, "min_area"):
            continue
        x0, y0 = int(stats[lab, cv2.CC_STAT_LEFT]), int(stats[lab, cv2.CC_STAT_TOP])
        w, hh = int(stats[lab, cv2.CC_STAT_WIDTH]), int(stats[lab, cv2.CC_STAT_HEIGHT])
        sub = np.where(
            labels[y0 : y0 + hh, x0 : x0 + w] == lab, img[y0 : y0 + hh, x0 : x0 + w], -np.inf
        )
        r, c = np.unravel_index(int(np.argmax(sub)), sub.shape)
        r, c = r + y0, c + x0
        if r - h < 0 or c - h < 0 or r + h >= rows or c + h >= cols:
            continue
        peaks.append((r, c))
        areas.append(area)
        kept.append(lab)
    size = 2 * h + 1
    if not peaks:
        empty = np.zeros((0,))
        return BlobSet(
            np.zeros((0, 2)),
            np.zeros((0, 2, 2)),
            empty,
            empty,
            np.zeros(0, int),
            np.zeros(0, bool),
            lev,
            sig,
            threshold,
            method,
        )
    pk = np.array(peaks)
    r0, c0 = pk[:, 0] - h, pk[:, 1] - h
    idx_r = r0[:, None] + np.arange(size)
    idx_c = c0[:, None] + np.arange(size)
    windows = img[idx_r[:, :, None], idx_c[:, None, :]]  # (N, size, size)
    above = windows - bg[idx_r[:, :, None], idx_c[:, None, :]]
    xs = c0[:, None] + np.arange(size) + 0.5
    ys = r0[:, None] + np.arange(size) + 0.5
    flux = above.sum(axis=(1, 2))
    mx = np.einsum("nij,nj->n", above, xs) / flux
    my = np.einsum("nij,ni->n", above, ys) / flux
    if method == "moment":
        dx2 = np.sum((xs - mx[:, None]) ** 2, axis=1) * size  # Σ over the window's pixels
        dy2 = np.sum((ys - my[:, None]) ** 2, axis=1) * size
        cov = np.zeros((pk.shape[0], 2, 2))
        cov[:, 0, 0], cov[:, 1, 1] = sig**2 * dx2 / flux**2, sig**2 * dy2 / flux**2
        width = np.sqrt(
            np.clip(np.einsum("nij,nj->n", above, (xs - mx[:, None]) ** 2) / flux, 0, None)
        )
        return BlobSet(
            np.column_stack([mx, my]),
            cov,
            flux,
            width,
            np.array(areas),
            np.ones(pk.shape[0], bool),
            lev,
            sig,
            threshold,
            method,
            binary[kept],
        )
    theta = np.column_stack(
        [
            mx,
            my,
            np.maximum(flux, sig),
            np.full(mx.shape, s0),
            bg[pk[:, 0], pk[:, 1]],
            np.zeros(mx.shape),
            np.zeros(mx.shape),
        ]
    )
    theta, cov_full, done = _fit_spots(
        windows, theta, c0.astype(float), r0.astype(float), read, gain
    )
    return BlobSet(
        theta[:, :2].copy(),
        cov_full[:, :2, :2].copy(),
        theta[:, 2].copy(),
        theta[:, 3].copy(),
        np.array(areas),
        done,
        lev,
        sig,
        threshold,
        method,
        binary[kept],
    )


def centroid_crb(
    centre: npt.ArrayLike,
    flux: float,
    sigma_px: float,
    noise: float,
    half_window: int | None = None,
    background: float = 0.0,
    gain: float | None = None,
) -> FloatArray:
    """Cramér–Rao bound (2, 2) on a spot's (x, y) from one frame: the inverse Fisher matrix of
    the pixel-integrated Gaussian spot with its flux, σ and background plane unknown, in the
    (2h + 1)² window :func:`extract_blobs` fits (module docstring). ``centre`` (x, y) pixels."""
    c = require_finite(centre, "centre").reshape(-1)
    if c.size != 2:
        raise FieldError("centre", f"must be (x, y), got {c.size} values")
    s = require_positive_scalar(sigma_px, "sigma_px")
    h = (
        int(np.ceil(4 * s)) + 1
        if half_window is None
        else require_count(half_window, "half_window")
    )
    noise_sd = require_positive_scalar(noise, "noise")
    f = require_positive_scalar(flux, "flux")
    r0, c0 = np.floor(c[1]) - h, np.floor(c[0]) - h
    theta = np.array([[c[0], c[1], f, s, float(background), 0.0, 0.0]])
    mu, jac = spot_window(theta, np.array([c0]), np.array([r0]), 2 * h + 1)
    var = np.full(mu.shape, noise_sd**2)
    if gain is not None:
        var = var + np.clip(mu, 0.0, None) / require_positive_scalar(gain, "gain")
    jr = jac.reshape(-1, 7)
    fisher = jr.T @ (jr / var.reshape(-1, 1))
    return np.linalg.inv(fisher)[:2, :2]


def centroid_crb_continuum(flux: float, sigma_px: float, noise: float) -> float:
    """Closed-form Cramér–Rao standard deviation of one coordinate of a Gaussian spot in white
    read noise, pixels ≪ σ: √(8π) s² σ_n / F (module docstring)."""
    s = require_positive_scalar(sigma_px, "sigma_px")
    return float(
        np.sqrt(8 * np.pi)
        * s**2
        * require_positive_scalar(noise, "noise")
        / require_positive_scalar(flux, "flux")
    )


# ----------------------------------------------------------------------------------------------
# cameras
# ----------------------------------------------------------------------------------------------
def _pitch(pixel_size: npt.ArrayLike) -> FloatArray:
    p = require_positive(pixel_size, "pixel_size", "m").reshape(-1)
    if p.size not in (1, 2):
        raise FieldError("pixel_size", f"must be a scalar or (px, py), got {p.size} values")
    return np.broadcast_to(p, (2,)).astype(float)


def _wh(shape: Sequence[int]) -> FloatArray:
    return np.array([float(shape[1]), float(shape[0])])


def pixels_to_image(
    pixels: npt.ArrayLike, pixel_size: npt.ArrayLike, shape: Sequence[int] = (244, 320)
) -> FloatArray:
    """Focal-plane (u, v) of pixel coordinates (x, y) on a (rows, columns) detector centred on
    the principal axis: u = (x − W/2) p_x, v = (y − H/2) p_y (photogrammetry's convention)."""
    px = require_numeric_pairs(pixels, "pixels")
    return (px - _wh(shape) / 2) * _pitch(pixel_size)


def image_to_pixels(
    image: npt.ArrayLike, pixel_size: npt.ArrayLike, shape: Sequence[int] = (244, 320)
) -> FloatArray:
    """Inverse of :func:`pixels_to_image`."""
    uv = require_numeric_pairs(image, "image")
    return uv / _pitch(pixel_size) + _wh(shape) / 2


def require_numeric_pairs(value: npt.ArrayLike, name: str) -> FloatArray:
    """An array whose last axis holds 2 coordinates (NaN allowed: a target out of view)."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != 2 or np.any(np.isinf(arr)):
        raise FieldError(name, f"must hold finite (x, y) pairs on the last axis, got {arr.shape}")
    return arr


def render_views(
    cameras: Sequence[Camera],
    points: npt.ArrayLike,
    pixel_size: npt.ArrayLike,
    spec: FrameSpec | None = None,
    seed: int | np.random.Generator | None = None,
) -> tuple[list[FloatArray], FloatArray]:
    """One rendered frame per camera of the targets at ``points`` (N, 3), and the true pixel
    centres (M, N, 2) (the collinearity projection of each point)."""
    sp = spec or FrameSpec()
    rng = np.random.default_rng(seed)
    truth = np.stack(
        [image_to_pixels(project(cam, points), pixel_size, sp.shape) for cam in cameras]
    )
    frames = [render_frame(t, sp, rng) for t in truth]
    return frames, truth


def match_targets(
    blobs: npt.ArrayLike, predicted: npt.ArrayLike, max_distance: float = 3.0
) -> npt.NDArray[np.int_]:
    """For each predicted target (N, 2) the index of its blob in ``blobs`` (K, 2), or −1 when no
    blob lies within ``max_distance`` pixels or the nearest blob is claimed by a closer target
    (targets must lie farther apart than twice their prediction error)."""
    from scipy.spatial import cKDTree

    b = require_numeric_pairs(blobs, "blobs").reshape(-1, 2)
    p = require_numeric_pairs(predicted, "predicted").reshape(-1, 2)
    dmax = require_positive_scalar(max_distance, "max_distance")
    out = np.full(p.shape[0], -1, dtype=int)
    if b.shape[0] == 0:
        return out
    dist, idx = cKDTree(b).query(np.nan_to_num(p, nan=-1e9), k=1)
    order = np.argsort(dist)
    taken: set[int] = set()
    for i in order:
        if np.isfinite(dist[i]) and dist[i] <= dmax and int(idx[i]) not in taken:
            out[i] = int(idx[i])
            taken.add(int(idx[i]))
    return out


def measure_views(
    cameras: Sequence[Camera],
    points: npt.ArrayLike,
    pixel_size: npt.ArrayLike,
    spec: FrameSpec | None = None,
    seed: int | np.random.Generator | None = None,
    method: str = "gaussian",
    max_distance: float = 3.0,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Render each camera's frame of the targets at ``points`` (N, 3), extract and match the
    blobs: focal-plane centroids (M, N, 2) for :func:`~flexsat.identify.photogrammetry.triangulate`
    (NaN where a target was not found), their standard deviations (M, N) in focal-plane units
    (the larger axis of each blob's predicted covariance), and the true centroids (M, N, 2)."""
    sp = spec or FrameSpec()
    frames, truth = render_views(cameras, points, pixel_size, sp, seed)
    pitch = _pitch(pixel_size)
    uv = np.full(truth.shape, np.nan)
    sd = np.full(truth.shape[:2], np.nan)
    for j, frame in enumerate(frames):
        blobs = extract_blobs(frame, sp.sigma_px, method=method, gain=sp.gain)
        idx = match_targets(blobs.centres, truth[j], max_distance)
        ok = idx >= 0
        uv[j, ok] = pixels_to_image(blobs.centres[idx[ok]], pitch, sp.shape)
        var = np.max(np.diagonal(blobs.covariance[idx[ok]], axis1=1, axis2=2), axis=1)
        sd[j, ok] = np.sqrt(var) * float(np.max(pitch))
    return uv, sd, pixels_to_image(truth, pitch, sp.shape)
