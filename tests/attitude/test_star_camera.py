"""Pinhole star camera on the photogrammetry model (seed 000 §2.3.4): projection, the inverse
pinhole, centroid noise, star counts per field, dropped and false stars."""

import numpy as np
import pytest

from flexsat.attitude.star_camera import StarCamera
from flexsat.attitude.star_catalog import StarCatalog, synthetic_sky
from flexsat.attitude.star_tracker import ARCSEC, random_attitudes
from flexsat.identify.photogrammetry import rotation_matrix
from flexsat.input_checks import FieldError


@pytest.fixture(scope="module")
def sky():
    return synthetic_sky(6.5, seed=0)


def test_focal_length_and_pixel_scale():
    cam = StarCamera()  # 12°, 4096 px of 5.5 µm
    assert cam.focal_length == pytest.approx(2048 * 5.5e-6 / np.tan(np.radians(6)), rel=1e-14)
    # 12° over 4096 px is 10.55″ per pixel at the boresight (to the tan's 0.4 % at 6°)
    assert cam.pixel_angle / ARCSEC == pytest.approx(12 * 3600 / 4096, rel=5e-3)
    assert cam.direction_sigma == pytest.approx(0.1 * cam.pixel_angle)
    np.testing.assert_allclose(
        StarCamera(mounting=(0, "90 deg", 0)).boresight, [1, 0, 0], atol=1e-15
    )


def test_gnomonic_projection_of_known_directions():
    # stars placed on the camera x axis at angle a image at n/2 + f tan(a)/pitch (the pinhole)
    cam = StarCamera(centroid_noise=0.0)
    a = np.radians([0.0, 1.0, 4.5, -5.0])
    r = np.stack([np.sin(a), np.zeros_like(a), np.cos(a)], 1)
    cat = StarCatalog(np.arange(4), np.zeros(4), r)
    frame = cam.observe(np.eye(3), cat, np.random.default_rng(0))
    px = frame.pixels[np.argsort(frame.truth)]
    np.testing.assert_allclose(
        px[:, 0], 2048 + cam.focal_length * np.tan(a) / cam.pixel_pitch, rtol=1e-13
    )
    np.testing.assert_allclose(px[:, 1], 2048, atol=1e-9)


def test_noise_free_directions_are_the_rotated_catalogue(sky):
    cam = StarCamera(centroid_noise=0.0, mounting=("10 deg", "-30 deg", "45 deg"))
    C_bn = random_attitudes(1, seed=3)[0]
    f = cam.observe(C_bn, sky, np.random.default_rng(0))
    expected = sky.vectors[f.truth] @ (rotation_matrix(cam.mounting) @ C_bn).T
    np.testing.assert_allclose(f.vectors, expected, atol=1e-14)


def test_centroid_noise_has_the_stated_sigma(sky):
    cam, ideal = StarCamera(centroid_noise=0.1), StarCamera(centroid_noise=0.0)
    att = random_attitudes(100, seed=1)
    d = []
    for k, C in enumerate(att):
        f = cam.observe(C, sky, np.random.default_rng(k))
        g = ideal.observe(C, sky, np.random.default_rng(k))
        common, i, j = np.intersect1d(f.truth, g.truth, return_indices=True)
        d.append(f.pixels[i] - g.pixels[j])
    d = np.concatenate(d).ravel()  # both axes pooled, ~3000 samples: sd of the sd ≈ 1.3 %
    assert np.std(d) == pytest.approx(0.1, rel=0.1)


def test_mean_star_count_matches_the_sky_density(sky):
    # a square field of full angle a subtends Ω = 4 arcsin(sin²(a/2)); 5000 stars on 4π sr
    cam = StarCamera()
    omega = 4 * np.arcsin(np.sin(cam.field_of_view / 2) ** 2)
    rng = np.random.default_rng(2)
    counts = [len(cam.observe(C, sky, rng)) for C in random_attitudes(400, seed=2)]
    mean = 5000 * omega / (4 * np.pi)  # ≈ 17.4; Poisson sd of the 400-frame mean ≈ 0.21
    assert np.mean(counts) == pytest.approx(mean, abs=5 * np.sqrt(mean / 400))


def test_dropped_and_false_stars(sky):
    cam = StarCamera()
    C = random_attitudes(1, seed=5)[0]
    full = cam.observe(C, sky, np.random.default_rng(0))
    f = cam.observe(C, sky, np.random.default_rng(0), false_stars=2, missing_fraction=0.2)
    n = len(full)
    assert np.sum(f.truth >= 0) == n - int(np.floor(0.2 * n + 0.5))
    assert np.sum(f.truth == -1) == 2
    assert set(f.truth[f.truth >= 0]) <= set(full.truth)
    assert np.all((f.pixels >= 0) & (f.pixels < cam.n_pixels))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(field_of_view=0), "field_of_view: must be > 0"),
        (dict(field_of_view="150 deg"), "below 120°"),
        (dict(n_pixels=1), "n_pixels: must be >= 2"),
        (dict(pixel_pitch=-1e-6), "pixel_pitch"),
        (dict(centroid_noise=-0.1), "centroid_noise: must be one finite number >= 0"),
        (dict(magnitude_limit=np.nan), "magnitude_limit"),
        (dict(mounting=(0, 0)), "mounting: must be 3"),
    ],
)
def test_bad_camera_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        StarCamera(**kwargs)


def test_bad_frame_requests(sky):
    cam, rng = StarCamera(), np.random.default_rng(0)
    with pytest.raises(ValueError, match="missing_fraction: must lie in"):
        cam.observe(np.eye(3), sky, rng, missing_fraction=1.0)
    with pytest.raises(ValueError, match="false_stars: must be a positive integer"):
        cam.observe(np.eye(3), sky, rng, false_stars=-1)


def test_a_pixel_below_any_detector_s_is_refused():
    # 1e-300 m made the focal length and image coordinates subnormal (divide by zero)
    with pytest.raises(FieldError, match=r"pixel_pitch: 1e-300 m is below 1e-07 m"):
        StarCamera(pixel_pitch="1e-300 m")


def test_mountings_must_be_three_angles_not_a_nested_list():
    with pytest.raises(ValueError, match=r"mounting: must be 3 finite"):
        StarCamera(mounting=[[0.0, 0.0, 0.0]])
