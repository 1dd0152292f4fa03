"""Gain-scheduled state feedback (seed 003 §2.6, checks F10): a constant schedule is a constant
gain, the interpolation returns the designed gains exactly at the schedule times and is linear
between them (so the command is continuous in time, F10), the linear form is the law, and bad
schedules are refused naming the field.

Tolerances: interpolating between equal gains, (1 − w)K + wK, rounds to within 2 ulps of K; a
command sums n products of these, so it matches within 4 eps × Σ|K||e|. Away from the knots the
gains are affine in t up to the same rounding.
"""

import numpy as np
import pytest

from flexsat.control import ScheduledStateFeedback, run_linear_law
from flexsat.control.linear_form import run_controller
from flexsat.control.scheduled import interpolate_schedule

EPS = np.finfo(float).eps
KNOTS = np.array([0.0, 2.0, 4.0, 6.0])
DT, NT, NC = 0.05, 160, 3  # the run passes every knot and holds past the last one
TIMES = DT * np.arange(NT)


@pytest.fixture(scope="module")
def rng():
    return np.random.default_rng(3)


def test_constant_schedule_is_a_constant_gain(rng):
    K = rng.normal(size=(2, 4))
    flat = ScheduledStateFeedback(
        KNOTS, np.broadcast_to(K, (4, 2, 4)), "state", commands=("torque", "force")
    )
    one = ScheduledStateFeedback([0.0], K[None], "state", commands=("torque", "force"))
    Y = rng.normal(size=(NT, NC, 4))
    direct = -np.einsum("ij,tcj->tci", K, Y)
    tol = 4 * EPS * np.einsum("ij,tcj->tci", np.abs(K), np.abs(Y)).max()
    for law in (flat, one):
        assert law.reads == ("state",) and law.read_sizes == (4,)
        assert np.abs(run_controller(law, TIMES, Y) - direct).max() <= tol
    assert one.linear_form(DT, TIMES, NC).Dk.shape == (1, 1, 2, 4)  # not tabulated in time


def test_interpolation_exact_at_knots_linear_between_held_outside(rng):
    gains = rng.normal(size=(4, 1, 3))
    np.testing.assert_array_equal(interpolate_schedule(KNOTS, gains, KNOTS), gains)
    w = rng.uniform(size=20)
    i = rng.integers(0, 3, size=20)
    t = KNOTS[i] + w * 2.0
    expect = (1 - w)[:, None, None] * gains[i] + w[:, None, None] * gains[i + 1]
    got = interpolate_schedule(KNOTS, gains, t)
    assert np.abs(got - expect).max() <= 4 * EPS * np.abs(gains).max()
    # linear: the midpoint of two times inside one interval has the mean of their gains
    a, b = interpolate_schedule(KNOTS, gains, [2.5, 3.5])
    mid = interpolate_schedule(KNOTS, gains, 3.0)
    assert np.abs(mid - (a + b) / 2).max() <= 4 * EPS * np.abs(gains).max()
    np.testing.assert_array_equal(interpolate_schedule(KNOTS, gains, [-1.0, 9.0]), gains[[0, -1]])


def test_command_is_continuous_across_the_knots(rng):
    """F10 "continuity of commands": for a fixed state, u(t_i ± δ) differ by O(δ)."""
    law = ScheduledStateFeedback(KNOTS, rng.normal(size=(4, 1, 2)), ["theta", "theta_dot"])
    y = {"theta": np.array([0.3]), "theta_dot": np.array([-0.1])}
    slope = np.abs(np.diff(law.gains, axis=0)).max() / 2.0  # max |dK/dt|, per second
    y_sum = 0.4  # Σ|y_j|
    delta = 1e-6
    for tk in KNOTS[1:-1]:
        u_minus, _ = law(tk - delta, y, {})
        u_plus, _ = law(tk + delta, y, {})
        # |Δu| <= Σ|ΔK_j||y_j| <= 2δ max|dK/dt| Σ|y_j|, plus the rounding of both commands
        bound = 2 * delta * slope * y_sum + 8 * EPS * np.abs(law.gains).max() * y_sum
        assert abs(u_plus - u_minus).max() <= bound


