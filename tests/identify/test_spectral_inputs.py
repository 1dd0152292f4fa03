"""Bad input to the FRF functions (:mod:`flexsat.identify.spectral`) is refused by name: every
call below raises a :class:`~flexsat.input_checks.FieldError` whose field is the parameter at
fault (never a numpy or scipy traceback, a long run or NaN)."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.cases import get_case
from flexsat.identify import Channel, Measurement
from flexsat.identify.spectral import estimate_frf, frequency_response
from flexsat.input_checks import FieldError
from flexsat.units import Q_
from param_ids import stable_id

NAN, INF = np.nan, np.inf
SENSORS = [Channel.at("displacement", 1, "z")]
INPUTS = [Channel.at("force", 1, "z")]
FREQUENCIES = np.array([0.1, 1.0, 5.0])


def _raises(field, call):
    with pytest.raises(FieldError) as err:
        call()
    assert err.value.field.startswith(field), str(err.value)
    assert str(err.value).startswith(field)


@pytest.fixture(scope="module")
def grid():
    return get_case("tamu_grid").builder().modal_model(4, damping=0.05)


@pytest.fixture(scope="module")
def undamped():
    return get_case("tamu_grid").builder().modal_model(4, damping=0.0)


def _test(inputs=1, samples=2000):
    """A random test at 40 Hz: white inputs, a moving average of the first as output."""
    rng = np.random.default_rng(0)
    t = np.arange(samples) / 40.0
    u = rng.standard_normal((inputs, samples))
    y = np.convolve(u[0], np.ones(5) / 5, "same")[None]
    chans = [Channel.at("force", node, "z") for node in range(1, inputs + 1)]
    return Measurement(t, y, SENSORS, u, chans, "time")


# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "field, changes",
    [
        *[
            ("segment", {"segment": b})
            for b in (
                NAN,
                INF,
                -1,
                0,
                2,
                [],
                "abc",
                True,
                Q_(1.0, "m"),
                1.5,
                np.ones((2, 2)),
                10**9,
            )
        ],
        *[
            ("overlap", {"overlap": b})
            for b in (NAN, INF, -0.1, 1.0, [], "abc", Q_(1.0, "m"), 1 + 1j, np.ones(2))
        ],
        *[
            ("window", {"window": b})
            for b in (
                NAN,
                0.0,
                [],
                "abc",
                "nope",
                ("kaiser",),
                np.ones(3),
                np.zeros(256),
                [NAN] * 256,
            )
        ],
        ("measurement", {"measurement": None}),
        ("measurement", {"measurement": np.ones((2, 100))}),
        ("measurement", {"measurement": Measurement(np.arange(3.0), np.ones((1, 3)), SENSORS)}),
        (
            "measurement",
            {
                "measurement": Measurement(
                    np.arange(1.0, 4.0), np.ones((1, 1, 3)), SENSORS, None, INPUTS, "frequency"
                )
            },
        ),
    ],
    ids=stable_id,
)
def test_estimate_frf_refuses_by_name(field, changes):
    given = {"measurement": _test(), "segment": 256, **changes}
    _raises(field, lambda: estimate_frf(**given))


def test_estimate_frf_refuses_no_input_power_and_correlated_inputs():
    test = _test(inputs=2)
    silent = Measurement(test.abscissa, test.outputs, SENSORS, 0 * test.inputs, test.input_channels)
    same = Measurement(
        test.abscissa, test.outputs, SENSORS, np.vstack([test.inputs[0]] * 2), test.input_channels
    )
    for measurement in (silent, same):
        _raises("measurement", lambda m=measurement: estimate_frf(m, 256))


def test_estimate_frf_needs_more_segments_than_inputs():
    """Three inputs, four segments of a 16-sample record: n_d - r = 1 is allowed, three
    segments are not (was: the random error divided by max(n_d - r, 1), silently)."""
    assert estimate_frf(_test(inputs=3, samples=16), 6, overlap=0.5).segments == 4
    _raises("segment", lambda: estimate_frf(_test(inputs=3, samples=16), 8, overlap=0.5))


def test_estimate_frf_window_forms():
    """A name, a (name, parameter) tuple and explicit weights give the same estimate."""
    test = _test()
    named = estimate_frf(test, 256, window="hann")
    weights = estimate_frf(test, 256, window=np.hanning(257)[:256])
    kaiser = estimate_frf(test, 256, window=("kaiser", 0.0))  # beta 0: the boxcar
    boxcar = estimate_frf(test, 256, window="boxcar")
    assert np.allclose(named.frf.outputs, weights.frf.outputs, rtol=1e-12)
    assert np.allclose(kaiser.frf.outputs, boxcar.frf.outputs, rtol=1e-12)


# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "field, changes",
    [
        *[
            ("frequencies_hz", {"frequencies_hz": b})
            for b in (NAN, INF, -1.0, [], "abc", Q_(1.0, "m"), np.ones((2, 3)), 1 + 1j)
        ],
        ("frequencies_hz", {"frequencies_hz": np.linspace(0.1, 10.0, 3_000_000)}),  # 3 GB solve
        *[
            ("sample_rate", {"sample_rate": b})
            for b in (NAN, INF, -1.0, 0.0, [], "abc", Q_(40.0, "m"), np.ones(2), 1e-300)
        ],
        ("modal_model", {"modal_model": None}),
        ("sensors", {"sensors": []}),
        ("sensors", {"sensors": None}),
        ("sensors[0]", {"sensors": ["x"]}),
        ("inputs", {"inputs": []}),
        ("inputs[0]", {"inputs": [5]}),
        ("sensors or inputs: node", {"sensors": [Channel.at("displacement", 9999, "z")]}),
    ],
    ids=lambda v: repr(v)[:60],
)
def test_frequency_response_refuses_by_name(grid, field, changes):
    given = {
        "modal_model": grid,
        "sensors": SENSORS,
        "inputs": INPUTS,
        "frequencies_hz": FREQUENCIES,
        **changes,
    }
    _raises(field, lambda: frequency_response(**given))


def test_frequency_response_at_an_undamped_resonance_is_refused(undamped):
    f1 = undamped.frequencies[0] / (2 * np.pi)
    _raises("frequencies_hz", lambda: frequency_response(undamped, SENSORS, INPUTS, [f1]))
    # beside it, finite
    assert np.all(np.isfinite(frequency_response(undamped, SENSORS, INPUTS, [0.9 * f1])))
