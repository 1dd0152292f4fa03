"""The collinearity camera model (:mod:`flexsat.identify.photogrammetry.camera`): projection,
Euler conventions, simulated centroids, OpenCV cross-check, bad camera parameters (issue #5
item 4)."""

import dataclasses

import numpy as np
import pytest

from flexsat.identify.photogrammetry import (
    Camera,
    euler_angles,
    look_at,
    project,
    rotation_matrix,
    simulate_centroids,
)
from flexsat.input_checks import FieldError
from stereo_rig import (
    PX,
    F,
    opencv_camera,
    stereo_pair,
    targets,
)


# ------------------------------------------------------------------------------ camera model
def test_projection_hand_case():
    pt = np.array([1.0, 2.0, 4.0])
    cam = Camera(position=[0, 0, 0], angles=[0, 0, 0], f=2.0, x0=0.1, y0=0.2, focal_sign=1)
    assert np.allclose(project(cam, pt), [0.1 + 2 * 1 / 4, 0.2 + 2 * 2 / 4])
    # Att. 8 sign: x = x0 - f X/Z
    cam8 = Camera(position=[0, 0, 0], angles=[0, 0, 0], f=2.0, x0=0.1, y0=0.2)
    assert np.allclose(project(cam8, pt), [0.1 - 0.5, 0.2 - 1.0])
    # phi = 90 deg (3-2-1): R3 maps (x, y, z) -> (y, -x, z); camera moved to (0, 0, -1)
    cam_r = Camera(position=[0, 0, -1], angles=[np.pi / 2, 0, 0], fx=2.0, fy=3.0, focal_sign=1)
    assert np.allclose(project(cam_r, pt), [2 * 2 / 5, 3 * -1 / 5])
    # Brown distortion on the ideal coordinates ub = 0.5, vb = 1.0 (r^2 = 1.25)
    k1, k2, p1, p2 = 0.01, 0.002, 0.003, -0.004
    camd = Camera(
        position=[0, 0, 0], angles=[0, 0, 0], f=2.0, focal_sign=1, k1=k1, k2=k2, p1=p1, p2=p2
    )
    ub, vb, r2 = 0.5, 1.0, 1.25
    du = ub * (k1 * r2 + k2 * r2**2) + p1 * (r2 + 2 * ub**2) + 2 * p2 * ub * vb
    dv = vb * (k1 * r2 + k2 * r2**2) + 2 * p1 * ub * vb + p2 * (r2 + 2 * vb**2)
    assert np.allclose(project(camd, pt), [ub + du, vb + dv])
    # the as-printed Att. 6 form (25)-(26) is a switch
    camp = Camera(
        position=[0, 0, 0],
        angles=[0, 0, 0],
        f=2.0,
        focal_sign=1,
        k1=k1,
        p1=p1,
        p2=p2,
        distortion="printed",
    )
    du = ub * k1 * r2 + p1 * (r2 + 2 * ub**2 * vb)
    dv = vb * k1 * r2 + p1 * (2 * ub**2 * vb) + p2 * (r2 + 2 * vb**2)
    assert np.allclose(project(camp, pt), [ub + du, vb + dv])
    # shapes: (..., 3) -> (..., 2)
    assert project(cam, np.zeros((4, 5, 3)) + pt).shape == (4, 5, 2)


def test_euler_conventions_round_trip_and_formulas():
    rng = np.random.default_rng(3)
    for euler in ("321", "123"):
        for _ in range(200):
            a = rng.uniform([-3, -1.5, -3], [3, 1.5, 3])
            c = rotation_matrix(a, euler)
            assert np.allclose(c @ c.T, np.eye(3)) and np.isclose(np.linalg.det(c), 1.0)
            assert np.allclose(euler_angles(c, euler), a)
    phi, th, psi = 0.3, -0.2, 0.7
    c = rotation_matrix([phi, th, psi], "321")  # Att. 8: R1(psi) R2(theta) R3(phi)
    assert np.allclose(c[0], [np.cos(th) * np.cos(phi), np.cos(th) * np.sin(phi), -np.sin(th)])
    assert np.isclose(c[1, 2], np.sin(psi) * np.cos(th))
    t1, t2, t3 = 0.3, -0.2, 0.7
    c = rotation_matrix([t1, t2, t3], "123")  # Att. 6: R3(t3) R2(t2) R1(t1)
    assert np.allclose(c[2], [np.sin(t2), -np.sin(t1) * np.cos(t2), np.cos(t1) * np.cos(t2)])
    assert not np.allclose(rotation_matrix([t1, t2, t3], "321"), c)
    with pytest.raises(ValueError, match="euler"):
        rotation_matrix([0, 0, 0], "313")
    with pytest.raises(ValueError, match="focal_sign"):
        Camera(position=[0, 0, 0], angles=[0, 0, 0], f=1.0, focal_sign=2)
    with pytest.raises(ValueError, match="^f: a focal length"):
        Camera(position=[0, 0, 0], angles=[0, 0, 0])
    with pytest.raises(ValueError, match="^position"):
        Camera(position=[0, np.nan, 0], angles=[0, 0, 0], f=1.0)


