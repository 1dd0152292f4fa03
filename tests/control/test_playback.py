"""Playback: u_k = U[k] at t_k = k Δt, zeros after the table, in the protocol's shapes."""

import numpy as np
import pytest

from flexsat.control.playback import Playback


def _play(law, n_cases, times):
    state = law.initial_state(n_cases)
    out = []
    for t in times:
        u, state = law(t, {}, state)
        out.append(u)
    return np.array(out), state


def test_wide_table_is_played_in_every_case_then_zeros():
    """A 2-wide table of 3 samples at Δt = 0.1 s over 5 samples: rows 0-2, then zeros, shape
    (n_cases, 2) at each sample (it was (2,), which the conformance suite's ``shapes`` caught)."""
    table = np.array([[1.0, -1.0], [2.0, -2.0], [3.0, -3.0]])
    u, state = _play(Playback(table, 0.1, "excitation"), 4, 0.1 * np.arange(5))
    assert u.shape == (5, 4, 2)
    np.testing.assert_array_equal(u[:3], np.broadcast_to(table[:, None, :], (3, 4, 2)))
    np.testing.assert_array_equal(u[3:], 0.0)
    np.testing.assert_array_equal(state["played"], [4, 4, 4, 4])


def test_one_wide_table_gives_one_value_per_case():
    u, _ = _play(Playback([5.0, 0.0], 0.5, "force"), 3, [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(u, [[5.0] * 3, [0.0] * 3, [0.0] * 3])


@pytest.mark.parametrize(
    "values, dt, match",
    [([], 0.1, r"^values: must be"), ([[[1.0]]], 0.1, r"^values: must be"), ([1.0], 0.0, "dt")],
)
def test_bad_table_is_refused(values, dt, match):
    with pytest.raises(ValueError, match=match):
        Playback(values, dt, "force")


def test_one_column_table_is_a_one_wide_channel():
    """(n_t, 1) drives a 1-wide channel as (n_t,) does: (n_cases,) per sample (what the engine
    asks of a size-1 channel; simulate_test passes its single excitation this way)."""
    a, _ = _play(Playback([[5.0], [1.0]], 0.5, "force"), 2, [0.0, 0.5, 1.0])
    b, _ = _play(Playback([5.0, 1.0], 0.5, "force"), 2, [0.0, 0.5, 1.0])
    assert a.shape == (3, 2)
    np.testing.assert_array_equal(a, b)
