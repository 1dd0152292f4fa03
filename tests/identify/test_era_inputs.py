"""Bad input to the realization API (:mod:`flexsat.identify.era`) is refused by name: every
call below raises a :class:`~flexsat.input_checks.FieldError` whose field is the parameter at
fault (never a numpy traceback, a long run or NaN).

The data are the exact pulse response of the two-mode SISO system of tests/markov_data.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat import limits
from flexsat.identify.era import (
    bootstrap_uncertainty,
    era,
    era_dc,
    mac,
)
from flexsat.input_checks import FieldError
from flexsat.units import Q_
from markov_data import DT, two_mode_system

NAN, INF = np.nan, np.inf
#: values that are no count
NOT_COUNTS = [NAN, INF, -1, 0, 1.5, [], "abc", Q_(1.0, "m"), 1 + 1j, np.ones((2, 2))]
#: values that are no positive number
NOT_POSITIVE = [NAN, INF, -1.0, 0.0, [], "abc", Q_(1.0, "m"), 1 + 1j, np.ones((2, 2))]


@pytest.fixture(scope="module")
def markov():
    Ad, Bd, Cd, Dd = two_mode_system()
    return np.array([Dd] + [Cd @ np.linalg.matrix_power(Ad, k - 1) @ Bd for k in range(1, 400)])


def _raises(field, call):
    with pytest.raises(FieldError) as err:
        call()
    assert err.value.field.startswith(field), str(err.value)
    assert str(err.value).startswith(field)


# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "field, changes",
    [
        *[("markov", {"markov": b}) for b in (NAN, INF, [], "abc", np.ones((2, 2, 2, 2)))],
        *[("dt", {"dt": b}) for b in NOT_POSITIVE],
        ("dt", {"dt": Q_(10.0, "m")}),
        *[("order", {"order": b}) for b in NOT_COUNTS],
        *[("rows", {"rows": b}) for b in NOT_COUNTS],
        *[("cols", {"cols": b}) for b in NOT_COUNTS],
        ("rows", {"rows": 10**9}),  # more than the data: refused before the Hankel matrix
        *[
            ("reference_shapes", {"reference_shapes": b})
            for b in (NAN, INF, [], "abc", Q_(1.0, "m"), np.ones((2, 2)), np.zeros((1, 2)))
        ],
    ],
    ids=lambda v: repr(v)[:50],
)
@pytest.mark.parametrize("realize", [era, era_dc])
def test_era_refuses_by_name(markov, realize, field, changes):
    given = {"markov": markov, "dt": DT, "order": 4, **changes}
    _raises(field, lambda: realize(**given))


def test_era_takes_dt_as_a_time_quantity(markov):
    """dt in ms gives the realization of dt in s (the frequencies 2 and 7 rad/s)."""
    real = era(markov, Q_(10.0, "ms"), order=4)
    assert np.allclose(np.asarray(real.frequencies_hz) * 2 * np.pi, [2.0, 7.0], rtol=1e-6)


@pytest.mark.parametrize(
    "field, args",
    [
        ("phi", ("abc", np.ones((2, 2)))),
        ("phi", (Q_(np.ones((2, 2)), "m"), np.ones((2, 2)))),
        ("phi", ([[NAN, 1.0], [1.0, 1.0]], np.ones((2, 2)))),
        ("phi", ([], np.ones((2, 2)))),
        ("reference_shapes", (np.ones((2, 2)), "abc")),
        ("reference_shapes", (np.ones((2, 2)), np.ones((3, 2)))),
    ],
    ids=lambda v: repr(v)[:50],
)
def test_mac_refuses_by_name(field, args):
    _raises(field, lambda: mac(*args))


@pytest.mark.parametrize(
    "field, changes",
    [
        ("realization", {"realization": None}),
        *[("markov", {"markov": b}) for b in (NAN, [], "abc")],
        *[("n_samples", {"n_samples": b}) for b in NOT_COUNTS],
        ("n_samples", {"n_samples": 1}),
        ("n_samples", {"n_samples": limits.MAX_BOOTSTRAP_SAMPLES + 1}),  # was: ran for hours
        *[("seed", {"seed": b}) for b in (NAN, INF, -1, 1.5, "abc", Q_(1.0, "m"), 2**40, [])],
        *[("match_tolerance", {"match_tolerance": b}) for b in NOT_POSITIVE],
        ("match_tolerance", {"match_tolerance": 2.0}),
    ],
    ids=lambda v: repr(v)[:50],
)
def test_bootstrap_uncertainty_refuses_by_name(markov, field, changes):
    given = {"realization": era(markov, DT, order=4), "markov": markov, "n_samples": 3, **changes}
    _raises(field, lambda: bootstrap_uncertainty(**given))
