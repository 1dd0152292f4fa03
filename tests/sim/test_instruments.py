"""Claims of the instruments (flexsat.sim.instruments): the true value of every linear channel
is y = C x + D u + D_f f_in from the plant's output matrices, stacked into one product; each
channel then goes through its own sensor (noise from its own stream columns, quantum, bias,
range); a derivative sensor differentiates the *measured* source channel.

The matrices, states and inputs below are small integers and halves, so every product and sum
is exact in binary floating point: "equal" means bit for bit, whatever order the stacked
product sums in."""

import numpy as np
import pytest

from flexsat.dynamics.plant import Channel, Plant
from flexsat.sim import ChannelSensor, SimConfig
from flexsat.sim.channels import noise_columns, resolve_channels
from flexsat.sim.instruments import Instruments, stacked_output_matrices, unit_row
from flexsat.sim.sensors import least_squares_derivative_weights

BASE = {
    # name: (C, D, D_f); None where the output does not depend on it
    "p": (np.array([[1.0, 0.0, 0.0]]), None, None),
    "pair": (
        np.array([[1.0, 2.0, 0.0], [0.0, -1.0, 3.0]]),
        np.array([[0.5, 0.0], [0.0, -2.0]]),
        None,
    ),
    "load": (np.array([[0.0, 0.0, 1.0]]), np.array([[0.25, 0.0]]), np.array([[1.0, 0.0]])),
    "scaled": (np.array([[0.0, 2.0, 0.0]]), None, None),
    "fed": (np.array([[0.0, 1.0, 0.0]]), np.array([[0.0, 1.0]]), None),
    "rate": (np.array([[0.0, 1.0, 0.0]]), None, None),
}


class Probe(Plant):
    """Three states, two inputs, outputs of every kind: a state coordinate ``p``, a 2-wide
    ``pair`` with feedthrough, ``load`` with an input-force term, a scaled coordinate, one with
    feedthrough only, a nonlinear ``curve`` = x_0² and ``rate`` (measured by a derivative
    sensor). ``gains`` (n_cases,) makes ``pair`` per case (a dispersed plant)."""

    inputs = (Channel("push", "N"), Channel("twist", "N*m"))
    outputs = (
        Channel("p", "m"),
        Channel("pair", "m", size=2),
        Channel("load", "N"),
        Channel("scaled", "m"),
        Channel("fed", "m"),
        Channel("curve", "m**2"),
        Channel("rate", "m/s"),
    )
    noise_channels = ("p", "pair", "load", "rate", "push")
    nx = 3

    def __init__(self, gains=None):
        self.gains = None if gains is None else np.asarray(gains, float)

    @property
    def n_cases(self):
        return 1 if self.gains is None else len(self.gains)

    def linear_part(self):
        return np.zeros((3, 3)), np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])

    def output_matrices(self, name):
        if name == "curve":
            return None
        C, D, Df = BASE[name]
        if name == "pair" and self.gains is not None:
            C = self.gains[:, None, None] * C
        return C, D, Df

    def output(self, name, x, u, f_in=None):
        if name == "curve":
            return x[..., 0] ** 2
        return super().output(name, x, u, f_in)


def _exact(rng, *shape):
    """Random halves in [-8, 8]: exact in binary floating point, as are their small sums."""
    return rng.integers(-16, 17, size=shape) / 2.0


def _truth(name, x, u, f):
    C, D, Df = BASE[name]
    y = x @ C.T + (0 if D is None else u @ D.T) + (0 if Df is None else f @ Df.T)
    return y[:, 0] if y.shape[1] == 1 else y


def _instruments(plant, names, nc, config=None, dt=0.1, batched=False, forced=True):
    config = config or SimConfig(duration=1.0)
    sensors = resolve_channels(plant, config)[0]
    return Instruments(plant, names, sensors, noise_columns(plant), dt, nc, batched, forced)


