"""Candidate-set searches: greedy is optimal for an additive score, exchange improves on
greedy and is bounded by the exhaustive optimum, the exhaustive search refuses what it cannot
enumerate before scoring anything, and bad inputs are refused by name."""

import math

import numpy as np
import pytest

from flexsat.analysis.placement_search import MAX_EXHAUSTIVE_SETS, exchange, exhaustive, greedy

CANDS = [f"c{i}" for i in range(10)]


def additive(weights):
    return lambda sel: sum(weights[c] for c in sel)


def test_greedy_optimal_for_additive_score():
    rng = np.random.default_rng(0)
    weights = dict(zip(CANDS, rng.normal(size=10)))
    ex = exhaustive(CANDS, 4, additive(weights))
    gr = greedy(CANDS, 4, additive(weights))
    assert gr.selection == ex.selection and gr.score == pytest.approx(ex.score)
    assert ex.evaluations == math.comb(10, 4)
    assert gr.evaluations == 10 + 9 + 8 + 7
    assert ex.best[0][0] >= ex.best[1][0] and len(ex.best) == 10


def _interaction_score(seed):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=10)
    P = rng.normal(size=(10, 10))
    P = 0.5 * (P + P.T)

    def score(sel):
        idx = [CANDS.index(c) for c in sel]
        return float(u[idx].sum() + 0.7 * P[np.ix_(idx, idx)].sum())

    return score


@pytest.mark.parametrize("seed", range(6))
def test_exchange_improves_on_greedy_and_bounded_by_exhaustive(seed):
    score = _interaction_score(seed)
    ex, gr, xc = (exhaustive(CANDS, 4, score), greedy(CANDS, 4, score), exchange(CANDS, 4, score))
    assert gr.score <= xc.score + 1e-12 <= ex.score + 2e-12
    assert xc.best[0][1] == gr.selection  # the exchange starts from greedy
    started = exchange(CANDS, 4, score, start=ex.selection)
    assert started.selection == ex.selection  # the optimum is a 1-swap local optimum


def test_exhaustive_refuses_c36_12_without_enumerating():
    def never(sel):
        raise AssertionError("score must not be called")

    cands = [f"a{i}" for i in range(36)]
    assert math.comb(36, 12) == 1_251_677_700
    with pytest.raises(
        ValueError,
        match=r"C\(36, 12\) = 1,251,677,700 .* exceeds max_sets = "
        r"1,000,000.*greedy\(\) or exchange\(\)",
    ):
        exhaustive(cands, 12, never)
    assert MAX_EXHAUSTIVE_SETS == 1_000_000
    # the heuristics handle it: greedy on an additive score is optimal, 354 evaluations
    weights = {c: float(i % 7) + 0.01 * i for i, c in enumerate(cands)}
    gr = greedy(cands, 12, additive(weights))
    assert set(gr.selection) == set(sorted(cands, key=weights.get)[-12:])
    assert gr.evaluations == sum(36 - j for j in range(12))


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: exhaustive(CANDS, 0, len), "size"),
        (lambda: exhaustive(CANDS, 11, len), "size"),
        (lambda: exhaustive(["a", "a"], 1, len), "distinct"),
        (lambda: exhaustive([], 1, len), "empty"),
        (lambda: greedy(CANDS, 2, "not callable"), "callable"),
        (lambda: greedy(CANDS, 2, lambda s: float("nan")), "NaN"),
        (lambda: greedy(CANDS, 2, lambda s: "x"), "number"),
        (lambda: greedy(CANDS, 2, len, start=["zz"]), "not a candidate"),
        (lambda: greedy(CANDS, 1, len, start=["c1", "c2"]), "more than size"),
        (lambda: exchange(CANDS, 2, len, start=["c1"]), "size = 2"),
        (lambda: exhaustive(CANDS, 2, len, max_sets=0), "max_sets"),
        (lambda: exhaustive([[1], [2]], 1, len), "hashable"),
    ],
)
def test_search_bad_inputs(call, match):
    with pytest.raises(ValueError, match=match):
        call()
