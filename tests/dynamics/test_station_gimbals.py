"""The space station with its CMG pyramid's gimbals as one plant (flexsat.dynamics.
station_gimbals): the station's equations untouched, the gimbal angles the integral of their
commanded rates (σ̇ = u), and the cluster's momentum and gain those of the pyramid at σ."""

import numpy as np
import pytest
from scipy.linalg import expm

from flexsat.cases.space_station_cmg import PAPER_STATION, design
from flexsat.dynamics import cmg
from flexsat.dynamics.station_gimbals import StationWithGimbals
from flexsat.input_checks import FieldError


@pytest.fixture(scope="module")
def station():
    return design(PAPER_STATION).plant


def test_the_station_block_is_the_station_and_the_gimbals_integrate_their_rates(station):
    plant = StationWithGimbals(station)
    A, B = plant.linear_part()
    As, Bs = station.linear_part()
    ns, m = station.nx, Bs.shape[1]
    assert A.shape == (ns + 4, ns + 4) and B.shape == (ns + 4, m + 4)
    np.testing.assert_array_equal(A[:ns, :ns], As)
    np.testing.assert_array_equal(B[:ns, :m], Bs)
    assert not A[ns:].any() and not A[:, ns:].any() and not B[:ns, m:].any()
    # a constant rate command for 30 s moves σ by 30 u exactly (the zero-order hold of σ̇ = u)
    u = np.array([0.01, -0.02, 0.0, 0.005])
    h = 30.0
    M = expm(h * np.block([[A, B], [np.zeros((m + 4, ns + 4 + m + 4))]]))
    step = M[: ns + 4, ns + 4 :] @ np.concatenate([np.zeros(m), u])
    np.testing.assert_allclose(step[ns:], h * u, rtol=1e-12)
    assert np.abs(step[:ns]).max() == 0.0  # the rates do not touch the station


def test_the_cluster_outputs_are_the_pyramid_at_the_gimbal_angles(station):
    plant = StationWithGimbals(station)
    sigma = np.deg2rad([45.0, -45.0, 45.0, -45.0])
    x = np.concatenate([np.zeros(station.nx), sigma])
    np.testing.assert_array_equal(plant.output("gimbal_angles", x), sigma)
    np.testing.assert_array_equal(plant.output("cluster_momentum", x), cmg.momentum(sigma))
    np.testing.assert_array_equal(plant.output("gain", x), cmg.gain(sigma))
    C, D, _ = plant.output_matrices("gimbal_angles")
    np.testing.assert_array_equal(C @ x, sigma)


def test_bad_input_is_refused_by_field(station):
    with pytest.raises(FieldError) as err:
        StationWithGimbals("a station")
    assert err.value.field == "station"
    with pytest.raises(ValueError, match="skew"):
        StationWithGimbals(station, skew="95 deg")
