"""Rendered frames, blob extraction and sub-pixel centroids (flexsat.identify.video_targets)."""

import numpy as np
import pytest
from scipy import ndimage
from scipy.stats import chi2

from flexsat.identify.photogrammetry import (
    Camera,
    look_at,
    project,
    simulate_centroids,
    triangulate,
)
from flexsat.identify.video_targets import (
    FrameSpec,
    centroid_crb,
    centroid_crb_continuum,
    extract_blobs,
    image_to_pixels,
    match_targets,
    measure_views,
    pixels_to_image,
    render_frame,
    spot_model,
    spot_window,
)
from flexsat.input_checks import FieldError

pytest.importorskip("cv2")  # connected components: the optional extra flexsat[opencv], in dev

#: 1,024 targets on a 16-pixel pitch (no two windows overlap), random sub-pixel phases
SPEC = FrameSpec(shape=(520, 520), sigma_px=1.2, flux=3000.0, background=50.0, noise=3.0)


def _targets(rng):
    g = np.arange(32) * 16 + 12.0
    x, y = np.meshgrid(g, g)
    return np.column_stack([x.ravel(), y.ravel()]) + rng.uniform(0, 1, (1024, 2))


def _chi2_bounds(dof, p=1e-3):
    return chi2.ppf(p / 2, dof), chi2.ppf(1 - p / 2, dof)


@pytest.mark.numerics
def test_spot_integrates_to_its_flux_and_its_first_moment_is_the_centre():
    img = spot_model([20.3], [15.8], 1000.0, 1.0, (40, 40))
    # Φ differences telescope: the 6σ+1 window holds all but 2e-9 of the flux
    assert img.sum() == pytest.approx(1000.0, rel=1e-8)
    rows, cols = np.indices(img.shape)
    # the binned Gaussian's pixel-centre moment differs from x by a periodic term of order
    # exp(-2π² s²) = 2.7e-9 at s = 1 (Poisson summation)
    assert (img * (cols + 0.5)).sum() / img.sum() == pytest.approx(20.3, abs=1e-7)
    assert (img * (rows + 0.5)).sum() / img.sum() == pytest.approx(15.8, abs=1e-7)


@pytest.mark.numerics
def test_spot_jacobian_matches_central_differences():
    theta = np.array([[7.3, 6.6, 900.0, 1.3, 40.0, 0.7, -0.4]])
    c0, r0 = np.array([1.0]), np.array([0.0])
    _, jac = spot_window(theta, c0, r0, 13)
    for a in range(7):
        h = 1e-5 * max(1.0, abs(theta[0, a]))
        tp, tm = theta.copy(), theta.copy()
        tp[0, a] += h
        tm[0, a] -= h
        fd = (spot_window(tp, c0, r0, 13)[0] - spot_window(tm, c0, r0, 13)[0]) / (2 * h)
        # central difference: truncation h² × third derivative ~ 1e-10 × flux; round-off
        # eps × 900 / h ~ 2e-8
        np.testing.assert_allclose(jac[..., a], fd, atol=1e-6 * max(1.0, np.abs(fd).max()))


@pytest.mark.parametrize("s", [2.0, 4.0, 8.0])
def test_location_fisher_information_tends_to_the_continuum_bound(s):
    """Σ (∂μ/∂x)² / σ_n² → F² / (8π s⁴ σ_n²) as the pixels shrink against the spot."""
    h = int(np.ceil(6 * s))
    theta = np.array([[h + 0.37, h + 0.61, 1000.0, s, 0.0, 0.0, 0.0]])
    _, jac = spot_window(theta, np.zeros(1), np.zeros(1), 2 * h + 1)
    info = np.sum(jac[..., 0] ** 2) / 2.0**2
    bound = centroid_crb_continuum(1000.0, s, 2.0) ** -2
    # pixel binning lowers the information by about 1/(8 s²) (variance of a uniform pixel, 1/12,
    # against the spot's curvature): the test allows 1/(4 s²)
    assert info == pytest.approx(bound, rel=1 / (4 * s**2))
    assert info < bound


