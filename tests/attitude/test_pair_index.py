"""Catalogue pair index (Mortari's k-vector) against the brute-force scan and an O(N²) list."""

import numpy as np
import pytest

from flexsat import limits
from flexsat.attitude.pair_index import (
    BruteForceIndex,
    KVectorIndex,
    catalog_pairs,
    expected_pairs,
)
from flexsat.attitude.star_catalog import StarCatalog, synthetic_sky
from flexsat.input_checks import FieldError


@pytest.fixture(scope="module")
def sky():
    return synthetic_sky(6.5, seed=0)


def test_every_pair_within_the_field_is_stored():
    small = synthetic_sky(4.0, seed=4)  # 281 stars: every pair by brute force
    first, second, theta = catalog_pairs(small, np.radians(20))
    v = small.vectors
    ang = np.arccos(np.clip(v @ v.T, -1, 1))
    i, j = np.nonzero(np.triu(ang <= np.radians(20), 1))
    assert set(zip(i, j)) == set(zip(first, second))
    # the chord form agrees with arccos to its ~1e-8 rad cancellation error near 0
    np.testing.assert_allclose(theta, ang[first, second], atol=1e-7)


def test_kvector_query_equals_the_brute_force_scan(sky):
    kv = KVectorIndex(sky, np.radians(17))
    bf = BruteForceIndex(sky, np.radians(17))
    rng = np.random.default_rng(0)
    centre = np.concatenate(
        [
            rng.uniform(0, np.radians(18), 300),
            kv.angles[rng.integers(0, len(kv), 100)],  # bounds on stored values
            [-1.0, 0.0, np.radians(17), 1.0],
        ]
    )  # outside the range
    half = np.concatenate([rng.uniform(0, 1e-4, 400), [1e-5, 1e-5, 1e-5, 1e-5]])
    half[300:400:2] = 0.0  # a zero-width query hits exactly the stored angle
    qk, rk = kv.query(centre - half, centre + half)
    qb, rb = bf.query(centre - half, centre + half)
    assert qk.size > 1000
    assert sorted(zip(qk, rk)) == sorted(zip(qb, rb))
    assert np.all(np.diff(kv.angles) >= 0)


def test_kvector_superset_is_small(sky):
    # the k-vector's point: the candidate range before trimming exceeds the answer by ~1 entry
    # per end (the pair-angle distribution is smooth, so z(i) = m i + q follows it closely)
    kv = KVectorIndex(sky, np.radians(17))
    lo = np.radians(np.linspace(0.5, 16, 200))
    hi = lo + np.radians(5 / 3600)
    jb = np.floor((lo - kv.q) / kv.m).astype(int) - 1
    jt = np.ceil((hi - kv.q) / kv.m).astype(int)
    superset = kv.k[jt] - kv.k[jb]
    answer = np.searchsorted(kv.angles, hi, "right") - np.searchsorted(kv.angles, lo, "left")
    assert np.mean(superset - answer) < 4


def test_bad_index_input():
    with pytest.raises(ValueError, match=r"max_angle: must lie in \(0, π\)"):
        KVectorIndex(synthetic_sky(6.5), 0.0)
    axes = StarCatalog([1, 2, 3], [1.0, 1.0, 1.0], np.eye(3))
    with pytest.raises(ValueError, match="catalog: no two of its 3 stars lie within 10°"):
        KVectorIndex(axes, np.radians(10))
    with pytest.raises(ValueError, match="catalog: must be a StarCatalog"):
        BruteForceIndex(np.eye(3), 0.1)


def test_expected_pairs_is_the_uniform_sky_count(sky):
    # for points uniform on the sphere two pairs sharing a star are independent events, so the
    # count is C(N, 2) Bernoulli(p) draws with no covariance: σ = √(C(N, 2) p (1 − p))
    angle = np.radians(17)
    n = len(sky)
    p = 0.5 * (1 - np.cos(angle))
    sigma = np.sqrt(0.5 * n * (n - 1) * p * (1 - p))
    stored = len(KVectorIndex(sky, angle))
    assert abs(stored - expected_pairs(n, angle)) < 5 * sigma


@pytest.mark.parametrize("index", [KVectorIndex, BruteForceIndex])
def test_count_is_the_size_of_the_query(sky, index):
    idx = index(sky, np.radians(17))
    lo = np.radians(np.linspace(0.01, 17.5, 300))
    hi = lo + np.radians(np.linspace(0, 0.2, 300))
    qid, _ = idx.query(lo, hi)
    assert idx.count(lo, hi) == qid.size


def test_an_index_beyond_the_pair_limit_is_refused_before_it_is_built(sky, monkeypatch):
    monkeypatch.setattr(limits, "MAX_CATALOG_PAIRS", 1000)
    with pytest.raises(FieldError, match=r"catalog: its 5,000 stars form about .* pairs") as err:
        KVectorIndex(sky, np.radians(17))
    assert "MAX_CATALOG_PAIRS" in str(err.value)
