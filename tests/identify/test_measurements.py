"""Measurement data object, synthetic tests and UFF 58 round trips."""

import numpy as np
import pytest

from flexsat.identify import (
    Channel,
    Measurement,
    harmonic_shaker,
    impulse_hammer,
    random_force,
    torque_history,
    uff_direction,
)
from flexsat.sim.vibration_test import simulate_test
from flexsat.structures.modal_model import ModalModel

pytest.importorskip("pyuff")


@pytest.fixture(scope="module")
def beam():
    """Two-mode, three-node toy modal model (z translation and x rotation only)."""
    shapes = np.zeros((2, 3, 6))
    shapes[0, :, 2] = [0.1, 0.3, 0.5]
    shapes[1, :, 2] = [0.4, 0.1, -0.3]
    shapes[:, :, 3] = 0.2 * shapes[:, :, 2]
    rigid = np.diag([10.0, 10.0, 10.0, 5.0, 5.0, 5.0])
    return ModalModel(
        [1, 2, 3],
        [[0, 0, 0], [1, 0, 0], [2, 0, 0]],
        [2 * np.pi, 6 * np.pi],
        0.02,
        shapes,
        rigid,
        np.zeros((2, 6)),
        boundary="cantilevered",
    )


def test_channel_defaults_and_errors():
    c = Channel.at("acceleration", 3, "z")
    assert c.unit == "m/s^2" and uff_direction(c) == 3 and c.name == "acceleration 3z"
    assert uff_direction(Channel.at("torque", 1, "x")) == 4
    assert Channel.at("torque", 1, "x").unit == "N*m"
    with pytest.raises(ValueError, match="^kind:"):
        Channel.at("pressure", 1, "z")
    with pytest.raises(ValueError, match="^direction:"):
        Channel.at("displacement", 1, "w")
    with pytest.raises(ValueError, match="^node_a:"):
        Channel.at("strain", 2, "x")


def test_measurement_validation():
    t = np.arange(5) * 0.1
    ch = (Channel.at("displacement", 1, "z"),)
    with pytest.raises(ValueError, match="^outputs: must be finite"):
        Measurement(t, [[0, np.nan, 0, 0, 0]], ch)
    with pytest.raises(ValueError, match="^outputs: must have shape"):
        Measurement(t, np.zeros((2, 5)), ch)
    with pytest.raises(ValueError, match="^inputs: must have shape"):
        Measurement(t, np.zeros((1, 5)), ch, np.zeros((1, 4)), (Channel.at("force", 1, "z"),))
    with pytest.raises(ValueError, match="^abscissa: time samples must be uniformly"):
        Measurement([0, 0.1, 0.3], np.zeros((1, 3)), ch)
    with pytest.raises(ValueError, match="^outputs: FRFs must have shape"):
        Measurement(
            [1.0, 2.0], np.zeros((1, 2)), ch, None, (Channel.at("force", 1, "z"),), "frequency"
        )
    with pytest.raises(ValueError, match="^outputs: must be finite"):
        Measurement(
            [1.0, 2.0], [[[1, np.nan]]], ch, None, (Channel.at("force", 1, "z"),), "frequency"
        )


def test_impulse_response_matches_modal_sum(beam):
    """Short hammer: displacement = J Σ φ_in φ_out e^{-ζωt} sin(ω_d t) / ω_d (J: impulse)."""
    fs = 200.0
    meas = simulate_test(
        beam,
        impulse_hammer(3, "z", 2.0, width=1e-4),
        [Channel.at("displacement", 1, "z")],
        2.0,
        fs,
        oversample=50,
    )
    t = meas.abscissa
    J = 2 * 2.0 * 1e-4 / np.pi
    w, z = beam.frequencies, beam.damping
    wd = w * np.sqrt(1 - z**2)
    phi_in, phi_out = beam.shapes[:, 2, 2], beam.shapes[:, 0, 2]
    ref = sum(
        phi_in[i] * phi_out[i] * J * np.exp(-z[i] * w[i] * t) * np.sin(wd[i] * t) / wd[i]
        for i in range(2)
    )
    assert np.allclose(meas.outputs[0], ref, atol=1e-3 * np.abs(ref).max())
    assert meas.inputs.sum() / fs == pytest.approx(J, rel=1e-9)


