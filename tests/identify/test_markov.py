"""Markov parameters (:mod:`flexsat.identify.markov`): OKID and impulse tests on the TAMU grid
against the exact pulse response (Juang et al. 1993), and bad input refused by name (a
:class:`~flexsat.input_checks.FieldError` naming the parameter at fault; the random test is
that of the two-mode system of tests/markov_data.py)."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.cases.tamu_grid import tamu_grid
from flexsat.identify import Channel, era, impulse_hammer, random_force, torque_history
from flexsat.identify.markov import markov_from_frf, markov_parameters, okid
from flexsat.input_checks import FieldError
from flexsat.sim.vibration_test import simulate_test
from flexsat.units import Q_
from markov_data import discrete_markov, frf_grid, two_mode_system

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels

RATE = 50.0  # sampling rate of the grid tests, Hz
NAN, INF = np.nan, np.inf
#: values that are no count
NOT_COUNTS = [NAN, INF, -1, 0, 1.5, [], "abc", Q_(1.0, "m"), 1 + 1j, np.ones((2, 2))]
#: values that are no positive number
NOT_POSITIVE = [NAN, INF, -1.0, 0.0, [], "abc", Q_(1.0, "m"), 1 + 1j, np.ones((2, 2))]


@pytest.fixture(scope="module")
def grid():
    return tamu_grid().modal_model(6, damping=0.01)


@pytest.fixture(scope="module")
def test_data():
    """(u, y) of 2000 samples of white noise through the system."""
    Ad, Bd, Cd, Dd = two_mode_system()
    u = np.random.default_rng(0).standard_normal((1, 2000))
    x, y = np.zeros(4), []
    for k in range(u.shape[1]):
        y.append(Cd @ x + Dd @ u[:, k])
        x = Ad @ x + Bd @ u[:, k]
    return u, np.array(y).T


def _raises(field, call):
    with pytest.raises(FieldError) as err:
        call()
    assert err.value.field.startswith(field), str(err.value)
    assert str(err.value).startswith(field)


def test_okid_recovers_markov_parameters(grid):
    """Noise-free random force and reaction-wheel torque: OKID Markov parameters to 1e-8."""
    out = [Channel.at("displacement", n, "z") for n in (1, 5, 9, 13)]
    out.append(Channel.at("acceleration", 3, "z"))
    torque = np.random.default_rng(3).standard_normal(500)
    ex = [random_force(1, "z"), torque_history(7, "x", torque)]
    meas = simulate_test(grid, ex, out, 10.0, RATE, seed=2)
    Y = okid(meas.inputs, meas.outputs, 60)
    ref = discrete_markov(grid, out, [e.channel for e in ex], meas.dt, 60)
    assert np.max(np.abs(Y - ref)) < 1e-8 * np.max(np.abs(ref))
    res = era(Y, dt=meas.dt, order=12)
    assert np.allclose(res.frequencies_hz, grid.frequencies_hz, rtol=1e-8)


def test_markov_from_longer_pulse(grid):
    """A half-sine hammer spanning two samples is deconvolved by least squares."""
    out = [Channel.at("displacement", 1, "z")]
    meas = simulate_test(grid, impulse_hammer(2, "z", 5.0, width=0.03), out, 4.0, RATE)
    n = meas.abscissa.size - 1
    Y = markov_parameters(meas, n_markov=n)
    ref = discrete_markov(grid, out, [meas.input_channels[0]], meas.dt, n)
    assert np.max(np.abs(Y - ref)) < 1e-8 * np.max(np.abs(ref))


def test_markov_degenerate_inputs():
    with pytest.raises(ValueError, match="^y: must have as many samples"):
        okid(np.zeros((1, 100)), np.zeros((2, 99)), 10)
    with pytest.raises(ValueError, match="^u: must be finite"):
        okid([np.nan] * 100, np.zeros(100), 10)
    with pytest.raises(ValueError, match="^u: the input is zero"):
        markov_parameters(u=np.zeros(50), y=np.ones(50))


def test_frf_degenerate_inputs():
    freqs = frf_grid(10.0, 20.0)
    H = 1 / (1 - (2 * np.pi * freqs) ** 2 + 0.02j * 2 * np.pi * freqs)
    bad = H.copy()
    bad[7] = np.nan
    with pytest.raises(ValueError, match="^frf: must be finite"):
        markov_from_frf(freqs, bad)
    uneven = freqs.copy()
    uneven[5] += 0.3 * (freqs[1] - freqs[0])
    with pytest.raises(ValueError, match="^frequencies: must be uniformly spaced"):
        markov_from_frf(uneven, H)
    with pytest.raises(ValueError, match="^frequencies: must start at 0 Hz"):
        markov_from_frf(freqs[1:], H[1:])
    with pytest.raises(ValueError, match="^frf: must have shape"):
        markov_from_frf(freqs, H[:-1])
    with pytest.raises(ValueError, match="^n_markov: the period holds"):
        markov_from_frf(freqs, H, n_markov=freqs.size * 2)


@pytest.mark.parametrize(
    "field, changes",
    [
        *[("u", {"u": b}) for b in (NAN, INF, [], "abc", np.ones((2, 2, 2)))],
        *[("y", {"y": b}) for b in (NAN, INF, "abc", np.ones((2, 2, 2)))],
        ("y", {"y": np.ones((1, 100))}),  # fewer samples than u
        *[("n_markov", {"n_markov": b}) for b in NOT_COUNTS],
        ("n_markov", {"n_markov": 10**9}),  # was: a recursion of 1e9 steps
        *[("n_observer", {"n_observer": b}) for b in NOT_COUNTS],
        ("n_observer", {"n_observer": 10**6}),
    ],
    ids=lambda v: repr(v)[:50],
)
def test_okid_refuses_by_name(test_data, field, changes):
    u, y = test_data
    given = {"u": u, "y": y, "n_markov": 50, **changes}
    _raises(field, lambda: okid(**given))


@pytest.mark.parametrize(
    "field, kwargs",
    [
        ("measurement", {}),
        ("measurement[0]", {"measurement": 5}),
        ("u", {"u": [NAN] * 10, "y": [1.0] * 10}),
        ("n_markov", {"u": [1.0] * 10, "y": [1.0] * 10, "n_markov": 0}),
    ],
    ids=repr,
)
def test_markov_parameters_refuses_by_name(field, kwargs):
    _raises(field, lambda: markov_parameters(**kwargs))


@pytest.mark.parametrize(
    "field, changes",
    [
        *[("frequencies", {"frequencies": b}) for b in (NAN, INF, [], "abc", Q_(1.0, "m"))],
        ("frequencies", {"frequencies": np.linspace(0.0, 50.0, 201) ** 1.1}),  # not uniform
        *[("frf", {"frf": b}) for b in (NAN, INF, [], "abc", np.ones((2, 2)))],
        *[("n_markov", {"n_markov": b}) for b in NOT_COUNTS],
        *[("tail_tolerance", {"tail_tolerance": b}) for b in NOT_POSITIVE],
    ],
    ids=lambda v: repr(v)[:50],
)
def test_markov_from_frf_refuses_by_name(field, changes):
    f = np.linspace(0.0, 50.0, 201)
    given = {"frequencies": f, "frf": np.ones(201, complex), **changes}
    _raises(field, lambda: markov_from_frf(**given))
