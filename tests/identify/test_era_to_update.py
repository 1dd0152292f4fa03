"""ERA's frequencies into a model update: the unit travels with the numbers (issue 20).

ERA gives cyclic frequencies (Hz); the Creamer-Junkins update (Att. 7 Eq. 9b) and the
differential correction (Att. 6) take angular ones (rad/s). Fed the Hz values as plain numbers,
the update scales every stiffness by 1/(2π)² and reports it without complaint (0.85 came out as
0.0215). Here the chain runs on a 3-dof spring-mass chain whose second stiffness group is 15 %
soft (p = [1, 0.85]): the free response of the truth is sampled exactly (Markov parameters of
the discrete system ``x_{k+1} = e^{A Δt} x_k``), ERA recovers its natural frequencies to
round-off (mass-proportional damping: |s| = ω_n), and

* ``frequencies_hz`` where rad/s is due is refused, naming the field;
* ``omega_rad_s`` recovers p = [1, 0.85] to the conditioning of the fit (1e-8 asked, the
  frequencies being exact to ~1e-12 relative).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.linalg import expm

from flexsat.identify.differential_correction import CorrectionData
from flexsat.identify.era import era
from flexsat.identify.markov import markov_from_frf
from flexsat.identify.structural import SubstructureModel, update_model
from flexsat.units import FrequencyArray, UnitError

P_TRUE = np.array([1.0, 0.85])
DT = 0.01  # s; the highest mode (about 3.4 Hz) is far below the 50 Hz Nyquist frequency


def _chain() -> SubstructureModel:
    """Masses 1, 2, 1.5 kg; group 1: the 400 N/m spring to ground; group 2: the two 300 N/m
    links between the masses."""
    K1 = np.zeros((3, 3))
    K1[0, 0] = 400.0
    K2 = np.zeros((3, 3))
    for i in (0, 1):
        K2[i : i + 2, i : i + 2] += 300.0 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return SubstructureModel([K1, K2], [np.diag([1.0, 2.0, 1.5])], names=("ground", "links"))


def _era_of_truth(model: SubstructureModel):
    K, M = model.K(P_TRUE), model.M()
    n = K.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -0.02 * np.eye(n)]])
    Ad = expm(A * DT)
    B = np.zeros((2 * n, 1))
    B[n:, 0] = [1.0, 0.0, 0.0]  # an impulse on the first mass
    C = np.hstack([np.eye(n), np.zeros((n, n))])
    Y, x = [np.zeros((n, 1))], B
    for _ in range(120):
        Y.append(C @ x)
        x = Ad @ x
    return era(np.array(Y), DT, order=2 * n)


def test_era_frequencies_in_hz_are_refused_where_rad_s_is_due():
    model = _chain()
    real = _era_of_truth(model)
    assert isinstance(real.frequencies_hz, FrequencyArray) and real.frequencies_hz.unit == "Hz"
    with pytest.raises(
        UnitError, match=r"^measured_frequencies: frequencies in Hz given where rad/s is expected"
    ):
        update_model(model, real.frequencies_hz)
    with pytest.raises(UnitError, match=r"^frequencies: frequencies in Hz given where rad/s"):
        CorrectionData(frequencies=real.frequencies_hz, frequency_sigma=1e-3)
    with pytest.raises(UnitError, match=r"^frequency_sigma: frequencies in Hz given"):
        update_model(model, real.omega_rad_s, frequency_sigma=real.frequencies_hz)
    # and the other way round: rad/s where a grid in Hz is due
    with pytest.raises(UnitError, match=r"^frequencies: frequencies in rad/s given where Hz"):
        markov_from_frf(FrequencyArray([0.0, 1.0, 2.0], "rad/s"), np.ones((1, 1, 3)))
    # a realization keeps its frequencies in Hz: rad/s values are refused, not relabelled
    with pytest.raises(UnitError, match=r"^frequencies_hz: frequencies in rad/s given where Hz"):
        dataclasses.replace(real, frequencies_hz=real.omega_rad_s)
    # a field that declares no unit refuses a tagged array too (its unit would be dropped)
    with pytest.raises(UnitError, match=r"^p0: frequencies in Hz given where a plain number"):
        update_model(model, real.omega_rad_s, p0=real.frequencies_hz[:2])


def test_era_angular_frequencies_recover_the_soft_substructure():
    model = _chain()
    real = _era_of_truth(model)
    w_true, _ = model.modes(P_TRUE)
    assert np.allclose(real.omega_rad_s, w_true, rtol=1e-10, atol=0)
    assert np.allclose(real.frequencies_hz * 2 * np.pi, w_true, rtol=1e-10, atol=0)
    result = update_model(model, real.omega_rad_s)
    assert result.undamped.converged
    assert np.allclose(result.p, P_TRUE, rtol=1e-8, atol=0)
    # the trap this closes: the same Hz numbers stripped of their unit scale K by 1/(2π)²
    stripped = update_model(model, np.array(real.frequencies_hz.view(np.ndarray)))
    assert np.allclose(stripped.p, P_TRUE / (2 * np.pi) ** 2, rtol=1e-8, atol=0)
    assert stripped.p[1] == pytest.approx(0.0215, abs=5e-5)


def test_tagged_frequencies_keep_their_unit_through_indexing_only():
    f = FrequencyArray([1.0, 2.0, 3.0], "Hz")
    assert f[1:].unit == "Hz" and f[[0, 2]].unit == "Hz"
    assert type(2 * np.pi * f) is np.ndarray  # arithmetic: a plain number the caller vouches for
    assert np.allclose(f.to("rad/s"), 2 * np.pi * np.array([1.0, 2.0, 3.0]), rtol=1e-15)
    assert f.to("rad/s").to("Hz").unit == "Hz"
    with pytest.raises(ValueError, match=r"^unit: must be one of \['Hz', 'rad/s'\]"):
        FrequencyArray([1.0], "rpm")