def test_sensors_noise_quantization(beam):
    sensors = [
        Channel.at("displacement", 2, "z"),
        Channel.at("velocity", 2, "z"),
        Channel.at("acceleration", 2, "z"),
        Channel.at("rotation", 3, "x"),
        Channel.at("strain", 3, "x", node_a=1),
    ]
    clean = simulate_test(
        beam, harmonic_shaker(1, "z", 1.0, 1.5), sensors, 4.0, 100.0, oversample=10
    )
    y = clean.outputs
    # velocity ≈ d(displacement)/dt, acceleration ≈ d(velocity)/dt
    dt = clean.dt
    assert np.allclose(np.gradient(y[0], dt)[5:-5], y[1][5:-5], atol=0.02 * np.abs(y[1]).max())
    assert np.allclose(np.gradient(y[1], dt)[5:-5], y[2][5:-5], atol=0.03 * np.abs(y[2]).max())
    # rotation shapes are 0.2 × z shapes: rotation at 3 and strain (θ3 − θ1) follow
    u1 = simulate_test(
        beam,
        harmonic_shaker(1, "z", 1.0, 1.5),
        [Channel.at("displacement", 3, "z"), Channel.at("displacement", 1, "z")],
        4.0,
        100.0,
        oversample=10,
    ).outputs
    assert np.allclose(y[3], 0.2 * u1[0], atol=1e-15)
    assert np.allclose(y[4], 0.2 * (u1[0] - u1[1]), atol=1e-15)
    noisy = simulate_test(
        beam,
        harmonic_shaker(1, "z", 1.0, 1.5),
        sensors,
        4.0,
        100.0,
        noise=0.05,
        seed=1,
        oversample=10,
    )
    rel = np.std(noisy.outputs - y, axis=1) / np.sqrt(np.mean(y**2, axis=1))
    assert np.allclose(rel, 0.05, rtol=0.2)
    quant = simulate_test(
        beam, harmonic_shaker(1, "z", 1.0, 1.5), sensors[:1], 4.0, 100.0, quantization=1e-4
    )
    assert np.allclose(quant.outputs / 1e-4, np.round(quant.outputs / 1e-4))


def test_excitation_errors(beam):
    s = [Channel.at("displacement", 1, "z")]
    with pytest.raises(ValueError, match="^sample_rate:"):
        simulate_test(beam, random_force(1, "z"), s, 1.0, -5.0)
    with pytest.raises(ValueError, match="^excitation:"):
        simulate_test(beam, [], s, 1.0, 10.0)
    with pytest.raises(ValueError, match="^sensors:"):
        simulate_test(beam, random_force(1, "z"), [], 1.0, 10.0)
    with pytest.raises(ValueError, match="^node:"):
        simulate_test(beam, random_force(9, "z"), s, 1.0, 10.0)
    with pytest.raises(ValueError, match="^values:"):
        torque_history(1, "x", [0.0, np.nan])


def test_uff_round_trip_time(beam, tmp_path):
    sensors = [Channel.at("acceleration", 2, "z"), Channel.at("strain", 3, "x", node_a=1)]
    meas = simulate_test(
        beam,
        [random_force(1, "z"), torque_history(2, "x", [1.0, -1.0])],
        sensors,
        1.0,
        64.0,
        seed=4,
    )
    path = tmp_path / "test.uff"
    meas.to_uff(path)
    back = Measurement.from_uff(path)
    assert back.output_channels == meas.output_channels
    assert back.input_channels == meas.input_channels
    assert np.allclose(back.abscissa, meas.abscissa)
    assert np.allclose(back.outputs, meas.outputs, rtol=1e-6, atol=1e-12)
    assert np.allclose(back.inputs, meas.inputs, rtol=1e-6, atol=1e-12)
    ds = meas.to_dataset()
    assert ds["outputs"].shape == (2, 64) and list(ds["output_kind"].values) == [
        "acceleration",
        "strain",
    ]


def test_uff_round_trip_frf(tmp_path):
    f = np.linspace(0.5, 10, 20)
    outs = (np.arange(2 * 1 * 20).reshape(2, 1, 20) + 1j).astype(complex)
    meas = Measurement(
        f,
        outs,
        (Channel.at("acceleration", 1, "z"), Channel.at("displacement", 4, "y")),
        None,
        (Channel.at("force", 9, "z"),),
        "frequency",
    )
    path = tmp_path / "frf.uff"
    meas.to_uff(path)
    back = Measurement.from_uff(path)
    assert back.domain == "frequency"
    assert back.output_channels == meas.output_channels
    assert back.input_channels == meas.input_channels
    assert np.allclose(back.outputs, outs)


def test_one_channel_class_with_one_unit_attribute():
    """A test's channel is the plant's Channel, located on the structure (issue 20): one class,
    one spelling of its unit."""
    from flexsat.dynamics.plant import Channel as PlantChannel

    c = Channel.at("strain", 3, "x", node_a=1)
    assert Channel is PlantChannel and isinstance(c, PlantChannel)
    assert (c.kind, c.node, c.node_a, c.direction, c.unit, c.size) == (
        "strain",
        3,
        1,
        "x",
        "rad",
        1,
    )
    assert not hasattr(c, "units")
    with pytest.raises(ValueError, match=r"^output_channels\[0\]: must be a Channel located"):
        Measurement([0.0, 1.0], np.zeros((1, 2)), (PlantChannel("theta", "rad"),))
    # a plant's own channel keeps the identifier rule; a located one may be named freely
    with pytest.raises(ValueError, match=r"^channel name: must be an identifier"):
        PlantChannel("hub angle", "rad")
