"""Static calibration (:mod:`flexsat.identify.photogrammetry.calibration`): Att. 8 counting,
resection within its covariance, degenerate geometry, a-priori camera values (issue #5 item 4)."""

import numpy as np
import pytest
from scipy import stats

from flexsat.identify.photogrammetry import (
    CAMERA_PARAMETERS,
    DEFAULT_FREE,
    calibrate,
    calibration_counts,
    simulate_centroids,
)
from stereo_rig import (
    PX,
    F,
    perturbed,
    stereo_pair,
    targets,
)


# ------------------------------------------------------------------------------ counting rule
def test_counting_rule_att8():
    c = calibration_counts(12, 2, 9)
    assert (c["equations"], c["unknowns"], c["min_points"]) == (48, 48, 12)
    for n in (12, 20, 30):
        c = calibration_counts(n, 2, 9)
        assert c["equations"] == 4 * n and c["unknowns"] == 3 * n + 12
    assert calibration_counts(20, 2, 10)["min_points"] == 14  # separate fx, fy
    rng = np.random.default_rng(1)
    cams = stereo_pair()
    pts = targets(rng, 11)
    obs = simulate_centroids(cams, pts, PX, 0.1, quantize=False, seed=0)
    with pytest.raises(ValueError, match="too few.*N >= 12"):
        calibrate(obs, cams, pts, scale=(0, 1, 1.0), target_sigma=1e-3)


# ------------------------------------------------------------------------------ calibration
def nees_trials(n_trials, free, prior):
    z_all, nees = [], []
    idx = [CAMERA_PARAMETERS.index("fx" if n == "f" else n) for n in free]
    for trial in range(n_trials):
        rng = np.random.default_rng(1000 + trial)
        cams = stereo_pair(k1=0.0)
        pts = targets(rng)
        obs = simulate_centroids(cams, pts, PX, 0.1, quantize=False, seed=trial)
        init = [perturbed(c, rng, free) for c in cams]
        if prior:
            guess = pts + rng.normal(0, prior, pts.shape)
            res = calibrate(
                obs,
                init,
                guess,
                datum=None,
                scale=None,
                sigma=0.1 * PX,
                free=free,
                target_sigma=prior,
            )
        else:
            d = np.linalg.norm(pts[1] - pts[0])
            guess = pts.copy()
            guess[3:] += rng.normal(0, 0.003, (len(pts) - 3, 3))  # datum points stay exact
            res = calibrate(obs, init, guess, scale=(0, 1, d), sigma=0.1 * PX, free=free)
        est = np.concatenate([c.vector()[idx] for c in res.cameras])
        tru = np.concatenate([c.vector()[idx] for c in cams])
        k = est.size
        cov = res.covariance[:k, :k]
        err = est - tru
        z_all.append(err / np.sqrt(np.diag(cov)))
        nees.append(err @ np.linalg.solve(cov, err))
        assert 0.3 < res.sigma0_squared < 2.5
    return np.concatenate(z_all), np.array(nees), k


def test_calibration_with_a_priori_targets_within_3_sigma():
    """Att. 6 resection: 2 cameras x 9 parameters, 20 targets with 0.3 mm a-priori positions."""
    z, nees, k = nees_trials(100, DEFAULT_FREE, prior=3e-4)
    assert np.mean(np.abs(z) > 3) <= 0.02  # per parameter: 0.27 % expected
    # The joint NEES has a heavier tail than chi2(18): this two-view geometry is weak (x0, f and
    # attitude trade off), so the linearised covariance is curved ("banana") across trials.
    assert np.median(nees) < stats.chi2.ppf(0.99, k)


def test_calibration_datum_and_scale_within_3_sigma():
    """Att. 8 datum (point 0 origin, point 1 on X, point 2 in XY) and one known distance."""
    free = ("xc", "yc", "zc", "a1", "a2", "a3", "f")
    z, nees, k = nees_trials(30, free, prior=None)
    # per parameter within 3 sigma (the acceptance criterion); the joint NEES of this weak
    # two-view geometry (focal length against range) is far from chi2 and is not tested
    assert np.mean(np.abs(z) > 3) <= 0.03