# -- stacked matrices and unit rows -----------------------------------------------------------
def test_output_matrices_are_stacked_row_wise_with_zeros_for_missing_blocks():
    plant = Probe()
    mats = [plant.output_matrices(k) for k in ("p", "pair", "load")]
    C, D, Df = stacked_output_matrices(mats, plant.n_inputs)
    np.testing.assert_array_equal(C, np.vstack([BASE[k][0] for k in ("p", "pair", "load")]))
    np.testing.assert_array_equal(D, [[0, 0], [0.5, 0], [0, -2], [0.25, 0]])
    np.testing.assert_array_equal(Df, [[0, 0], [0, 0], [0, 0], [1, 0]])


def test_a_dispersed_block_makes_every_block_per_case():
    plant = Probe(gains=[1.0, 2.0, -1.0])
    mats = [plant.output_matrices(k) for k in ("p", "pair")]
    C, D, Df = stacked_output_matrices(mats, plant.n_inputs)
    assert C.shape == (3, 3, 3) and D.shape == (3, 3, 2) and Df.shape == (3, 3, 2)
    for i, g in enumerate([1.0, 2.0, -1.0]):
        np.testing.assert_array_equal(C[i], np.vstack([BASE["p"][0], g * BASE["pair"][0]]))
        np.testing.assert_array_equal(D[i, 1:], BASE["pair"][1])


@pytest.mark.parametrize(
    "name, row",
    [
        ("p", 0),
        ("rate", 1),  # x_0 and x_1 exactly
        ("pair", None),
        ("scaled", None),  # not one unit row
        ("fed", None),
        ("load", None),  # a feedthrough term
        ("curve", None),
        ("nothing", None),  # nonlinear; not an output
    ],
)
def test_unit_row_is_the_state_index_an_output_reads_exactly(name, row):
    assert unit_row(Probe(), name) == row


def test_unit_row_of_a_dispersed_output_must_hold_for_every_case():
    class PerCase(Probe):
        def output_matrices(self, name):
            if name == "p":
                C = np.zeros((3, 1, 3))
                C[:, 0, 0] = self.gains
                return C, None, None
            return super().output_matrices(name)

    assert unit_row(PerCase(gains=[1.0, 1.0, 1.0]), "p") == 0
    assert unit_row(PerCase(gains=[1.0, 1.0, 0.5]), "p") is None


# -- true values ------------------------------------------------------------------------------
def test_ideal_measurements_are_c_x_plus_d_u_plus_df_f_exactly():
    rng = np.random.default_rng(0)
    plant, nc = Probe(), 5
    inst = _instruments(plant, ("p", "pair", "load", "scaled", "fed"), nc)
    for first in (True, False):
        x, u, f = _exact(rng, nc, 3), _exact(rng, nc, 2), _exact(rng, nc, 2)
        y = inst.measure(x, u, f, None, first)
        assert set(y) == {"p", "pair", "load", "scaled", "fed"}
        assert y["pair"].shape == (nc, 2) and y["p"].shape == (nc,)
        for k, v in y.items():
            np.testing.assert_array_equal(v, _truth(k, x, u, f), err_msg=k)


def test_a_nonlinear_output_comes_from_the_plants_output():
    rng = np.random.default_rng(1)
    inst = _instruments(Probe(), ("curve", "p"), 4)
    x = _exact(rng, 4, 3)
    y = inst.measure(x, np.zeros((4, 2)), None, None, True)
    np.testing.assert_array_equal(y["curve"], x[:, 0] ** 2)
    np.testing.assert_array_equal(y["p"], x[:, 0])


def test_a_dispersed_plant_is_measured_per_case():
    rng = np.random.default_rng(2)
    gains = np.array([1.0, 2.0, -0.5])
    inst = _instruments(Probe(gains=gains), ("p", "pair"), 3, batched=True)
    x, u = _exact(rng, 3, 3), _exact(rng, 3, 2)
    y = inst.measure(x, u, None, None, True)
    pair = gains[:, None] * (x @ BASE["pair"][0].T) + u @ BASE["pair"][1].T
    np.testing.assert_array_equal(y["pair"], pair)
    np.testing.assert_array_equal(y["p"], x[:, 0])


