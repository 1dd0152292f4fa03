"""Star-pattern identification by inter-star angles (seed 000 §2.3.4, L280: identified when
>= 3 inter-star-angle triplets match within 5″ in each of two fields; unmatched stars are
deleted): per-field matching, ambiguity, mirror images, false stars, acceptance rules."""

from math import comb

import numpy as np
import pytest

from flexsat import limits
from flexsat.attitude import star_id
from flexsat.attitude.star_camera import StarCamera, StarFrame
from flexsat.attitude.star_catalog import StarCatalog, synthetic_sky
from flexsat.attitude.star_id import match_field
from flexsat.attitude.star_tracker import ARCSEC, StarTracker, random_attitudes, score
from flexsat.input_checks import FieldError

CAMERAS = (StarCamera(), StarCamera(mounting=(0, "90 deg", 0)))


@pytest.fixture(scope="module")
def sky():
    return synthetic_sky(6.5, seed=0)


@pytest.fixture(scope="module")
def tracker(sky):
    return StarTracker(CAMERAS, sky)


def test_a_clean_field_is_matched_star_for_star(tracker):
    C = random_attitudes(1, seed=11)[0]
    frame = tracker.observe(C, np.random.default_rng(0))[0]
    fm = match_field(frame.vectors, tracker.index, tracker.tolerance)
    assert np.array_equal(fm.matches, frame.truth)
    assert fm.triplets == comb(len(frame), 3)


def test_false_stars_are_deleted_and_true_ones_kept(tracker):
    rng = np.random.default_rng(1)
    for C in random_attitudes(50, seed=12):
        for frame in tracker.observe(C, rng, false_stars=3, missing_fraction=0.2):
            fm = match_field(frame.vectors, tracker.index, tracker.tolerance)
            assert np.all(fm.matches[frame.truth == -1] == -1)
            kept = fm.matches >= 0
            assert np.array_equal(fm.matches[kept], frame.truth[kept])


def test_a_field_of_false_stars_matches_nothing(tracker):
    rng = np.random.default_rng(2)
    cam = tracker.cameras[0]
    vec = cam.directions(rng.uniform(0, cam.n_pixels, (12, 2)))
    assert match_field(vec, tracker.index, tracker.tolerance).triplets == 0


def test_an_ambiguous_sky_is_not_identified(sky):
    # a rotated copy of the stars of camera 0's field makes every measured pair match two
    # catalogue pairs equally: no star can be told from its twin, so nothing is accepted
    C = random_attitudes(1, seed=13)[0]
    seen = CAMERAS[0].observe(C, sky, np.random.default_rng(0)).truth
    twin = sky.vectors[seen] @ random_attitudes(1, seed=14)[0].T
    doubled = StarCatalog(
        np.concatenate([sky.ids, 10**6 + sky.ids[seen]]),
        np.concatenate([sky.magnitudes, sky.magnitudes[seen]]),
        np.vstack([sky.vectors, twin]),
    )
    tr = StarTracker(CAMERAS, doubled)
    frames = tr.observe(C, np.random.default_rng(0))
    ident = tr.identify(frames)
    assert not ident.accepted and "1 of 2 fields" in ident.reason
    assert ident.fields[0].n_matched == 0


def test_a_mirror_image_field_is_rejected_by_the_attitude_fit(tracker):
    # reflection keeps every inter-star angle, so the field matches; no rotation fits it
    C = random_attitudes(1, seed=15)[0]
    frames = tracker.observe(C, np.random.default_rng(3))
    f0 = frames[0]
    frames[0] = StarFrame(0, f0.pixels, f0.vectors * [-1, 1, 1], f0.truth, f0.magnitudes)
    assert match_field(frames[0].vectors, tracker.index, tracker.tolerance).triplets >= 3
    ident = tracker.identify(frames)
    assert not ident.accepted
    assert score(ident, frames) == (False, 0)


def test_one_field_alone_is_not_enough(tracker):
    # camera 1 sees no star: the paper asks for matched triplets in two fields
    C = random_attitudes(1, seed=16)[0]
    rng = np.random.default_rng(4)
    frames = tracker.observe(C, rng)
    frames[1] = StarFrame(1, np.zeros((0, 2)), np.zeros((0, 3)), np.zeros(0, int), np.zeros(0))
    ident = tracker.identify(frames)
    assert not ident.accepted and ident.reason.startswith("1 of 2 fields")
    one = StarTracker(CAMERAS, tracker.catalog, min_fields=1)
    assert one.identify(frames).accepted


def test_bad_tracker_settings(sky):
    with pytest.raises(ValueError, match="tolerance: .* below 3√2 σ"):
        StarTracker(CAMERAS, sky, tolerance="2 arcsec")
    with pytest.raises(ValueError, match="cameras: the identification needs 2 fields of view"):
        StarTracker(CAMERAS[:1], sky)
    with pytest.raises(ValueError, match="index: must be 'kvector' or 'brute'"):
        StarTracker(CAMERAS, sky, index="hash")
    with pytest.raises(ValueError, match="tolerance: must be one finite angle > 0"):
        StarTracker(CAMERAS, sky, tolerance=-5 * ARCSEC)
    with pytest.raises(ValueError, match="cameras\\[1\\]: must be a StarCamera"):
        StarTracker([CAMERAS[0], "camera"], sky)


def test_the_sparse_tally_equals_the_dense_table(tracker, monkeypatch):
    # the votes of a crowded field (300 false stars), tallied both ways: same hypotheses
    frame = tracker.observe(random_attitudes(1, seed=21)[0], np.random.default_rng(3), 300)[0]
    dense = match_field(frame.vectors, tracker.index, tracker.tolerance)
    monkeypatch.setattr(star_id, "DENSE_TALLY", 0)
    sparse = match_field(frame.vectors, tracker.index, tracker.tolerance)
    assert np.array_equal(dense.matches, sparse.matches) and dense.triplets == sparse.triplets
    assert dense.n_matched >= 3


def _reference_deletion(conflict, support):
    """The rule as stated: delete the star with the most conflicts among those alive (ties:
    fewest votes, then the first), recounting the whole table every time."""
    alive = np.ones(len(support), bool)
    while True:
        conflicts = np.where(alive, (conflict & alive[None, :]).sum(1), -1)
        if conflicts.max() <= 0:
            return alive
        tied = np.flatnonzero(conflicts == conflicts.max())
        alive[tied[np.argmin(support[tied])]] = False


@pytest.mark.parametrize("density", [0.02, 0.1, 0.5])
def test_the_updated_conflict_counts_delete_as_recounting_does(density):
    rng = np.random.default_rng(int(density * 100))
    for h in (1, 3, 40, 200):
        upper = np.triu(rng.random((h, h)) < density, 1)
        conflict = upper | upper.T
        support = rng.integers(2, 6, h)  # few distinct votes: many ties
        kept = star_id.consistent_stars(conflict, support)
        assert np.array_equal(kept, _reference_deletion(conflict, support))
        assert not np.any(conflict[np.ix_(kept, kept)])  # no conflict left among the kept


def test_a_field_beyond_the_candidate_limit_is_refused_before_voting(tracker, monkeypatch):
    frame = tracker.observe(random_attitudes(1, seed=23)[0], np.random.default_rng(4), 100)[0]
    monkeypatch.setattr(limits, "MAX_PAIR_CANDIDATES", 1000)
    with pytest.raises(FieldError, match=r"vectors: the field's .*MAX_PAIR_CANDIDATES") as err:
        match_field(frame.vectors, tracker.index, tracker.tolerance)
    assert err.value.field == "vectors"
