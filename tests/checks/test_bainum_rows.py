"""Bainum & Reddy rows of ``flexsat validate`` on the simulation core (flexsat.checks.bainum;
issue #10: "the Ch. II/III numbers come from the new core").

The response rows are sampled-data runs of :func:`flexsat.sim.simulate`; the report's loop is
continuous. Each run's sampled-data error is measured here against the case's continuous loop
(``BainumBeam.simulate``: DOP853 at rtol 1e-10, whose own error is ~1e-10 of these values) and
must stay inside the allowance the check module states for it.
"""

import numpy as np
import pytest

from flexsat.cases.bainum import bainum, closed_loop_matrix, published_matrix, sorted_poles
from flexsat.cases.bainum_control import chapter2_example, chapter3_case
from flexsat.checks import bainum as rows
from flexsat.checks import run_checks


@pytest.fixture(scope="module")
def results():
    return run_checks("bainum")


def test_every_bainum_row_passes_and_the_core_rows_are_there(results):
    assert [r.check.quantity for r in results if r.status != "pass"] == []
    core = [r for r in results if r.check.quantity.startswith(("Ch. II ", "Ch. III "))]
    assert len(core) == 33  # Ch. II: 9 roots/ζ + 5 responses; Case 1: 6 + 3; Case 2: 10
    responses = [r for r in core if "simulation core" in r.check.note]
    assert len(responses) == 8
    # the rows that add the sampled-data error to the half unit say so
    widened = [r.check.quantity for r in responses if "sampled-data error" in r.check.note]
    assert widened == ["Ch. II example, max |θ|", "Ch. II example, θ(τ = 10)"]


def test_roots_from_the_plants_linear_part_equal_the_cases_closed_loop():
    """The core's roots (eig of the plant's linear part in seconds under the SI gains, scaled
    to τ) equal the eigenvalues of the case's nondimensional closed-loop matrix (eq 16 with
    f = K x'): the two are the same loop, to round-off of eigenvalues spread over 1e2."""
    cl = chapter2_example()
    np.testing.assert_allclose(rows._ch2_roots(), sorted_poles(cl.matrix), rtol=1e-10)
    F, G = chapter3_case(1)
    expected = sorted_poles(closed_loop_matrix(F, G, None, published_matrix("ch3_case1_K")))
    np.testing.assert_allclose(
        np.sort_complex(rows._ch3_roots()), np.sort_complex(expected), rtol=1e-10
    )
    F, G = chapter3_case(2)
    expected = sorted_poles(closed_loop_matrix(F, G, None, published_matrix("ch3_case2_K")))
    np.testing.assert_allclose(
        np.sort_complex(rows._ch3_case2_roots()), np.sort_complex(expected), rtol=1e-9
    )


def _continuous(G, K, tau_end, n_points, nonlinear):
    return bainum().simulate(
        G, None, K, [0.01] * 3, tau_end, nonlinear=nonlinear, n_points=n_points
    )


def test_chapter2_sampled_data_error_is_inside_each_rows_allowance():
    """Allowances of flexsat.checks.bainum: max |f| at 40 Hz within 1e-6 (of the 5e-6 half
    unit), its τ within 1e-6; max |θ| at 4 Hz within 4e-6 and θ(τ = 10) at 0.5 Hz within
    2.5e-5 (both added to the half unit in the rows)."""
    cl = chapter2_example()
    ref = _continuous(cl.G, cl.K_rate, rows.CH2_FORCE_RUN[0], 15001, False)
    peak, tau = rows.refined_peak(ref.tau, ref.forces[:, 0])
    core_peak, core_tau = rows._ch2_force_peak()
    assert abs(core_peak - peak) <= 1e-6 and abs(core_tau - tau) <= 1e-6
    ref = _continuous(cl.G, cl.K_rate, rows.CH2_PITCH_RUN[0], 7001, False)
    peak, tau = rows.refined_peak(ref.tau, ref.states[:, 0])
    core_peak, core_tau = rows._ch2_pitch_peak()
    assert abs(core_peak - peak) <= 4e-6 and abs(core_tau - tau) <= 1e-4
    ref = _continuous(cl.G, cl.K_rate, rows.CH2_LONG_RUN[0], 3, False)
    tau, pitch, _ = rows._ch2_run(rows.CH2_LONG_RUN)
    assert tau[-1] == pytest.approx(10.0, rel=1e-12)  # the last sample is at τ = 10
    assert abs(pitch[-1] - ref.states[-1, 0]) <= 2.5e-5


def test_chapter3_case1_sampled_data_error_is_inside_the_half_unit():
    """Peak forces at 200 Hz on the nonlinear plant with the printed G: within 1.8e-3 of the
    continuous nonlinear loop, inside the 5e-3 half unit of the printed 3.69, 1.83, 10.98."""
    _, G = chapter3_case(1)
    ref = _continuous(G, published_matrix("ch3_case1_K"), rows.CH3_FORCE_RUN[0], 7501, True)
    peaks = [rows.refined_peak(ref.tau, ref.forces[:, j])[0] for j in range(3)]
    assert np.all(np.abs(np.array(rows._ch3_peaks()) - peaks) <= 1.8e-3)


def test_refined_peak_is_the_vertex_and_refuses_a_peak_at_the_end():
    tau = np.linspace(0.0, 1.0, 11)
    value, where = rows.refined_peak(tau, -(1.0 - (tau - 0.43) ** 2))  # |y| peaks at 0.43
    assert value == pytest.approx(1.0, abs=1e-14) and where == pytest.approx(0.43, abs=1e-14)
    with pytest.raises(ValueError, match="^y: the peak is at an end of the run"):
        rows.refined_peak(tau, tau)
