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
