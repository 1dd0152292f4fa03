"""Static calibration (resection) of stereo cameras from images of targets.

Sources (Att. 6 and 8 of Junkins, Pollock & Rahman 1990):

* Att. 6 (James & Junkins 1989), eqs. (22)–(29): ``u = u0 + du + f_u (C1.d)/(C3.d)`` with a
  (1,2,3) Euler matrix ``C = R3(t3) R2(t2) R1(t1)``, separate ``f_u, f_v`` and Brown distortion.
* Att. 8 (Junkins & James 1988), eq. (1): ``x = x0 - f (C1.d)/(C3.d)`` with the 3-2-1 matrix
  ``C = R1(psi) R2(theta) R3(phi)``, angles stored in the order ``(phi, theta, psi)``.

Calibration (resection) follows Att. 8's counting: with the datum of §3.3 (point ``i0`` at the
origin, point ``i1`` on the X axis, point ``i2`` in the XY plane) the unknowns are
``3N - 6 + p M`` (``p`` free parameters per camera, ``M`` cameras) against ``2 M N`` image
equations, i.e. ``4N`` equations and ``3N + 12`` unknowns for two 9-parameter cameras, so
``N >= 12``.  The scale left free by the datum is fixed by a known distance (``scale``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix

from flexsat.identify.photogrammetry.camera import (
    CAMERA_PARAMETERS,
    Camera,
    check_cameras,
    project,
    project_vector,
)
from flexsat.input_checks import (
    FieldError,
    require_numeric,
    require_positive,
    require_positive_scalar,
)
from flexsat.units import FloatArray

__all__ = [
    "DEFAULT_FREE",
    "CalibrationResult",
    "calibration_counts",
    "calibrate",
]

#: Att. 8's nine calibration unknowns per camera (``"f"`` ties ``fx = fy``).
DEFAULT_FREE = ("xc", "yc", "zc", "a1", "a2", "a3", "x0", "y0", "f")
_FREE_NAMES = set(CAMERA_PARAMETERS) | {"f"}


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
    cams = check_cameras(initial_cameras, "initial_cameras", minimum=2)
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
                project_vector(vecs[j], cams[j].euler, cams[j].focal_sign, cams[j].distortion, t)[0]
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
