import numpy as np

from flexsat.control import LyapunovRegulator, LyapunovTracker
from flexsat.maneuvers import SmoothBangBang


def test_tabulated_reference_equals_direct_evaluation():
    ref = SmoothBangBang(0.7, 15.0, u_max=np.array([2.0, 2.8]), alpha=0.2)
    law = LyapunovTracker(ref, 10.0, 5.0)
    direct = [law.reference_at(t) for t in (0.0, 1.0, 2.5)]
    law.tabulate_reference(np.array([0.0, 1.0, 2.5]))
    for t, want in zip((0.0, 1.0, 2.5), direct):
        for got, exp in zip(law.reference_at(t), want):
            assert np.array_equal(got, exp)
    # off the grid it falls back to evaluating the shape
    assert np.array_equal(law.reference_at(1.7)[0], ref(1.7).theta)


def test_law_without_reference_commands_a_step():
    law = LyapunovRegulator(1.0, 1.0, target=np.array([0.1, 0.2, 0.3]))
    th, thd, thdd, u = law.reference_at(5.0)
    assert np.array_equal(th, [0.1, 0.2, 0.3]) and not thd.any() and not u.any()
    assert law.n_cases == 3


def test_a_law_must_declare_its_channels():
    """The base class has no default channels (a single-axis law's ``theta``/``torque`` used to
    be assumed): a law that declares no ``reads`` or no ``writes`` is refused before the run,
    by a ValueError naming the field and the law."""
    import pytest

    from flexsat.cases.tamu import tamu
    from flexsat.control.base import Controller
    from flexsat.sim import SimConfig, simulate

    class Forgetful(Controller):
        target = 0.0

        def __call__(self, t, y, state):
            return np.zeros(np.shape(y["theta"])), state

    class ReadsOnly(Forgetful):
        reads = ("theta",)

    assert not hasattr(Controller, "reads") and not hasattr(Controller, "writes")
    # nor a hub angle: target and reference belong to the slew laws (SlewLaw)
    assert not hasattr(Controller, "reference_at") and "target" not in Controller.__annotations__
    plant = tamu(n_modes=2).model()
    with pytest.raises(ValueError, match=r"^reads: Forgetful declares no measurement channels"):
        simulate(plant, Forgetful(), SimConfig(duration=0.1))
    with pytest.raises(ValueError, match=r"^writes: ReadsOnly declares no input channels"):
        simulate(plant, ReadsOnly(), SimConfig(duration=0.1))
