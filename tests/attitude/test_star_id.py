"""Star-pattern identification by inter-star angles (seed 000 §2.3.4, L280: identified when
>= 3 inter-star-angle triplets match within 5″ in each of two fields; unmatched stars are
deleted): per-field matching, ambiguity, mirror images, false stars, acceptance rules."""

from math import comb

import numpy as np
import pytest

from flexsat.attitude.star_camera import StarCamera, StarFrame
from flexsat.attitude.star_catalog import StarCatalog, synthetic_sky
from flexsat.attitude.star_id import match_field
from flexsat.attitude.star_tracker import ARCSEC, StarTracker, random_attitudes, score

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
