"""Star catalogues (seed 000 §2.3.4): the synthetic sky's counts and uniformity, and the
Hipparcos hip_main.dat loader on a small file in the same format."""

import numpy as np
import pytest
from scipy import stats

from flexsat.attitude.star_catalog import (
    MIN_STARS,
    STARS_BRIGHTER_THAN_6_5,
    StarCatalog,
    load_hipparcos,
    synthetic_sky,
)
from flexsat.input_checks import FieldError


@pytest.fixture(scope="module")
def sky():
    return synthetic_sky(6.5, seed=0)


def test_synthetic_sky_holds_the_calibrated_count_to_6_5(sky):
    assert len(sky) == STARS_BRIGHTER_THAN_6_5 == 5000
    assert sky.magnitudes.max() <= 6.5


def test_star_counts_grow_about_threefold_per_magnitude(sky):
    # log10 N(<m) = 0.5 m + c: N(<5.5)/N(<6.5) = 10^-0.5; the sampled fraction is binomial,
    # sd = sqrt(p(1 - p)/N) = 0.0066, so 4 sd = 0.027
    for m in (5.5, 4.5):
        p = 10 ** (0.5 * (m - 6.5))
        frac = np.mean(sky.magnitudes <= m)
        assert abs(frac - p) <= 4 * np.sqrt(p * (1 - p) / len(sky))
    # a deeper sky is 10^0.5 times larger per magnitude
    assert len(synthetic_sky(7.5, seed=0)) == round(5000 * 10**0.5)


def test_synthetic_sky_is_uniform_on_the_sphere(sky):
    # each component of a uniform unit vector has variance 1/3: the mean's sd is sqrt(1/(3N))
    assert np.all(np.abs(sky.vectors.mean(0)) <= 4 * np.sqrt(1 / (3 * len(sky))))
    # z = sin(dec) is uniform on [-1, 1] (Archimedes): a KS test at the 1e-3 level
    assert stats.kstest(sky.vectors[:, 2], stats.uniform(-1, 2).cdf).pvalue > 1e-3
    np.testing.assert_allclose(np.linalg.norm(sky.vectors, axis=1), 1.0, atol=1e-15)


def test_synthetic_sky_is_seeded(sky):
    np.testing.assert_array_equal(synthetic_sky(6.5, seed=0).vectors, sky.vectors)
    assert not np.array_equal(synthetic_sky(6.5, seed=1).vectors, sky.vectors)


def _hip_line(hip, vmag, ra, dec):
    """One hip_main.dat line: 78 '|'-separated fields, HIP at 1, Vmag at 5, RAdeg/DEdeg at 8/9
    (the ReadMe of CDS I/239); the other fields are filled as in the real file."""
    f = [""] * 78
    f[0], f[1], f[2] = "H", f"{hip:12d}", " "
    f[3], f[4] = "06 45 08.92", "-16 42 58.0"
    f[5] = "" if vmag is None else f"{vmag:5.2f}"
    f[6], f[7] = " ", "G"
    f[8] = "" if ra is None else f"{ra:012.8f}"
    f[9] = "" if dec is None else f"{dec:+012.8f}"
    f[10], f[11] = " ", "379.21"
    return "|".join(f) + "\n"


# Sirius, Canopus, Arcturus, Vega as in hip_main.dat (V, RA, Dec in degrees)
STARS = [
    (32349, -1.44, 101.28854105, -16.71314306),
    (30438, -0.62, 95.98787763, -52.69571799),
    (69673, -0.05, 213.91811403, 19.18726997),
    (91262, 0.03, 279.23410832, 38.78299311),
]


@pytest.fixture
def hip_file(tmp_path):
    p = tmp_path / "hip_main.dat"
    p.write_text(
        "".join(_hip_line(*s) for s in STARS)
        + _hip_line(55203, None, None, None)  # no astrometric solution: skipped
        + _hip_line(1, 9.10, 0.00091185, 1.08901332)
    )
    return p


def test_hipparcos_loader_reads_ids_magnitudes_and_directions(hip_file):
    cat = load_hipparcos(hip_file)
    assert cat.ids.tolist() == [32349, 30438, 69673, 91262, 1]
    np.testing.assert_allclose(cat.magnitudes, [-1.44, -0.62, -0.05, 0.03, 9.10])
    # Sirius–Canopus angle by the haversine formula, independent of the loader's unit vectors
    (_, _, a1, d1), (_, _, a2, d2) = np.radians(STARS[0]), np.radians(STARS[1])
    hav = np.sin((d2 - d1) / 2) ** 2 + np.cos(d1) * np.cos(d2) * np.sin((a2 - a1) / 2) ** 2
    angle = 2 * np.arcsin(np.sqrt(hav))
    np.testing.assert_allclose(np.arccos(cat.vectors[0] @ cat.vectors[1]), angle, rtol=1e-12)
    assert len(load_hipparcos(hip_file, magnitude_limit=6.5)) == 4


def test_empty_or_too_small_catalogues_are_refused(tmp_path, hip_file):
    empty = tmp_path / "empty.dat"
    empty.write_text("")
    with pytest.raises(ValueError, match=f"at least {MIN_STARS}"):
        load_hipparcos(empty)
    with pytest.raises(ValueError, match=f"at least {MIN_STARS}"):
        load_hipparcos(hip_file, magnitude_limit=-0.5)  # only Sirius and Canopus left
    with pytest.raises(ValueError, match="at least 3 stars"):
        StarCatalog([1, 2], [1.0, 2.0], [[1, 0, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match="at least 3"):
        synthetic_sky(-1.4)
    with pytest.raises(ValueError, match="only 0 stars"):
        synthetic_sky(6.5).brighter_than(-3)


def test_bad_catalogue_files_name_the_line(tmp_path):
    with pytest.raises(ValueError, match="no Hipparcos catalogue file"):
        load_hipparcos(tmp_path / "missing.dat")
    short = tmp_path / "short.dat"
    short.write_text("H|1|x|y\n")
    with pytest.raises(ValueError, match=r"short.dat:1: .*'\|'-separated fields"):
        load_hipparcos(short)
    bad = tmp_path / "bad.dat"
    bad.write_text(_hip_line(1, 1.0, 10.0, 5.0).replace("010.00000000", "ten"))
    with pytest.raises(ValueError, match="bad.dat:1: HIP, Vmag, RAdeg and DEdeg must be numbers"):
        load_hipparcos(bad)
    with pytest.raises(ValueError, match="vectors: must be unit"):
        StarCatalog([1, 2, 3], [1.0, 2.0, 3.0], [[2, 0, 0], [0, 1, 0], [0, 0, 1]])


@pytest.mark.parametrize("limit", [30.0, 1e6])
def test_a_sky_beyond_the_star_limit_is_refused_before_it_is_drawn(limit):
    # m = 30 would be ~10^15.7 stars (20 PiB), m = 1e6 overflows 10^x: both refused by name
    with pytest.raises(FieldError, match=r"magnitude_limit: .*MAX_CATALOG_STARS") as err:
        synthetic_sky(limit)
    assert err.value.field == "magnitude_limit"


def test_the_calibration_count_must_be_a_count():
    for bad in (float("inf"), 0, 2.5, True):
        with pytest.raises(FieldError, match="stars_brighter_than_6_5"):
            synthetic_sky(6.5, stars_brighter_than_6_5=bad)