def test_thousand_targets_bias_and_scatter_match_the_cramer_rao_bound():
    rng = np.random.default_rng(7)
    truth = _targets(rng)
    frame = render_frame(truth, SPEC, rng)
    blobs = extract_blobs(frame, SPEC.sigma_px)
    assert len(blobs) == 1024 and blobs.converged.all()
    idx = match_targets(blobs.centres, truth)
    assert np.all(idx >= 0) and np.unique(idx).size == 1024
    err = blobs.centres[idx] - truth
    var = np.diagonal(blobs.covariance[idx], axis1=1, axis2=2)
    crb = np.array([np.diag(centroid_crb(c, SPEC.flux, SPEC.sigma_px, SPEC.noise)) for c in truth])
    # the fit's covariance is the Cramér-Rao bound at the estimate: the noise estimate (MAD of
    # ~2e5 pixels) is good to 0.5 %; the window starts at the peak pixel rather than at the true
    # centre's, which moves the background plane's lever arm (up to 7 % per target, 1 % mean)
    np.testing.assert_allclose(var, crb, rtol=0.08)
    assert var.mean() == pytest.approx(crb.mean(), rel=0.02)
    # acceptance: bias below 0.02 px, and within 4 standard errors of zero
    mean = err.mean(axis=0)
    assert np.all(np.abs(mean) < 0.02)
    assert np.all(np.abs(mean) < 4 * np.sqrt(var.mean(axis=0) / 1024))
    # scatter consistent with the image noise: Σ err²/σ²_CRB ~ χ²(2048), two-sided 0.1 %
    lo, hi = _chi2_bounds(2048)
    assert lo < np.sum(err**2 / crb) < hi


def test_moment_centroid_scatter_matches_its_propagated_noise():
    rng = np.random.default_rng(8)
    truth = _targets(rng)
    blobs = extract_blobs(render_frame(truth, SPEC, rng), SPEC.sigma_px, method="moment")
    idx = match_targets(blobs.centres, truth)
    err = blobs.centres[idx] - truth
    var = np.diagonal(blobs.covariance[idx], axis1=1, axis2=2)
    h = int(np.ceil(4 * SPEC.sigma_px)) + 1
    n = 2 * h + 1
    # σ² = σ_n² n² h(h+1) / (3F²) for a centred window (module docstring), within the
    # off-centre lever arms (< 1 px of 6) and the flux estimate
    formula = SPEC.noise**2 * n**2 * h * (h + 1) / (3 * SPEC.flux**2)
    assert var.mean() == pytest.approx(formula, rel=0.05)
    lo, hi = _chi2_bounds(2048)
    assert lo < np.sum(err**2 / var) < hi
    # the moment centroid is ~6x worse than the fit here: the window's noise at its lever arms
    assert np.sqrt(var.mean()) > 4 * centroid_crb_continuum(SPEC.flux, SPEC.sigma_px, SPEC.noise)


def test_background_gradient_and_photon_noise_keep_the_fit_unbiased():
    rng = np.random.default_rng(9)
    truth = _targets(rng)[:400]
    rows, cols = np.indices(SPEC.shape)
    background = 40.0 + 0.05 * cols + 0.03 * rows  # 26 counts across the frame
    spec = FrameSpec(SPEC.shape, 1.2, 3000.0, 0.0, 3.0, gain=2.0)
    frame = render_frame(truth, spec, rng, background=background)
    blobs = extract_blobs(frame, 1.2, gain=2.0, noise=3.0)
    assert len(blobs) == 400  # the gradient makes no blob: the threshold follows the map
    idx = match_targets(blobs.centres, truth)
    assert np.all(idx >= 0)
    err = blobs.centres[idx] - truth
    var = np.diagonal(blobs.covariance[idx], axis1=1, axis2=2)
    assert np.all(np.abs(err.mean(axis=0)) < 4 * np.sqrt(var.mean(axis=0) / 400))
    lo, hi = _chi2_bounds(800)
    assert lo < np.sum(err**2 / var) < hi


def test_components_agree_with_scipy_labelling():
    rng = np.random.default_rng(10)
    truth = _targets(rng)[:100] * 0.5 + 3  # some targets close enough to touch
    frame = render_frame(truth, FrameSpec((270, 270), 1.0, 2000.0, 20.0, 2.0), rng)
    blobs = extract_blobs(frame, 1.0, min_area=1, half_window=1, level=20.0, noise=2.0)
    labels, count = ndimage.label(frame > blobs.threshold, structure=np.ones((3, 3)))
    assert len(blobs) == count
    # the binary (VP-110-like) centroid is the mean pixel centre of each component
    com = np.array(ndimage.center_of_mass(np.ones_like(frame), labels, range(1, count + 1)))
    ref = com[:, ::-1] + 0.5  # (row, col) indices -> (x, y) pixel centres
    idx = match_targets(ref, blobs.binary_centres, 0.01)
    np.testing.assert_allclose(ref[idx], blobs.binary_centres, atol=1e-12)


