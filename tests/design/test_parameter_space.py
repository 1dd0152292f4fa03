"""Parameter spaces of sweeps and Monte Carlo sets (issue 13): grids are the full factorial in the
stated order; Latin hypercube and Sobol' samples lie in their bounds, keep their stratification
and are reproducible from the seed; every distribution samples its own law (a truncated normal
stays in its bounds, a lognormal has the stated median); plain Monte Carlo gives the same cases
whatever the chunking; values are read in their units; bad input is refused by field and rule.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import stats

from flexsat.design.parameter_space import (
    GridAxis,
    GridSpace,
    LogNormal,
    Normal,
    ParameterSpace,
    TruncatedNormal,
    Uniform,
    parameter_from_spec,
    space_from_spec,
)
from flexsat.units import Q_, UnitError

#: seed 000's TAMU ranges: α in [0, 0.25], u_max in [100, 600] oz-in
TAMU_BOX = ParameterSpace(
    [Uniform("alpha", 0.0, 0.25), Uniform("u_max", "100 ozf*in", "600 ozf*in", "N*m")]
)
OZF_IN = Q_(1, "ozf*in").to("N*m").magnitude


def unit_points(table, space):
    """The table mapped back to the unit cube by each parameter's CDF."""
    return np.column_stack([p.frozen.cdf(table.values[p.name]) for p in space.parameters])


# -- grids -----------------------------------------------------------------------------------------
def test_grid_is_the_full_factorial_with_the_first_axis_slowest():
    alpha = GridAxis.linspace("alpha", 0.0, 0.25, 6)
    u_max = GridAxis("u_max", [f"{u} ozf*in" for u in (100, 200, 300, 400, 500, 600)], "N*m")
    mode = GridAxis("modes", [2, 10])
    space = GridSpace([alpha, u_max, mode])
    table = space.table()
    expected = list(itertools.product(alpha.values, u_max.values, mode.values))
    assert space.shape == (6, 6, 2) and space.size == len(table) == 72
    assert np.array_equal(table.matrix(), np.array(expected))
    assert np.allclose(u_max.values, OZF_IN * np.arange(100, 700, 100), rtol=1e-15, atol=0)
    # case k sits at grid index unravel_index(k, shape)
    k = 29
    i, j, m = np.unravel_index(k, space.shape)
    assert table.case(k) == {
        "alpha": alpha.values[i],
        "u_max": u_max.values[j],
        "modes": mode.values[m],
    }


# -- space-filling sequences -----------------------------------------------------------------------
@pytest.mark.parametrize("method, n", [("latin_hypercube", 100), ("sobol_sequence", 128)])
def test_sequences_lie_in_their_bounds_are_stratified_and_reproducible(method, n):
    table = getattr(TAMU_BOX, method)(n, seed=11)
    again = getattr(TAMU_BOX, method)(n, seed=11)
    other = getattr(TAMU_BOX, method)(n, seed=12)
    assert np.array_equal(table.matrix(), again.matrix())
    assert not np.array_equal(table.matrix(), other.matrix())
    assert np.all(table.values["alpha"] >= 0) and np.all(table.values["alpha"] <= 0.25)
    u_max = table.values["u_max"]
    assert np.all(u_max >= 100 * OZF_IN) and np.all(u_max <= 600 * OZF_IN)
    # both designs put exactly one point in each of the n equal strata of every parameter (a
    # Latin hypercube by construction, a Sobol' net of 2^m points in every 1-D projection)
    strata = np.floor(unit_points(table, TAMU_BOX) * n).astype(int)
    for j in range(2):
        assert np.array_equal(np.sort(strata[:, j]), np.arange(n))


def test_sequences_map_through_the_distributions():
    # a Latin hypercube over a normal: the n strata of equal probability hold one case each
    space = ParameterSpace([Normal("J", "1.2 kg*m**2", "0.05 kg*m**2", "kg*m**2")])
    table = space.latin_hypercube(50, seed=3)
    strata = np.floor(stats.norm(1.2, 0.05).cdf(table.values["J"]) * 50).astype(int)
    assert np.array_equal(np.sort(strata), np.arange(50))