# -- sensors per channel ----------------------------------------------------------------------
def test_each_channel_gets_its_own_sensor_and_noise_columns():
    """Stream columns (noise_channels p, pair, load, rate, push): p → 0, pair → 1:3,
    load → 3. p is noisy, the 2-wide pair noisy then quantized, load biased and clipped; the
    unmeasured ``fed`` stays exact. Quantized values are compared after the same operations
    (round(·/q) of the same double: exact)."""
    rng = np.random.default_rng(3)
    nc = 6
    config = SimConfig(
        duration=1.0,
        channel_sensors={
            "p": ChannelSensor(noise=0.5),
            "pair": ChannelSensor(noise="250 mm", quantum=0.25),
            "load": ChannelSensor(bias=1.0, range=3.0),
        },
    )
    plant = Probe()
    assert noise_columns(plant)["pair"] == slice(1, 3)
    inst = _instruments(plant, ("p", "pair", "load", "fed"), nc, config)
    x, u, f = _exact(rng, nc, 3), _exact(rng, nc, 2), _exact(rng, nc, 2)
    noise = rng.standard_normal((nc, 6))
    y = inst.measure(x, u, f, noise, True)
    np.testing.assert_array_equal(y["p"], _truth("p", x, u, f) + 0.5 * noise[:, 0])
    np.testing.assert_array_equal(
        y["pair"], 0.25 * np.round((_truth("pair", x, u, f) + 0.25 * noise[:, 1:3]) / 0.25)
    )
    np.testing.assert_array_equal(y["load"], np.clip(_truth("load", x, u, f) + 1.0, -3, 3))
    np.testing.assert_array_equal(y["fed"], _truth("fed", x, u, f))


def test_a_derivative_sensor_differentiates_the_measured_source():
    """``rate`` as the least-squares derivative of the *quantized* ``p`` over its last 4
    samples: 0 at the first sample (the filter starts at rest on the first measurement), then
    hist @ w of the measured history; a ramp p = 0.75 t with a 1/8 quantum reads exactly as
    the measured samples allow, and the source is measured even when the law does not read
    it."""
    dt, nc = 0.1, 2
    config = SimConfig(
        duration=1.0,
        channel_sensors={
            "p": ChannelSensor(quantum=0.125),
            "rate": ChannelSensor(derivative_of="p", window=4, order=1),
        },
    )
    inst = _instruments(Probe(), ("rate",), nc, config, dt=dt)
    w = least_squares_derivative_weights(4, 1, dt)
    measured, out = [], []
    for k in range(10):
        x = np.zeros((nc, 3))
        x[:, 0] = [0.75 * k * dt, -0.75 * k * dt]
        y = inst.measure(x, np.zeros((nc, 2)), None, None, k == 0)
        measured.append(0.125 * np.round(x[:, 0] / 0.125))
        np.testing.assert_array_equal(y["p"], measured[-1])
        out.append(y["rate"])
    assert np.all(out[0] == 0.0)
    hist = [measured[0]] * 3 + measured
    for k in range(10):
        expected = np.stack(hist[k : k + 4], axis=1) @ w
        # the filter shifts its history in place; its dot product may sum in another order:
        # a few ulp of the largest term |w_j p_j| (≈ 10 × 1)
        np.testing.assert_allclose(out[k], expected, rtol=0, atol=1e-13)
    # away from the start the quantized ramp's slope is recovered to about q / (window·dt)
    assert np.abs(np.array(out[5:])[:, 0] - 0.75).max() < 0.125 / (4 * dt)


def test_a_derivative_of_an_exact_ramp_is_its_slope():
    """Order-1 fit of a line: exact to rounding (cond of the 8-point Vandermonde × eps)."""
    dt = 1 / 75
    config = SimConfig(
        duration=1.0, channel_sensors={"rate": ChannelSensor(derivative_of="p", window=8, order=1)}
    )
    inst = _instruments(Probe(), ("p", "rate"), 1, config, dt=dt)
    for k in range(12):
        x = np.array([[0.3 + 2.5 * k * dt, 0.0, 0.0]])
        y = inst.measure(x, np.zeros((1, 2)), None, None, k == 0)
    np.testing.assert_allclose(y["rate"], 2.5, rtol=1e-12)
