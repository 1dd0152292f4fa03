"""Pareto fronts of the hub-boom co-design (structural mass vs LQ slew cost) by ε-constraint and
weighted sums, run as batches (issue 23 deliverable 4): the front points are nondominated, every
ε-constraint binds with KKT <= 1e-6, the multiplier is the front's slope, two optimisers agree,
the weighted sums land on the ε front, and the batch guarantees hold (a point equals the point
run alone, chunking does not matter, an interrupted run resumes to the same store)."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.design.batch_runner import open_results
from flexsat.design.pareto import (
    FrontSetup,
    front_levels,
    front_metrics,
    front_table,
    nondominated,
    run_front,
    solve_case,
)
from flexsat.design.reference_problems import HubBoomCodesign
from flexsat.input_checks import FieldError

POINTS, STARTS, SEED = 4, 2, 7


@pytest.fixture(scope="module")
def setup() -> FrontSetup:
    return FrontSetup(HubBoomCodesign(), "lq_cost", "mass")


@pytest.fixture(scope="module")
def store(setup, tmp_path_factory):
    path = tmp_path_factory.mktemp("front") / "front.zarr"
    run_front(setup, path, points=POINTS, starts=STARTS, base_seed=SEED, chunk_size=3)
    return path


def _values(path):
    ds = open_results(path).load()
    return {k: ds[k].values for k in ds.data_vars}, dict(ds.attrs)


def test_nondominated_against_a_hand_example():
    # (1, 4), (2, 2), (4, 1) are a front; (3, 3) is dominated by (2, 2); (2, 5) by (1, 4)
    f1 = np.array([1.0, 2.0, 4.0, 3.0, 2.0])
    f2 = np.array([4.0, 2.0, 1.0, 3.0, 5.0])
    assert nondominated(f1, f2).tolist() == [True, True, True, False, False]


def test_front_points_are_nondominated_and_trade(store):
    front = front_table(store)
    assert front["primary"].size == POINTS  # every level converged from some start
    assert nondominated(front["primary"], front["secondary"]).all()
    # ordered by mass, the LQ cost falls strictly: a real trade, not a single design
    assert np.all(np.diff(front["secondary"]) > 0) and np.all(np.diff(front["primary"]) < 0)


def test_every_epsilon_binds_with_a_kkt_residual_within_tolerance(store):
    ds = open_results(store).load()
    assert np.all(ds["metric_kkt_residual"].values <= 1e-6)
    assert np.all(ds["metric_success"].values == 1)
    assert np.all(ds["metric_epsilon_active"].values == 1)
    assert np.all(ds["metric_epsilon_multiplier"].values > 0)
    # active: the mass equals ε to the optimiser's tolerance (scaled 1e-12; 1e-9 relative
    # leaves room for the final projection onto the bounds)
    np.testing.assert_allclose(ds["metric_secondary"].values, ds["param_level"].values, rtol=1e-9)


def test_the_multiplier_is_the_slope_of_the_front(setup):
    """Sensitivity theorem (Fiacco 1976): λ_ε = −dJ*/dε. Central difference with h = 1e-4 ε:
    truncation O(h²)·J''' ~ 1e-8 relative, optimum noise ~1e-12 / h ~ 1e-8 — tolerance 1e-5."""
    eps = float(front_levels(setup, 3)[1])
    lam = solve_case(setup, eps, 0).multipliers["mass <= epsilon"]
    h = 1e-4 * eps
    up, down = solve_case(setup, eps + h, 0).objective, solve_case(setup, eps - h, 0).objective
    assert lam == pytest.approx(-(up - down) / (2 * h), rel=1e-5)


def test_two_optimisers_agree_within_one_percent(setup):
    other = FrontSetup(setup.reference, "lq_cost", "mass", method="trust-constr")
    for eps in front_levels(setup, 3):
        a, b = solve_case(setup, eps, 0), solve_case(other, eps, 0)
        assert b.kkt.residual <= 1e-6
        assert b.objective == pytest.approx(a.objective, rel=1e-2)
        np.testing.assert_allclose(b.x, a.x, rtol=1e-2)


def test_weighted_sums_land_on_the_epsilon_front(setup):
    """Each weighted-sum optimum (a convex front here) is the ε-constraint optimum at its own
    mass: the same LQ cost to the optimisers' accuracy (1e-8 relative)."""
    weighted = FrontSetup(setup.reference, "lq_cost", "mass", scalarisation="weighted")
    for w in front_levels(weighted, 3):
        r = front_metrics(weighted, solve_case(weighted, w, 0))
        assert r["kkt_residual"] <= 1e-6
        e = front_metrics(setup, solve_case(setup, r["secondary"], 0))
        assert e["primary"] == pytest.approx(r["primary"], rel=1e-8)


def test_a_front_point_equals_the_point_run_alone(setup, store):
    ds = open_results(store).load()
    for case in (0, 2 * STARTS - 1, POINTS * STARTS - 1):
        level = float(ds["param_level"].values[case])
        start = int(ds["param_start"].values[case])
        alone = front_metrics(setup, solve_case(setup, level, start, SEED))
        for name, value in alone.items():
            stored = ds[f"metric_{name}"].values[case]
            assert stored == value or (np.isnan(stored) and np.isnan(value)), name


def test_the_store_does_not_depend_on_the_chunking(setup, store, tmp_path):
    path = tmp_path / "one.zarr"
    run_front(setup, path, points=POINTS, starts=STARTS, base_seed=SEED, chunk_size=1)
    (a, attrs_a), (b, attrs_b) = _values(store), _values(path)
    assert attrs_a["fingerprint"] == attrs_b["fingerprint"]
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


class _StopAfter:
    """Interrupt (as Ctrl-C would) once ``k`` chunks are stored."""

    def __init__(self, k: int):
        self.k, self.calls = k, 0

    def __call__(self, p):
        self.calls += 1
        if p.chunks_done >= self.k and self.calls > 1:
            raise KeyboardInterrupt


def test_an_interrupted_front_resumes_to_the_same_store(setup, store, tmp_path):
    path = tmp_path / "r.zarr"
    with pytest.raises(KeyboardInterrupt):
        run_front(
            setup,
            path,
            points=POINTS,
            starts=STARTS,
            base_seed=SEED,
            chunk_size=3,
            progress=_StopAfter(1),
        )
    done = open_results(path)["done"].values
    assert 0 < done.sum() < done.size
    summary = run_front(setup, path, points=POINTS, starts=STARTS, base_seed=SEED, chunk_size=3)
    assert summary.chunks_skipped >= 1
    (a, _), (b, _) = _values(store), _values(path)
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_starts_depend_on_their_index_alone(setup):
    x1 = setup.start(1, SEED)
    assert np.array_equal(x1, setup.start(1, SEED))
    assert not np.array_equal(x1, setup.start(2, SEED))
    p = setup.reference.problem()
    assert np.all((x1 >= p.lower) & (x1 <= p.upper))
    assert np.array_equal(setup.start(0, SEED), p.x0)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"primary": "settling"}, "primary"),
        ({"secondary": "lq_cost"}, "secondary"),
        ({"scalarisation": "minimax"}, "scalarisation"),
        ({"method": "nelder-mead"}, "method"),
    ],
    ids=["primary", "same", "scalarisation", "method"],
)
def test_bad_setups_are_refused_by_field(kwargs, field):
    args = {"reference": HubBoomCodesign(), "primary": "lq_cost", "secondary": "mass", **kwargs}
    with pytest.raises(FieldError) as info:
        FrontSetup(**args)
    assert info.value.field == field


def test_bad_counts_are_refused(setup, tmp_path):
    with pytest.raises(FieldError, match="points"):
        front_levels(setup, 0)
    with pytest.raises(FieldError, match="starts"):
        run_front(setup, tmp_path / "x.zarr", points=2, starts=0)