def test_saltelli_design_has_n_times_d_plus_2_cases_in_the_bounds():
    design = TAMU_BOX.sobol_design(64, seed=5)
    assert len(design.table) == 64 * (2 + 2) and not design.second_order
    assert len(TAMU_BOX.sobol_design(64, seed=5, second_order=True).table) == 64 * (2 * 2 + 2)
    assert np.all((design.table.values["alpha"] >= 0) & (design.table.values["alpha"] <= 0.25))
    assert np.array_equal(design.table.matrix(), TAMU_BOX.sobol_design(64, seed=5).table.matrix())


# -- distributions ---------------------------------------------------------------------------------
DISPERSED = ParameterSpace(
    [
        Normal("hub_inertia", "1.2 kg*m**2", "0.05 kg*m**2", "kg*m**2"),
        Uniform("friction", "0.1 N*m", "0.3 N*m", "N*m"),
        LogNormal("stiffness", "2000 N/m", 1.5, "N/m"),
        TruncatedNormal("tip_mass", "0.1 kg", "0.05 kg", "0.08 kg", "0.2 kg", "kg"),
    ]
)


def test_every_distribution_samples_its_own_law():
    table = DISPERSED.sample(4000, seed=2026)
    for p in DISPERSED.parameters:
        # Kolmogorov-Smirnov against the stated law; at a 1e-3 level a correct sampler fails
        # once in a thousand seeds (this one is fixed), a wrong map fails at once
        assert stats.kstest(table.values[p.name], p.frozen.cdf).pvalue > 1e-3, p.name


def test_lognormal_median_and_geometric_sd_are_as_stated():
    p = DISPERSED.parameters[2]
    assert p.median == 2000.0 and p.ppf(0.5) == pytest.approx(2000.0, rel=4 * np.finfo(float).eps)
    x = DISPERSED.sample(4000, seed=7).values["stiffness"]
    # the sample median's standard error: sqrt(pi/2) * ln(g) * m / sqrt(n) (asymptotic)
    se = math.sqrt(math.pi / 2) * math.log(1.5) * 2000.0 / math.sqrt(x.size)
    assert abs(np.median(x) - 2000.0) < 4 * se
    # [m/g, m g] holds the +-1 sd of ln X: 68.27 %, binomial standard error 0.74 % at n = 4000
    inside = np.mean((x > 2000 / 1.5) & (x < 2000 * 1.5))
    assert abs(inside - 0.6827) < 4 * math.sqrt(0.6827 * 0.3173 / x.size)


@pytest.mark.parametrize(
    "low, high",
    [("0.08 kg", "0.2 kg"), ("0.25 kg", "0.26 kg"), ("-inf", "0.0 kg"), ("0.1 kg", "inf")],
)
def test_truncated_normal_stays_in_its_bounds(low, high):
    # including a window 3-3.2 sd out in the tail and one-sided truncations
    p = TruncatedNormal("tip_mass", "0.1 kg", "0.05 kg", low, high, "kg")
    x = ParameterSpace([p]).sample(20000, seed=1).values["tip_mass"]
    assert np.all(x >= p.low) and np.all(x <= p.high)
    assert np.all(np.isfinite(x))


