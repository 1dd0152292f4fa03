"""The stereo rig of the photogrammetry tests (tests/identify/test_camera.py,
test_calibration.py, test_triangulation.py): two cameras with skew optical axes, targets
in the datum frame, perturbed starting cameras, a calibrated rig and the OpenCV mapping."""

import numpy as np

from flexsat.identify.photogrammetry import (
    CAMERA_PARAMETERS,
    Camera,
    calibrate,
    look_at,
    simulate_centroids,
)

PX = 1e-5  # 10 micrometre pixels
F = 0.004  # 4 mm lens: the 320 x 244 field spans about +-0.4 x +-0.3 rad


def stereo_pair(euler="321", sign=-1, **kw):
    # the optical axes are skew (aimed at different points): with intersecting axes the two
    # focal lengths are not determined by image data (a classic two-view degeneracy)
    return [
        Camera(
            position=p, angles=look_at(p, aim, euler, sign), f=F, euler=euler, focal_sign=sign, **kw
        )
        for p, aim in (([-1.3, 0.2, 2.0], [0.0, 0.15, 0.0]), ([1.3, -0.2, 2.0], [0.0, -0.15, 0.0]))
    ]


def targets(rng, n=20):
    t = np.column_stack(
        [rng.uniform(-0.35, 0.35, n), rng.uniform(-0.3, 0.3, n), rng.uniform(-0.4, 0.4, n)]
    )
    t[0] = 0.0
    t[1, 1:] = 0.0
    t[2, 2] = 0.0
    return t


def perturbed(cam, rng, free):
    v = cam.vector()
    v[:3] += rng.normal(0, 0.02, 3)
    v[3:6] += rng.normal(0, 0.01, 3)
    if "x0" in free:
        v[6:8] += rng.normal(0, 1e-5, 2)
    v[8] = v[9] = v[8] * (1 + 0.01 * rng.normal())
    return cam.with_vector(v)


# ------------------------------------------------------------------ camera uncertainty (eqs. 34-37)
# x0, y0 held fixed: with Att. 8's nine parameters this two-view rig trades x0 against attitude
# (sigma about 1e-2 rad), where the first-order propagation is no longer accurate (triangulate
# notes); without them the attitude sigma is 7e-4 rad.
RIG_FREE = ("xc", "yc", "zc", "a1", "a2", "a3", "f")


def calibrate_rig():
    """Att. 6 resection (0.3 mm a-priori targets, 0.1 px) of a pair with Brown distortion."""
    rng = np.random.default_rng(21)
    cams = stereo_pair(k1=2e3, p1=-1e-3, p2=5e-4)
    pts = targets(rng)
    obs = simulate_centroids(cams, pts, PX, 0.1, quantize=False, seed=4)
    init = [perturbed(c, rng, RIG_FREE) for c in cams]
    guess = pts + rng.normal(0, 3e-4, pts.shape)
    return calibrate(
        obs, init, guess, datum=None, scale=None, sigma=0.1 * PX, target_sigma=3e-4, free=RIG_FREE
    )


def sample_cameras(res, rng, scale=1.0):
    """Cameras deviating from the calibrated ones by a draw from scale^2 x its covariance."""
    lam, vec = np.linalg.eigh(res.full_camera_covariance())
    dev = scale * vec @ (np.sqrt(np.clip(lam, 0, None)) * rng.standard_normal(lam.size))
    n = len(CAMERA_PARAMETERS)
    return [c.with_vector(c.vector() + dev[j * n : (j + 1) * n]) for j, c in enumerate(res.cameras)]


def opencv_camera(cv2, cam):
    """Camera matrix (pixels, principal point at the detector centre), rvec, tvec (mapping in
    the photogrammetry module docstring)."""
    s = cam.focal_sign
    k = np.array(
        [[s * cam.fx / PX, 0.0, cam.x0 / PX], [0.0, s * cam.fy / PX, cam.y0 / PX], [0.0, 0.0, 1.0]]
    )
    rvec = cv2.Rodrigues(cam.matrix)[0]
    return k, rvec, -cam.matrix @ np.asarray(cam.position)
