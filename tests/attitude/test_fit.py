"""q-method attitude and QUEST covariance, against scipy's Rotation.align_vectors (an
independent SVD solution of Wahba's problem) and a Monte Carlo of the errors."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from flexsat.attitude.fit import q_method, quest_covariance, rotation_error
from flexsat.attitude.star_tracker import ARCSEC, random_attitudes


def _stars(n, seed):
    rng = np.random.default_rng(seed)
    # two clusters 90° apart, like two star cameras' fields
    v = np.concatenate([rng.normal([0, 0, 1], 0.08, (n, 3)), rng.normal([1, 0, 0], 0.08, (n, 3))])
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_noise_free_vectors_give_the_attitude_exactly():
    C = random_attitudes(1, seed=1)[0]
    r = _stars(5, 0)
    C_est, beta, _ = q_method(r @ C.T, r)
    # eigenvector of a 4x4 symmetric matrix: a few eps of the matrix norm
    assert np.max(np.abs(rotation_error(C_est, C))) < 1e-13
    assert np.linalg.norm(beta) == pytest.approx(1.0, abs=1e-15) and beta[0] >= 0


def test_q_method_agrees_with_scipy_align_vectors():
    rng = np.random.default_rng(2)
    for k, C in enumerate(random_attitudes(20, seed=2)):
        r = _stars(8, k)
        sigma = rng.uniform(0.5, 2.0, r.shape[0]) * ARCSEC
        b = r @ C.T + rng.normal(0, 1, r.shape) * sigma[:, None]
        b /= np.linalg.norm(b, axis=1, keepdims=True)
        C_est, _, _ = q_method(b, r, sigma)
        R, _ = Rotation.align_vectors(b, r, weights=1 / sigma**2)
        # both minimise the same Wahba loss; they differ by the solvers' round-off
        assert np.max(np.abs(rotation_error(C_est, R.as_matrix()))) < 1e-10


def test_quest_covariance_predicts_the_errors():
    C = random_attitudes(1, seed=4)[0]
    r = _stars(6, 3)
    sigma = 2 * ARCSEC
    rng = np.random.default_rng(5)
    err = []
    for _ in range(3000):
        b = r @ C.T
        # tangential noise of sd sigma per axis (the QUEST measurement model)
        n = rng.normal(0, sigma, b.shape)
        n -= np.sum(n * b, 1, keepdims=True) * b
        b = b + n
        err.append(rotation_error(q_method(b, r, sigma)[0], C))
    err = np.array(err)
    P = quest_covariance(r @ C.T, sigma)
    # 3000 samples: a variance's sampling sd is sqrt(2/3000) = 2.6 %, so 12 % is > 4 sd
    np.testing.assert_allclose(np.var(err, 0), np.diag(P), rtol=0.12)
    assert np.mean(np.einsum("ni,ij,nj->n", err, np.linalg.inv(P), err)) == pytest.approx(
        3.0, abs=4 * np.sqrt(6 / 3000)
    )


def test_bad_attitude_input():
    with pytest.raises(ValueError, match="at least 2 non-parallel directions"):
        q_method([[0, 0, 1]], [[0, 0, 1]])
    with pytest.raises(ValueError, match="parallel"):
        q_method([[0, 0, 1], [0, 0, 2]], [[0, 0, 1], [0, 0, 1]])
    with pytest.raises(ValueError, match="sigma: direction noise must be finite and > 0"):
        q_method(np.eye(3), np.eye(3), 0.0)
    with pytest.raises(ValueError, match="shape"):
        q_method(np.eye(3), np.eye(2))
