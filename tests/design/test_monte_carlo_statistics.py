"""Monte Carlo statistics (issue 13): the probability interval covers the true probability of a
metric with a known law at its nominal level; its end points are the published closed forms at 0
and N successes; NaN metrics fail requirements; percentiles and their order-statistic intervals
are distribution-free and cover; convergence tables end at the full estimate and narrow as
1/sqrt(N); Sobol' indices of the Ishigami function match the closed form within SALib's
intervals and rank its parameters; the cheap rankings order a linear model's parameters by
their variance shares; bad input is refused by field.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from flexsat.design.monte_carlo_statistics import (
    Requirement,
    checkpoints,
    metric_summary,
    monte_carlo_summary,
    percentile_convergence,
    percentile_interval,
    probability_convergence,
    probability_of_meeting,
    proportion_interval,
    requirement_from_spec,
    sample_sensitivity,
    sobol_indices,
)
from flexsat.design.parameter_space import ParameterSpace, Uniform, space_from_spec
from flexsat.units import UnitError

Z95 = stats.norm.ppf(0.975)

# a metric with a known law: m = x^2 with x ~ N(1, 0.5^2); P(m <= c) = Phi((sqrt c - mu)/sigma)
# - Phi((-sqrt c - mu)/sigma)
MU, SIGMA, C = 1.0, 0.5, 1.5
P_TRUE = stats.norm.cdf((math.sqrt(C) - MU) / SIGMA) - stats.norm.cdf((-math.sqrt(C) - MU) / SIGMA)
SPACE = space_from_spec({"x": {"distribution": "normal", "mean": MU, "sd": SIGMA}}, {"x": ""})
REQUIREMENT = requirement_from_spec("m", {"max": C}, "")


@pytest.mark.parametrize("method", ["clopper_pearson", "wilson"])
def test_probability_interval_covers_the_true_value_at_its_nominal_level(method):
    n, repetitions = 200, 50
    estimates = [
        probability_of_meeting(SPACE.sample(n, seed=s).values["x"] ** 2, REQUIREMENT, 0.95, method)
        for s in range(repetitions)
    ]
    coverage = np.mean([e.low <= P_TRUE <= e.high for e in estimates])
    print(
        f"{method}: P = {P_TRUE:.4f}, coverage of the 95 % interval in {repetitions} "
        f"repetitions of N = {n}: {coverage:.2f}"
    )
    assert coverage >= 0.90  # the acceptance level for a nominal 95 % interval
    # and not by being uninformative: the mean width is within 30 % of the large-sample width
    # 2 z sqrt(p (1 - p) / N) (Clopper-Pearson's excess at N = 200 is a few per cent)
    width = np.mean([e.high - e.low for e in estimates])
    wald = 2 * Z95 * math.sqrt(P_TRUE * (1 - P_TRUE) / n)
    assert 0.9 * wald < width < 1.3 * wald


@pytest.mark.parametrize("n", [1, 20, 1000])
def test_interval_at_zero_and_all_successes_is_the_closed_form(n):
    # Clopper-Pearson at k = 0: [0, 1 - (alpha/2)^(1/n)]; at k = n: [(alpha/2)^(1/n), 1]
    # (expm1 keeps the small upper end accurate); to the root-finding tolerance of scipy's
    # inverse incomplete beta function (boost ibeta_inv: 6e-11 relative measured at n = 1000)
    upper = -math.expm1(math.log(0.025) / n)
    assert proportion_interval(0, n) == pytest.approx((0.0, upper), rel=1e-9, abs=1e-15)
    assert proportion_interval(n, n) == pytest.approx((1 - upper, 1.0), rel=1e-9)
    # Wilson at k = 0: [0, z^2 / (n + z^2)]
    assert proportion_interval(0, n, method="wilson") == pytest.approx(
        (0.0, Z95**2 / (n + Z95**2)), rel=1e-12, abs=1e-15
    )


def test_wilson_is_the_score_interval():
    k, n = 37, 120
    p = k / n
    centre = (p + Z95**2 / (2 * n)) / (1 + Z95**2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + Z95**2 / (4 * n * n)) / (1 + Z95**2 / n)
    assert proportion_interval(k, n, method="wilson") == pytest.approx(
        (centre - half, centre + half), rel=1e-12
    )
    # Clopper-Pearson is the wider, exact one
    low, high = proportion_interval(k, n)
    assert low < centre - half and high > centre + half


def test_a_missing_metric_fails_every_requirement():
    settle = np.array([3.0, 7.9, 8.0, 8.1, np.nan, np.inf])
    assert list(Requirement("settling_time", "<=", "8 s", "s").met(settle)) == [
        True,
        True,
        True,
        False,
        False,
        False,
    ]
    assert list(Requirement("margin", ">=", 8.0).met(settle)) == [
        False,
        False,
        True,
        True,
        False,
        True,
    ]
    estimate = probability_of_meeting(settle, Requirement("settling_time", "<=", 8.0, "s"))
    assert (estimate.successes, estimate.n, estimate.probability) == (3, 6, 0.5)


def test_requirements_read_their_units():
    overshoot = requirement_from_spec("overshoot", {"max": "2 deg"}, "rad")
    assert overshoot.relation == "<=" and overshoot.threshold == pytest.approx(math.radians(2))
    assert requirement_from_spec("t", {"min": 3}, "s").relation == ">="


# -- percentiles -----------------------------------------------------------------------------------
def test_percentiles_skip_missing_values_and_keep_inf_as_the_worst():
    values = np.array([5.0, 1.0, np.nan, 3.0, 2.0, 4.0, np.inf, np.nan])
    summary = metric_summary(values, "t", q=(0, 50, 80, 100))
    assert (summary.n, summary.n_nan, summary.minimum, summary.maximum) == (8, 2, 1.0, math.inf)
    # six values 1 2 3 4 5 inf: the smallest with at least q % at or below it
    assert summary.percentiles == {0.0: 1.0, 50.0: 3.0, 80.0: 5.0, 100.0: math.inf}
    empty = metric_summary([np.nan, np.nan], "t")
    assert empty.n_nan == 2 and all(math.isnan(v) for v in empty.percentiles.values())


def test_percentile_interval_is_a_pair_of_order_statistics():
    # the textbook ranks of the median's 95 % interval at n = 100: the 40th and 61st values
    assert percentile_interval(np.arange(1.0, 101.0), 50) == (50.0, 40.0, 61.0)
    # too few cases for a 95 % upper bound of the 99th percentile: open on that side
    estimate, low, high = percentile_interval(np.arange(1.0, 21.0), 99)
    assert estimate == 20.0 and high == math.inf and low < 20.0


def test_percentile_interval_covers_the_true_percentile():
    # p90 of N(0, 1) from 200 samples, 200 repetitions: nominal coverage >= 95 %; the binomial
    # standard error of the measured coverage at 0.95 is 1.5 %, so >= 0.91 is 2.6 of them
    rng = np.random.default_rng(13)
    truth = stats.norm.ppf(0.9)
    hits = []
    for _ in range(200):
        _, low, high = percentile_interval(rng.standard_normal(200), 90)
        hits.append(low <= truth <= high)
    assert np.mean(hits) >= 0.91


# -- convergence -----------------------------------------------------------------------------------
def test_convergence_ends_at_the_full_estimate_and_narrows_as_one_over_sqrt_n():
    assert list(checkpoints(1000)) == [10, 20, 50, 100, 200, 500, 1000]
    assert list(checkpoints(7)) == [7] and list(checkpoints(230)) == [10, 20, 50, 100, 200, 230]
    metric = SPACE.sample(2000, seed=8).values["x"] ** 2
    conv = probability_convergence(metric, REQUIREMENT)
    full = probability_of_meeting(metric, REQUIREMENT)
    assert conv.n[-1] == 2000 and conv.estimate[-1] == full.probability
    assert (conv.low[-1], conv.high[-1]) == (full.low, full.high)
    # the first N' cases are the run of N' cases (the sample is prefix-consistent)
    assert (
        conv.estimate[2]
        == probability_of_meeting(
            SPACE.sample(50, seed=8).values["x"] ** 2, REQUIREMENT
        ).probability
    )
    width = conv.high - conv.low
    # 200 times the cases: the width shrinks by about sqrt(200) = 14; allow a factor 2 for the
    # small-N end, where the exact interval is wider than the large-sample one
    assert width[0] / width[-1] > math.sqrt(200) / 2
    p50 = percentile_convergence(metric, 50, "m")
    assert p50.estimate[-1] == metric_summary(metric, "m").percentiles[50.0]
    assert np.all(p50.low <= p50.estimate) and np.all(p50.estimate <= p50.high)


# -- sensitivity -----------------------------------------------------------------------------------
def ishigami(x, a=7.0, b=0.1):
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami_indices(a=7.0, b=0.1):
    """Closed form (Ishigami & Homma 1990; Sobol' & Levitan 1999): first and total indices."""
    pi4, pi8 = math.pi**4, math.pi**8
    v1 = 0.5 * (1 + b * pi4 / 5) ** 2
    v2 = a**2 / 8
    v13 = 8 * b**2 * pi8 / 225
    v = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


def test_sobol_indices_of_the_ishigami_function_match_the_closed_form():
    space = ParameterSpace([Uniform(f"x{i}", -math.pi, math.pi) for i in (1, 2, 3)])
    design = space.sobol_design(4096, seed=3)
    result = sobol_indices(design, ishigami(design.table.matrix()), "ishigami", seed=4)
    first, total = ishigami_indices()
    print("S1", result.first, "+-", result.first_conf, "exact", first)
    print("ST", result.total, "+-", result.total_conf, "exact", total)
    # within SALib's 95 % bootstrap half-widths (0.015 to 0.05 at 4096 base points; the
    # errors measured are below 0.002)
    assert np.all(np.abs(result.first - first) <= result.first_conf)
    assert np.all(np.abs(result.total - total) <= result.total_conf)
    assert result.ranking == ["x1", "x2", "x3"]
    assert json.loads(json.dumps(result.as_dict()))["ranking"] == ["x1", "x2", "x3"]


LINEAR_SHARES = np.array([9.0, 4.0, 1.0]) / 14  # y = 3 a + 2 b + c, a, b, c ~ U(0, 1)


@pytest.mark.parametrize("method", ["spearman", "rbd_fast"])
def test_sample_rankings_order_a_linear_model(method):
    space = ParameterSpace([Uniform(n, 0.0, 1.0) for n in ("a", "b", "c")])
    table = space.sample(2000, seed=21)
    x = table.matrix()
    y = x @ np.array([3.0, 2.0, 1.0])
    y[:50] = np.nan  # cases without a value are left out
    result = sample_sensitivity(table, y, "y", method=method, seed=2)
    assert result.ranking == ["a", "b", "c"] and result.n == 1950
    if method == "rbd_fast":
        # RBD-FAST estimates the first-order indices: the variance shares, within its
        # bootstrap half-widths
        assert np.all(np.abs(result.scores - LINEAR_SHARES) <= result.conf)


def test_summary_is_plain_numbers():
    metric = SPACE.sample(300, seed=1).values["x"] ** 2
    summary = monte_carlo_summary({"m": metric}, [REQUIREMENT])
    text = json.dumps(summary)
    back = json.loads(text)
    assert back["requirements"][0]["n"] == 300 and back["metrics"]["m"]["n"] == 300
    assert back["requirements"][0]["convergence"]["n"][-1] == 300


# -- bad input -------------------------------------------------------------------------------------
def test_bad_input_is_refused_by_field():
    with pytest.raises(ValueError, match=r"requirement 'm'\.relation: must be one of <=, >="):
        Requirement("m", "<", 1.0)
    with pytest.raises(
        UnitError,
        match=r"overshoot\.max: incompatible units \(kilogram given, "
        r"rad expected\)",
    ):
        requirement_from_spec("overshoot", {"max": "5 kg"}, "rad")
    with pytest.raises(ValueError, match=r"requirements\.t: give exactly one of max:"):
        requirement_from_spec("t", {"max": 1, "min": 0}, "s", "requirements.t")
    with pytest.raises(ValueError, match=r"t\.max: must be finite"):
        requirement_from_spec("t", {"max": "nan"}, "s")
    with pytest.raises(ValueError, match=r"confidence: must be a number in \(0, 1\)"):
        probability_of_meeting([1.0], REQUIREMENT, confidence=95)
    with pytest.raises(ValueError, match=r"method: must be one of clopper_pearson, wilson"):
        probability_of_meeting([1.0], REQUIREMENT, method="wald")
    with pytest.raises(ValueError, match=r"successes: must be an integer in 0\.\.n = 5"):
        proportion_interval(6, 5)
    with pytest.raises(ValueError, match=r"m: must be a 1-D array over the cases"):
        probability_of_meeting(np.ones((2, 2)), REQUIREMENT)
    with pytest.raises(ValueError, match=r"q: percentiles must be numbers in \[0, 100\]"):
        metric_summary([1.0, 2.0], "t", q=(50, 101))
    with pytest.raises(ValueError, match=r"requirement 'z': no such metric; metrics: m"):
        monte_carlo_summary({"m": [1.0]}, [Requirement("z", "<=", 1.0)])
    space = ParameterSpace([Uniform("a", 0, 1), Uniform("b", 0, 1)])
    design = space.sobol_design(8, seed=1)
    y = np.ones(len(design.table))
    y[3] = np.nan
    with pytest.raises(
        ValueError,
        match=r"y: Sobol' indices need a finite value in every case; "
        r"1 are NaN",
    ):
        sobol_indices(design, y, "y")
    with pytest.raises(ValueError, match=r"y: has 5 cases, the Sobol' design 32"):
        sobol_indices(design, np.ones(5), "y")
    with pytest.raises(ValueError, match=r"method: must be one of spearman, rbd_fast"):
        sample_sensitivity(design.table, np.ones(32), method="delta")