def test_two_view_nine_parameter_self_calibration_is_reported_singular():
    """With x0, y0, f free and no a-priori targets two views leave an ambiguity (Kruppa)."""
    rng = np.random.default_rng(5)
    cams = stereo_pair()
    pts = targets(rng)
    obs = simulate_centroids(cams, pts, PX, 0.1, quantize=False, seed=0)
    d = np.linalg.norm(pts[1])
    with pytest.raises(ValueError, match="singular"):
        calibrate(obs, cams, pts, scale=(0, 1, d), sigma=0.1 * PX)


def test_calibration_degenerate_inputs():
    rng = np.random.default_rng(2)
    cams = stereo_pair()
    pts = targets(rng)
    obs = simulate_centroids(cams, pts, PX, 0.1, quantize=False, seed=0)
    line = np.outer(np.linspace(0, 0.5, 20), [1.0, 0, 0])
    with pytest.raises(ValueError, match="collinear"):
        calibrate(obs, cams, line, scale=(0, 1, 0.1))
    with pytest.raises(ValueError, match="^scale"):
        calibrate(obs, cams, pts, scale=None)
    with pytest.raises(ValueError, match="datum frame"):
        calibrate(obs, cams, pts + 0.1, scale=(0, 1, 0.1))
    bad = pts.copy()
    bad[2] = [0.2, 0.0, 0.0]  # datum points collinear
    with pytest.raises(ValueError, match="^datum"):
        calibrate(obs, cams, bad, scale=(0, 1, 0.1))
    with pytest.raises(ValueError, match="^initial_cameras"):
        calibrate(obs[:1], cams[:1], pts, scale=(0, 1, 0.1))
    with pytest.raises(ValueError, match="^observations"):
        calibrate(obs[:, :5], cams, pts, scale=(0, 1, 0.1))
    with pytest.raises(ValueError, match="^observations"):
        calibrate(np.full_like(obs, np.nan), cams, pts, scale=(0, 1, 0.1))
    with pytest.raises(ValueError, match="^free"):
        calibrate(obs, cams, pts, scale=(0, 1, 0.1), free=("xc", "zoom"))


def test_full_camera_covariance_layout(calibrated_rig):
    res = calibrated_rig
    full = res.full_camera_covariance()
    n = len(CAMERA_PARAMETERS)
    assert full.shape == (2 * n, 2 * n)
    fx, fy, k1 = (CAMERA_PARAMETERS.index(p) for p in ("fx", "fy", "k1"))
    for j in range(2):
        var_f = res.covariance[res.names.index(f"cam{j}.f"), res.names.index(f"cam{j}.f")]
        assert full[j * n + fx, j * n + fx] == full[j * n + fx, j * n + fy] == var_f
        assert not np.any(full[j * n + k1])  # k1 held fixed
    xc0, xc1 = CAMERA_PARAMETERS.index("xc"), n + CAMERA_PARAMETERS.index("xc")
    assert full[xc0, xc1] == res.covariance[res.names.index("cam0.xc"), res.names.index("cam1.xc")]


ATT6_FREE = ("xc", "yc", "zc", "a1", "a2", "a3", "fx", "fy", "x0", "y0", "k1", "p1", "p2")
#: a-priori camera uncertainty matching ``perturbed`` (distortion: ~0.1 px at the field edge)
ATT6_SIGMA = {
    "xc": 0.02,
    "yc": 0.02,
    "zc": 0.02,
    "a1": 0.01,
    "a2": 0.01,
    "a3": 0.01,
    "fx": 0.01 * F,
    "fy": 0.01 * F,
    "x0": 1e-5,
    "y0": 1e-5,
    "k1": 1e3,
    "p1": 0.03,
    "p2": 0.03,
}


def att6_trial(trial):
    rng = np.random.default_rng(2000 + trial)
    cams = stereo_pair()
    pts = targets(rng)
    obs = simulate_centroids(cams, pts, PX, 0.1, quantize=False, seed=trial)
    init = [perturbed(c, rng, ATT6_FREE) for c in cams]
    guess = pts + rng.normal(0, 3e-4, pts.shape)
    res = calibrate(
        obs,
        init,
        guess,
        datum=None,
        scale=None,
        sigma=0.1 * PX,
        free=ATT6_FREE,
        target_sigma=3e-4,
        camera_sigma=ATT6_SIGMA,
    )
    idx = [CAMERA_PARAMETERS.index(n) for n in ATT6_FREE]
    err = np.concatenate([a.vector()[idx] - b.vector()[idx] for a, b in zip(res.cameras, cams)])
    return res, err / np.sqrt(np.diag(res.covariance)[: err.size])


