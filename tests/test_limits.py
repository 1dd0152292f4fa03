"""Resource limits (flexsat.limits): a count or a memory estimate above its limit is refused with
a ``field: ...`` message naming the limit; at the limit it passes; the limits are read at call
time, so a user can raise them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexsat import limits
from flexsat.limits import check_count, check_memory, is_integral, memory_estimate


@pytest.mark.parametrize(
    "value", [3, -2, 0, np.int64(7), np.uint8(255), 10**40, 1e3, np.float64(2.0), -0.0]
)
def test_integral_values(value):
    assert is_integral(value)


@pytest.mark.parametrize(
    "value",
    [
        True,
        False,
        np.bool_(True),
        2.5,
        np.float32(0.5),
        math.nan,
        math.inf,
        -math.inf,
        "3",
        None,
        3 + 0j,
        [1],
    ],
)
def test_non_integral_values(value):
    assert not is_integral(value)


def test_count_at_the_limit_passes_and_one_above_is_refused():
    check_count(1_000, 1_000, "substeps", "substeps per control period")
    with pytest.raises(ValueError) as info:
        check_count(
            1_001, 1_000, "substeps", "substeps per control period", "raise the integration step"
        )
    assert str(info.value) == (
        "substeps: substeps per control period = 1001, above the limit "
        "1,000 (flexsat.limits); raise the integration step"
    )


def test_count_message_without_a_hint_ends_at_the_limit():
    with pytest.raises(ValueError) as info:
        check_count(7.5e13, limits.MAX_SAMPLES, "duration", "control samples")
    assert str(info.value) == (
        "duration: control samples = 7.5e+13, above the limit 2,000,000 (flexsat.limits)"
    )


def test_memory_estimate_is_eight_bytes_per_value_without_overflow():
    assert memory_estimate(151, 2, 29) == 8 * 151 * 2 * 29
    # numpy int32 counts would wrap at 2**31 if multiplied as they are
    big = memory_estimate(np.int32(2**30), np.int32(4), np.int32(4))
    assert big == 2**37 and isinstance(big, int)


def test_memory_at_the_limit_passes_and_above_is_refused_in_readable_units():
    check_memory(limits.MAX_MEMORY, "duration", "a run")
    with pytest.raises(ValueError) as info:
        check_memory(12 * 1024**3, "duration", "a run of 3e9 samples")
    assert str(info.value) == (
        "duration: a run of 3e9 samples needs about 12 GB of memory, above "
        "the limit 2 GB (flexsat.limits.MAX_MEMORY)"
    )


def test_memory_limit_is_read_at_call_time(monkeypatch):
    monkeypatch.setattr(limits, "MAX_MEMORY", 1000)
    check_memory(1000, "n_cases", "a batch")
    with pytest.raises(ValueError) as info:
        check_memory(1500, "n_cases", "a batch")
    # 1500 B = 1.46 kB; a limit below 1 kB is shown in bytes
    assert str(info.value) == (
        "n_cases: a batch needs about 1.46 kB of memory, above the limit "
        "1000 B (flexsat.limits.MAX_MEMORY)"
    )
    monkeypatch.setattr(limits, "MAX_MEMORY", 3 * 1024**2)
    with pytest.raises(ValueError, match=r"needs about 4 MB of memory, above the limit 3 MB"):
        check_memory(4 * 1024**2, "n_cases", "a batch")


def test_largest_seed_plus_a_case_index_stays_an_int64():
    # each case of a batch draws its noise from seed + case index (the docstring of MAX_SEED)
    assert limits.MAX_SEED + limits.MAX_CASES <= np.iinfo(np.int64).max