def test_linear_form_is_the_law_per_case_gains(rng):
    """Per-case schedules, a tabulated state reference, a feedforward function of t, several
    channels of several widths: the linear form equals the law called sample by sample."""
    n, m = 4, 3
    gains = rng.normal(size=(4, NC, m, n))
    x_ref = rng.normal(size=(4, NC, n))

    def u_ff(t):
        return np.array([np.sin(t), np.cos(t), t])

    law = ScheduledStateFeedback(
        KNOTS,
        gains,
        ["theta", "theta_dot", ("q", 2)],
        {"torque": 1, "force": 2},
        state_reference=x_ref,
        feedforward=u_ff,
    )
    assert law.n_cases == NC and law.write_sizes == (1, 2)
    form = law.linear_form(DT, TIMES, NC)
    assert form.Dk.shape == (NT, NC, m, n)
    Y = rng.normal(size=(NT, NC, n))
    slow, fast = run_controller(law, TIMES, Y), run_linear_law(form, Y)
    terms = np.abs(form.u_ff) + np.einsum("tcij,tcj->tci", np.abs(form.Dk), np.abs(Y - form.y_ref))
    assert np.abs(fast - slow).max() <= 4 * EPS * terms.max()
    k = int(np.searchsorted(TIMES, 2.0))  # a knot on the sample grid: the designed gain
    np.testing.assert_array_equal(form.Dk[k], -gains[1])


def test_times_accept_units():
    law = ScheduledStateFeedback(["0 s", "500 ms", "1 s"], np.zeros((3, 1, 1)), "theta")
    np.testing.assert_array_equal(law.knots, [0.0, 0.5, 1.0])


@pytest.mark.parametrize(
    "kwargs,field,rule",
    [
        (dict(times=[0.0, 1.0, 1.0]), "times", "strictly increasing"),
        (dict(times=["0 s", "1 m"]), "times", "incompatible units"),
        (dict(gains=np.zeros((3, 1, 2))), "gains", r"n_knots = 2 schedule times, got \(3, 1, 2\)"),
        (dict(gains=np.full((2, 1, 2), np.nan)), "gains", "finite"),
        (dict(measurements=["theta"]), "measurements", "sum to 1, the gains have n = 2 columns"),
        (dict(commands=["torque", "force"]), "commands", "sum to 2, the gains have m = 1 rows"),
        (dict(state_reference=np.zeros((2, 3))), "state_reference", r"\(n_knots, 2\)"),
        (dict(feedforward=np.zeros((3, 1))), "feedforward", r"\(n_knots, 1\)"),
    ],
)
def test_bad_schedules_name_the_field(kwargs, field, rule):
    args = (
        dict(
            times=[0.0, 1.0],
            gains=np.zeros((2, 1, 2)),
            measurements=["theta", "theta_dot"],
            commands="torque",
        )
        | kwargs
    )
    with pytest.raises(ValueError, match=rf"^{field}: .*{rule}"):
        ScheduledStateFeedback(**args)


def test_case_counts_and_feedforward_shapes_are_checked():
    law = ScheduledStateFeedback(
        [0.0, 1.0],
        np.zeros((2, 3, 1, 2)),
        ["theta", "theta_dot"],
        feedforward=lambda t: np.zeros(2),
    )
    with pytest.raises(ValueError, match=r"^gains: have 3 cases, the run has n_cases = 5"):
        law.linear_form(DT, TIMES, 5)
    with pytest.raises(ValueError, match=r"^feedforward: must have shape \(1,\)"):
        law.linear_form(DT, TIMES, 3)
    law = ScheduledStateFeedback(
        [0.0, 1.0], np.zeros((2, 1, 2)), ["theta", "theta_dot"], state_reference=np.zeros((2, 4, 2))
    )
    with pytest.raises(ValueError, match=r"^state_reference: have 4 cases, the run has n_cases"):
        law.linear_form(DT, TIMES, 3)
