"""The plant protocol's shared pieces: channels, their layout, linear outputs."""

import numpy as np
import pytest

from flexsat.dynamics.plant import Channel, Plant, channel_slices, find_channel


class _Oscillator(Plant):
    """x'' = −x + u, output position and the 2-wide [x, x']."""

    inputs = (Channel("force", "N"),)
    outputs = (Channel("position", "m"), Channel("phase", "", size=2))
    nx = 2

    def linear_part(self):
        return np.array([[0.0, 1.0], [-1.0, 0.0]]), np.array([[0.0], [1.0]])

    def output_matrices(self, name):
        C = {"position": np.array([[1.0, 0.0]]), "phase": np.eye(2)}[name]
        return C, np.zeros((C.shape[0], 1)), None


def test_channels_are_laid_out_in_order():
    chans = (Channel("torque", "N*m", 3), Channel("force", "N"), Channel("q", "", 4))
    assert channel_slices(chans) == {"torque": slice(0, 3), "force": slice(3, 4), "q": slice(4, 8)}


@pytest.mark.parametrize("name, size", [("not an id", 1), ("ok", 0), ("ok", 1.5)])
def test_bad_channel_is_refused(name, size):
    with pytest.raises(ValueError):
        Channel(name, "m", size)


def test_unknown_channel_names_the_channel_and_the_known_ones():
    with pytest.raises(ValueError, match=r"gyro: .*no output channel 'gyro'.*position, phase"):
        find_channel(_Oscillator.outputs, "gyro", "output", "_Oscillator")


def test_linear_outputs_keep_leading_axes():
    plant = _Oscillator()
    x = np.arange(24.0).reshape(3, 4, 2)  # time × case × state
    u = np.zeros((3, 4, 1))
    assert plant.output("position", x, u).shape == (3, 4)
    np.testing.assert_array_equal(plant.output("phase", x, u), x)
    assert plant.n_inputs == 1 and plant.initial_state(5).shape == (5, 2)
    assert plant.energy(x) is None and plant.force_matrix is None


def test_unknown_output_is_a_value_error_naming_it():
    """Plant.output on a name the plant does not declare: a ValueError naming it, not the
    NotImplementedError of a plant whose output_matrices returns None for what it does not know
    (StateSpacePlant, SpaceStation did; found by the conformance suite's bad_input)."""
    from flexsat.dynamics.state_space import StateSpacePlant

    plant = StateSpacePlant([[-1.0]], [[1.0]], [[2.0]], [[0.0]])
    x, u = np.ones((2, 1)), np.zeros((2, 1))
    np.testing.assert_array_equal(plant.output("y", x, u), [2.0, 2.0])
    with pytest.raises(ValueError, match=r"^gyro: StateSpacePlant has no output channel 'gyro'"):
        plant.output("gyro", x, u)
