"""Catalogue pair index (Mortari's k-vector) against the brute-force scan and an O(N²) list."""

import numpy as np
import pytest

from flexsat.attitude.pair_index import BruteForceIndex, KVectorIndex, catalog_pairs
from flexsat.attitude.star_catalog import StarCatalog, synthetic_sky


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