def test_binary_centroid_is_limited_by_its_quantization():
    """Counting pixels above a threshold quantizes: ~0.1 px whatever the noise, against the
    fit's Cramér-Rao 0.008 px (docs: the VP-110's 0.5 px and its 0.1 px upgrade goal)."""
    rng = np.random.default_rng(12)
    truth = _targets(rng)
    blobs = extract_blobs(render_frame(truth, SPEC, rng), SPEC.sigma_px)
    err = blobs.binary_centres[match_targets(blobs.centres, truth)] - truth
    sd = err.std(axis=0)
    crb = centroid_crb_continuum(SPEC.flux, SPEC.sigma_px, SPEC.noise)
    assert np.all(sd > 5 * crb) and np.all(sd < 0.3)
    assert np.all(np.abs(err.mean(axis=0)) < 4 * sd / np.sqrt(1024))  # unbiased over phases


def test_triangulated_points_from_rendered_frames_match_their_covariance():
    """Two 320 x 244 cameras (8 mm, 27 µm pixels) on the grid's 20 targets, 40 frames: the
    triangulated errors are consistent with triangulate's covariance built from the blobs'
    predicted centroid scatter, as for directly simulated centroids of that scatter."""
    s = 14.5 * 0.0254
    pts0 = np.array([[((n - 1) % 5) * s, ((n - 1) // 5) * s, 0.0] for n in range(1, 21)])
    rig = [
        ((-0.6, 0.5525, 2.4), (0.7366, 0.5525, 0.0)),
        ((2.0732, 0.5525, 2.4), (0.7366, 0.5525, 0.0)),
    ]
    cams = [Camera(position=p, angles=look_at(p, a), f=0.008) for p, a in rig]
    spec = FrameSpec(sigma_px=1.0, flux=1500.0, background=30.0, noise=3.0)
    rng = np.random.default_rng(11)
    nees_r = nees_d = 0.0
    frames = 40
    for _ in range(frames):
        pts = pts0 + np.column_stack([np.zeros((20, 2)), rng.normal(0, 0.01, 20)])
        uv, sd, truth = measure_views(cams, pts, 27e-6, spec, rng)
        assert np.all(np.isfinite(uv))
        # the true centroids are the collinearity projections, through the pixel round trip:
        # ε × 160 px × 27 µm = 1e-18 m
        np.testing.assert_allclose(truth[1], project(cams[1], pts), rtol=0, atol=1e-17)
        np.testing.assert_allclose(
            image_to_pixels(truth, 27e-6), truth / 27e-6 + [160, 122], rtol=1e-14
        )
        np.testing.assert_allclose(
            pixels_to_image(image_to_pixels(truth, 27e-6), 27e-6), truth, rtol=0, atol=1e-17
        )
        sigma = np.mean(sd, axis=1)
        p_r, c_r = triangulate(cams, uv, sigma)
        e = p_r - pts
        nees_r += np.einsum("ni,nij,nj->", e, np.linalg.inv(c_r), e)
        uvd = simulate_centroids(
            cams, pts, 27e-6, float(sigma.mean()) / 27e-6, quantize=False, seed=rng, field_px=None
        )
        p_d, c_d = triangulate(cams, uvd, sigma)
        e = p_d - pts
        nees_d += np.einsum("ni,nij,nj->", e, np.linalg.inv(c_d), e)
    lo, hi = _chi2_bounds(3 * 20 * frames)
    assert lo < nees_r < hi
    assert lo < nees_d < hi


def test_match_targets_and_bad_inputs():
    blobs = np.array([[10.0, 10.0], [30.0, 5.0], [50.0, 50.0]])
    pred = np.array([[30.5, 5.2], [9.0, 10.5], [80.0, 80.0]])
    np.testing.assert_array_equal(match_targets(blobs, pred), [1, 0, -1])
    with pytest.raises(FieldError, match="frame"):
        extract_blobs(np.zeros(5))
    with pytest.raises(FieldError, match="method"):
        extract_blobs(np.random.default_rng(0).normal(size=(20, 20)), method="edge")
    with pytest.raises(FieldError, match="sigma_px"):
        FrameSpec(sigma_px=0.0)
    with pytest.raises(FieldError, match="noise"):
        extract_blobs(np.ones((20, 20)))
    with pytest.raises(FieldError, match="background"):
        render_frame([[5.0, 5.0]], FrameSpec((10, 10)), background=np.zeros((3, 3)))
