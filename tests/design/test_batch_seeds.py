"""Case seeds of flexsat.design.batch_seeds: case i's seed from the base seed and i alone."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.design.batch_seeds import case_seeds, nonneg_int
from flexsat.input_checks import FieldError


@pytest.mark.parametrize("base", [0, 7, 2**40 + 3])
def test_a_case_s_seed_does_not_depend_on_its_chunk(base):
    """Case i's seed is the same whether computed in one chunk of 0..99, in a later chunk,
    alone, or in a shuffled chunk."""
    every = case_seeds(base, np.arange(100))
    for start, stop in [(0, 10), (10, 37), (37, 100), (63, 64)]:
        assert case_seeds(base, np.arange(start, stop)).tolist() == every[start:stop].tolist()
    order = np.random.default_rng(1).permutation(100)
    assert case_seeds(base, order).tolist() == every[order].tolist()


def test_seeds_differ_across_cases_and_base_seeds_and_fit_the_engine_range():
    """10,000 cases of two bases: all distinct (63-bit values: a collision has probability
    ~ n² / 2⁶⁴ ≈ 1e-11), int64 and in [0, 2⁶³)."""
    a, b = case_seeds(1, np.arange(10_000)), case_seeds(2, np.arange(10_000))
    assert a.dtype == np.int64
    assert np.unique(np.r_[a, b]).size == 20_000
    assert a.min() >= 0 and b.min() >= 0  # int64 cannot exceed 2⁶³ − 1


def test_case_i_is_the_i_th_child_numpy_s_spawn_gives():
    """The module's claim: spawn_key (i,) is what SeedSequence(b).spawn gives the i-th child."""
    children = np.random.SeedSequence(2026).spawn(5)
    expected = [int(c.generate_state(1, np.uint64)[0]) >> 1 for c in children]
    assert case_seeds(2026, range(5)).tolist() == expected


@pytest.mark.parametrize("bad", [-1, 1.5, True, float("nan")])
def test_base_seed_must_be_a_nonnegative_integer(bad):
    with pytest.raises(FieldError, match="base_seed"):
        case_seeds(bad, [0])


def test_nonneg_int_accepts_integral_floats_and_names_the_field():
    assert nonneg_int(3.0, "n_cases") == 3 and isinstance(nonneg_int(3.0, "n_cases"), int)
    with pytest.raises(FieldError, match="n_cases.*integer >= 0"):
        nonneg_int(-2, "n_cases")