# -- reproducibility -------------------------------------------------------------------------------
@pytest.mark.parametrize("chunk", [1, 7, 100, 300])
def test_monte_carlo_cases_do_not_depend_on_the_chunking(chunk):
    whole = DISPERSED.sample(300, seed=99)
    parts = [DISPERSED.sample(min(chunk, 300 - s), seed=99, start=s) for s in range(0, 300, chunk)]
    assert np.array_equal(whole.matrix(), np.vstack([p.matrix() for p in parts]))
    assert parts[-1].start == (299 // chunk) * chunk
    assert np.array_equal(whole.rows(100, 107).matrix(), DISPERSED.sample(7, 99, 100).matrix())


def test_a_case_depends_only_on_seed_name_and_index():
    small = DISPERSED.sample(100, seed=4)
    assert np.array_equal(DISPERSED.sample(300, seed=4).matrix()[:100], small.matrix())
    fewer = ParameterSpace(DISPERSED.parameters[1:3]).sample(100, seed=4)
    for name in fewer.names:
        assert np.array_equal(fewer.values[name], small.values[name])
    assert not np.array_equal(DISPERSED.sample(100, seed=5).matrix(), small.matrix())
    # the parameters' streams are independent: no two uniforms columns correlate beyond
    # sampling error (|r| < 4 / sqrt(n))
    u = unit_points(DISPERSED.sample(5000, seed=4), DISPERSED)
    r = np.corrcoef(u.T)[np.triu_indices(4, 1)]
    assert np.all(np.abs(r) < 4 / math.sqrt(5000))


def test_noise_seeds_are_per_case_and_apart_from_the_parameters():
    seeds = ParameterSpace.noise_seeds(100, seed=4)
    assert seeds.dtype == np.uint64 and np.unique(seeds).size == 100
    assert np.array_equal(ParameterSpace.noise_seeds(30, seed=4, start=70), seeds[70:])
    assert not np.array_equal(ParameterSpace.noise_seeds(100, seed=4, name="wind"), seeds)
    # a parameter named "noise" draws from another stream than the noise seeds
    raw = ParameterSpace.stream("noise", 4).random_raw(100)
    assert not np.any(raw == seeds)


# -- units and scenario dicts ----------------------------------------------------------------------
def test_values_are_read_in_their_units():
    assert Uniform("u_max", "100 ozf*in", "600 ozf*in", "N*m").high == pytest.approx(
        600 * OZF_IN, rel=1e-15
    )
    assert Normal("alpha", "5 deg", "0.5 deg", "rad").mean == pytest.approx(math.radians(5))
    assert Normal("J", Q_(1.2, "kg*m**2"), 0.05, "kg*m**2").sd == 0.05


def test_scenario_dicts_build_the_objects():
    units = {"hub_inertia": "kg*m**2", "alpha": "", "u_max": "N*m"}
    space = space_from_spec(
        {
            "hub_inertia": {"distribution": "normal", "mean": "1.2 kg*m**2", "sd": "0.05 kg*m**2"},
            "alpha": {"low": 0, "high": 0.25},
        },
        units,
    )
    assert isinstance(space, ParameterSpace)
    assert space.parameters[0] == Normal("hub_inertia", 1.2, 0.05, "kg*m**2")
    assert space.parameters[1] == Uniform("alpha", 0.0, 0.25)
    grid = space_from_spec(
        {
            "alpha": {"low": 0, "high": 0.25, "n": 6},
            "u_max": {"values": ["100 ozf*in", "600 ozf*in"]},
        },
        units,
    )
    assert isinstance(grid, GridSpace) and grid.shape == (6, 2)
    p = parameter_from_spec(
        "k",
        {"distribution": "truncated_normal", "mean": 1, "sd": 1, "low": 0, "high": "inf"},
        "N/m",
    )
    assert p == TruncatedNormal("k", 1, 1, 0, math.inf, "N/m")


BAD = [
    (
        {"x": {"distribution": "gaussian", "mean": 1, "sd": 1}},
        r"parameters\.x\.distribution: unknown distribution 'gaussian'; known: normal",
    ),
    ({"x": {"distribution": "normal", "mean": 1, "sd": 0}}, r"parameters\.x\.sd: must be > 0"),
    ({"x": {"distribution": "normal", "mean": 1, "sd": -2}}, r"parameters\.x\.sd: must be > 0"),
    (
        {"x": {"distribution": "normal", "mean": "nan", "sd": 1}},
        r"parameters\.x\.mean: must be finite",
    ),
    (
        {"x": {"distribution": "normal", "mean": 1, "sd": "inf"}},
        r"parameters\.x\.sd: must be finite",
    ),
    ({"x": {"distribution": "uniform", "low": 2, "high": 2}}, r"parameters\.x: low must be < high"),
    ({"x": {"distribution": "uniform", "low": 3, "high": 2}}, r"parameters\.x: low must be < high"),
    ({"x": {"low": 1, "high": 0, "n": 5}}, r"parameters\.x: low must be < high"),
    ({"x": {"low": 0, "high": 1, "n": 1}}, r"parameters\.x\.n: a linspace needs n >= 2"),
    ({"x": {"low": 0, "high": 1, "n": 2.5}}, r"parameters\.x\.n: must be a positive integer"),
    ({"x": {"values": []}}, r"parameters\.x\.values: must be a non-empty list"),
    ({"x": {"values": [1, "inf"]}}, r"parameters\.x\.values: must be finite"),
    (
        {"x": {"distribution": "lognormal", "median": 0, "gsd": 1.5}},
        r"parameters\.x\.median: must be > 0",
    ),
    (
        {"x": {"distribution": "lognormal", "median": 1, "gsd": 1.0}},
        r"parameters\.x\.gsd: the geometric standard deviation must be > 1",
    ),
    (
        {"x": {"distribution": "truncated_normal", "mean": 0, "sd": 1, "low": 1, "high": -1}},
        r"parameters\.x: low must be < high",
    ),
    (
        {"x": {"distribution": "truncated_normal", "mean": 0, "sd": 1, "low": 50, "high": 60}},
        r"parameters\.x: the normal .* puts no probability in \[50, 60\]",
    ),
    (
        {"x": {"distribution": "truncated_normal", "mean": 0, "sd": 1, "low": "nan", "high": 1}},
        r"parameters\.x\.low: must be finite \(no NaN",
    ),
    (
        {"x": {"distribution": "normal", "mean": 1}},
        r"parameters\.x\.sd: missing; a normal distribution takes distribution, mean, sd",
    ),
    (
        {"x": {"distribution": "normal", "mean": 1, "sd": 1, "sigma": 1}},
        r"parameters\.x\.sigma: unknown key; a normal distribution takes",
    ),
    ({"x": {"median": 1}}, r"parameters\.x: give a distribution"),
    ({"x": 3.0}, r"parameters\.x: must be a mapping"),
    ({"nope": {"values": [1]}}, r"parameters\.nope: unknown parameter; known: angle, x"),
    (
        {"x": {"values": [1, 2]}, "angle": {"distribution": "normal", "mean": 0, "sd": 1}},
        r"parameters\.angle: grid axes .* cannot be mixed",
    ),
    ({}, r"parameters: must be a non-empty mapping"),
]


@pytest.mark.parametrize("spec, message", BAD)
def test_bad_input_is_refused_naming_the_field_and_the_rule(spec, message):
    with pytest.raises(ValueError, match=message):
        space_from_spec(spec, {"x": "", "angle": "rad"})


@pytest.mark.parametrize("key", ["mean", "sd"])
def test_a_unit_mismatch_is_refused_naming_the_field(key):
    spec = {"distribution": "normal", "mean": "5 deg", "sd": "1 deg", key: "5 kg"}
    with pytest.raises(
        UnitError,
        match=rf"parameters\.angle\.{key}: incompatible units "
        r"\(kilogram given, rad expected\)",
    ):
        space_from_spec({"angle": spec}, {"angle": "rad"})


def test_other_misuse_is_refused():
    with pytest.raises(ValueError, match=r"alpha\.unit: must be an SI unit .* 1 deg is 0\.0174"):
        Normal("alpha", 1, 0.1, "deg")
    with pytest.raises(ValueError, match=r"parameters: the parameter 'a' is given twice"):
        ParameterSpace([Uniform("a", 0, 1), Normal("a", 0, 1)])
    with pytest.raises(ValueError, match=r"n: a Sobol' sequence needs a power of 2"):
        TAMU_BOX.sobol_sequence(100, seed=1)
    with pytest.raises(ValueError, match=r"n_base: the Saltelli design needs a power of 2"):
        TAMU_BOX.sobol_design(100, seed=1)
    with pytest.raises(ValueError, match=r"seed: the seed must be a non-negative integer"):
        TAMU_BOX.sample(10, seed=-1)
    with pytest.raises(ValueError, match=r"start: must be a non-negative integer"):
        TAMU_BOX.sample(10, seed=1, start=2.5)
    with pytest.raises(ValueError, match=r"parameter: a parameter name must be a non-empty"):
        Uniform("", 0, 1)