def test_simulated_centroids_quantized_field_and_shapes():
    rng = np.random.default_rng(0)
    cams = stereo_pair()
    pts = targets(rng)
    uv = simulate_centroids(cams, pts, PX, noise_px=0.3, seed=1)
    assert uv.shape == (2, 20, 2)
    frac = uv / PX - 0.5
    assert np.allclose(frac, np.round(frac))  # pixel centres
    assert np.max(np.abs(uv - np.stack([project(c, pts) for c in cams]))) < 2.5 * PX
    again = simulate_centroids(cams, pts, PX, noise_px=0.3, seed=1)
    assert np.array_equal(uv, again)
    far = np.array([[5.0, 0.0, 0.0]])  # outside the 320 x 244 field
    assert np.all(np.isnan(simulate_centroids(cams, far, PX, 0.0)))
    hist = np.broadcast_to(pts, (7, 20, 3))  # 7 fields (35 ms at 200 Hz)
    assert simulate_centroids(cams, hist, PX, 0.1, seed=2).shape == (2, 7, 20, 2)


# ------------------------------------------------------------------ OpenCV cross-check (optional)
@pytest.mark.parametrize("euler,sign", [("321", -1), ("123", 1)])
def test_projection_matches_opencv_with_brown_distortion(euler, sign):
    """Square pixels: the mapped coefficients reproduce cv2.projectPoints. Measured 6e-14 px
    (float64 roundoff on coordinates of 80 px); 1e-9 px allows for another evaluation order
    and is far below any centroid precision. The distortion moves the points by 2-3 px, so the
    check cannot pass with any term mapped wrongly."""
    cv2 = pytest.importorskip("cv2")
    pts = targets(np.random.default_rng(4), 50)
    for cam in stereo_pair(euler, sign, k1=5e4, k2=-2e10, p1=5.0, p2=-3.0, x0=2e-5, y0=-1e-5):
        k, rvec, tvec = opencv_camera(cv2, cam)
        f = cam.fx
        dist = np.array([cam.k1 * f**2, cam.k2 * f**4, sign * cam.p2 * f, sign * cam.p1 * f, 0.0])
        theirs = cv2.projectPoints(pts, rvec, tvec, k, dist)[0].reshape(-1, 2)
        ours = project(cam, pts) / PX
        plain = project(dataclasses.replace(cam, f=None, k1=0.0, k2=0.0, p1=0.0, p2=0.0), pts) / PX
        assert np.max(np.abs(ours - plain)) > 1.0
        assert np.max(np.abs(theirs - ours)) < 1e-9


def test_look_at_puts_the_target_on_the_optical_axis():
    """The aimed point projects to the principal point, in both focal-sign conventions."""
    for euler, sign in (("321", -1), ("123", 1)):
        cam = Camera(
            position=[1.0, 0.4, 2.0],
            angles=look_at([1.0, 0.4, 2.0], [0.1, 0.2, 0.0], euler, sign),
            f=F,
            euler=euler,
            focal_sign=sign,
        )
        assert np.allclose(project(cam, [0.1, 0.2, 0.0]), 0.0, atol=1e-15)
        # a point in front, off axis, projects off the principal point
        assert np.abs(project(cam, [0.3, 0.2, 0.0])).max() > 1e-4
    with pytest.raises(ValueError, match="target: the line of sight is along the world Y axis"):
        look_at([0, 2, 0], [0, 0, 0])


# ------------------------------------------------------------------------------ bad input
NAN = np.nan
NOT_ONE_NUMBER = [NAN, np.inf, [], "abc", np.ones(2), np.ones((2, 2))]


def _raises(field, call):
    with pytest.raises(FieldError) as err:
        call()
    assert err.value.field == field, str(err.value)


@pytest.mark.parametrize("bad", NOT_ONE_NUMBER, ids=repr)
@pytest.mark.parametrize("field", ["f", "fx", "x0", "y0", "k1", "k2", "p1", "p2"])
def test_camera_scalars_refused_by_name(field, bad):
    given = {"position": [0.0, 0.0, 10.0], "angles": [0.0, 0.0, 0.0], "f": 1.0, field: bad}
    if field == "fx":
        given.update(f=None, fy=1.0)
    _raises(field, lambda: Camera(**given))


@pytest.mark.parametrize("bad", NOT_ONE_NUMBER, ids=repr)
def test_centroid_noise_refused_by_name(bad):
    camera = Camera([0.0, 0.0, 10.0], [0.0, 0.0, 0.0], f=1.0)
    _raises("noise_px", lambda: simulate_centroids([camera], np.zeros((1, 3)), 1e-5, bad))