def test_att6_resection_dimensions_and_camera_priors():
    """Att. 6 eqs. (30)-(31): 13 parameters per camera (with v0), 20 targets, 2 cameras:
    Q has 80 image + 60 target + 26 camera measurements = 166, P has 60 + 26 = 86 unknowns;
    with the a-priori camera values weighted, the estimates stay within 3 sigma of their
    covariance (20 trials x 26 parameters; 0.27 % expected outside, 3 % allowed)."""
    z = []
    for trial in range(20):
        res, zt = att6_trial(trial)
        z.append(zt)
    assert res.counts["measurements"] == 166 and res.counts["unknowns_solved"] == 86
    assert np.mean(np.abs(np.concatenate(z)) > 3) <= 0.03


def test_camera_priors_resolve_two_view_self_calibration():
    """The nine-parameter two-view ambiguity (reported singular above) is removed by a-priori
    camera values, as in Att. 6."""
    rng = np.random.default_rng(5)
    cams = stereo_pair()
    pts = targets(rng)
    obs = simulate_centroids(cams, pts, PX, 0.1, quantize=False, seed=0)
    d = np.linalg.norm(pts[1])
    sig = {k: ATT6_SIGMA[k] for k in ("x0", "y0")} | {"f": 0.01 * F}
    res = calibrate(obs, cams, pts, scale=(0, 1, d), sigma=0.1 * PX, camera_sigma=sig)
    assert np.all(np.isfinite(res.covariance))
    with pytest.raises(ValueError, match="camera_sigma: 'k1' is not a free parameter"):
        calibrate(obs, cams, pts, scale=(0, 1, d), sigma=0.1 * PX, camera_sigma={"k1": 1.0})
    with pytest.raises(ValueError, match="camera_sigma: must be a mapping"):
        calibrate(obs, cams, pts, scale=(0, 1, d), sigma=0.1 * PX, camera_sigma=[{}])


def test_calibration_with_targets_out_of_view():
    """Targets a camera does not see are NaN: those image rows drop out (4 fewer equations per
    hidden target and camera), the fit stays within 4 sigma; a target no camera pair sees needs
    a-priori positions."""
    rng = np.random.default_rng(11)
    cams = stereo_pair()
    pts = targets(rng)
    obs = simulate_centroids(cams, pts, PX, 0.1, quantize=False, seed=2)
    obs[0, [5, 6]] = np.nan  # camera 0 misses targets 5 and 6
    obs[1, 7] = np.nan  # camera 1 misses target 7
    init = [perturbed(c, rng, DEFAULT_FREE) for c in cams]
    guess = pts + rng.normal(0, 3e-4, pts.shape)
    res = calibrate(obs, init, guess, datum=None, scale=None, sigma=0.1 * PX, target_sigma=3e-4)
    assert res.counts["equations"] == 2 * (2 * 20 - 3)
    assert np.all(np.isnan(res.residuals_px[0, [5, 6]]))
    assert np.all(np.isfinite(res.residuals_px[1, 5]))
    idx = [CAMERA_PARAMETERS.index("fx" if n == "f" else n) for n in DEFAULT_FREE]
    err = np.concatenate([a.vector()[idx] - b.vector()[idx] for a, b in zip(res.cameras, cams)])
    assert np.all(np.abs(err) < 4 * np.sqrt(np.diag(res.covariance)[: err.size]))
    with pytest.raises(
        ValueError,
        match=r"observations: targets \[5, 6, 7\] are seen by fewer "
        r"than 2 camera",
    ):
        d = np.linalg.norm(pts[1])
        calibrate(
            obs,
            cams,
            pts,
            scale=(0, 1, d),
            sigma=0.1 * PX,
            free=("xc", "yc", "zc", "a1", "a2", "a3", "f"),
        )
    half = obs.copy()
    half[1, 3, 0] = np.nan
    with pytest.raises(ValueError, match="observations: an unseen target must be NaN in both"):
        calibrate(half, init, guess, datum=None, scale=None, sigma=0.1 * PX, target_sigma=3e-4)
    blind = obs.copy()
    blind[0, :17] = np.nan
    with pytest.raises(ValueError, match="observations: camera 0 sees 3 targets, too few"):
        calibrate(blind, init, guess, datum=None, scale=None, sigma=0.1 * PX, target_sigma=3e-4)
