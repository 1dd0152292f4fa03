"""The frontal-assault FRF + frequency identification (flexsat.identify.frontal_assault)."""

import numpy as np
import pytest
from scipy.stats import chi2

from flexsat.identify.frontal_assault import (
    FRFData,
    FrontalAssaultModel,
    basin,
    frontal_assault,
    trapezoid_weights,
)
from flexsat.input_checks import FieldError


def _chain(n=6):
    """A fixed-free spring-mass chain: springs grouped into two substructures (odd, even)."""
    m = np.diag(np.linspace(1.0, 2.0, n))
    parts = [np.zeros((n, n)), np.zeros((n, n))]
    for i in range(n):
        k = 1000.0 * (1 + 0.1 * i)
        e = np.zeros(n)
        e[i] = 1.0
        if i > 0:
            e[i - 1] = -1.0
        parts[i % 2] += k * np.outer(e, e)
    b = np.zeros((n, 2))
    b[-1, 0], b[2, 1] = 1.0, 1.0
    h = np.zeros((3, n))
    h[0, -1], h[1, 1], h[2, 3] = 1.0, 1.0, 1.0
    h[2, 2] = -1.0  # a relative displacement, like a strain gauge
    return FrontalAssaultModel(m, np.zeros((n, n)), tuple(parts), b, h, 0.05, 2e-4)


def _data(model, p, noise=0.0, fnoise=0.0, rng=None, n_freq=3):
    w = np.linspace(2.0, 80.0, 60)
    g = model.frf(p, w)
    rms = np.sqrt(np.mean(np.abs(g) ** 2, axis=(0, 2)))[:, None]
    sig = np.broadcast_to((noise or 1e-3) * rms / np.sqrt(2), g.shape)
    om = model.modes(p, n_freq)[0]
    osig = (fnoise or 1e-4) * om
    if noise:
        g = g + sig * (rng.standard_normal(g.shape) + 1j * rng.standard_normal(g.shape))
        om = om + osig * rng.standard_normal(om.shape)
    return FRFData(w, g, sig, om, osig)


@pytest.mark.numerics
def test_frf_is_the_direct_solution_of_the_damped_equations():
    model = _chain()
    p = np.array([0.9, 1.1])
    w = 17.0
    k = model.stiffness(p)
    z = k + 1j * w * (model.alpha * model.M + model.beta * k) - w**2 * model.M
    # one 6 x 6 solve: round-off ~ cond(Z) ε
    np.testing.assert_allclose(
        model.frf(p, [w])[0], model.H @ np.linalg.solve(z, model.B), rtol=1e-12, atol=1e-16
    )


@pytest.mark.numerics
def test_sensitivities_match_central_differences():
    model = _chain()
    p = np.array([0.9, 1.1])
    w = np.linspace(2.0, 80.0, 9)
    _, dg = model.frf_and_sensitivity(p, w)
    om, dom = model.frequencies_and_sensitivity(p, 4)
    for k in range(2):
        h = 1e-6
        e = np.eye(2)[k] * h
        fd_g = (model.frf(p + e, w) - model.frf(p - e, w)) / (2 * h)
        fd_o = (model.modes(p + e, 4)[0] - model.modes(p - e, 4)[0]) / (2 * h)
        # central differences: h² × third derivative + ε/h; 1e-7 relative to the largest entry
        np.testing.assert_allclose(dg[..., k], fd_g, atol=1e-7 * np.abs(fd_g).max())
        np.testing.assert_allclose(dom[:, k], fd_o, rtol=1e-7)


def test_trapezoid_weights_integrate_exactly_on_linear_functions():
    w = np.array([0.0, 1.0, 2.5, 3.0])
    q = trapezoid_weights(w) * np.diff(w).mean()
    assert q @ (2 * w + 1) == pytest.approx(3.0**2 + 3.0, rel=1e-14)


@pytest.mark.numerics
def test_noise_free_data_recover_the_parameters():
    model = _chain()
    truth = np.array([1.05, 0.96])
    res = frontal_assault(model, _data(model, truth), [1.0, 1.0])
    assert res.converged
    # acceptance 1e-6; Gauss-Newton with zero residual converges quadratically to round-off
    np.testing.assert_allclose(res.p, truth, rtol=1e-6)
    assert res.cost[-1] < 1e-12 * res.cost[0]


def test_a_far_start_needs_the_frequencies_first():
    """20 % off: the FRF term alone holds the paper's plain iteration in a wrong valley (its
    "potential trouble"); fitted to the frequencies first (FRF weight 1e-6), it then converges."""
    model = _chain()
    truth = np.array([1.2, 0.85])
    data = _data(model, truth)
    plain = frontal_assault(model, data, [1.0, 1.0])
    assert not np.allclose(plain.p, truth, rtol=1e-3)
    start = frontal_assault(model, data, [1.0, 1.0], frf_weight=1e-6).p
    np.testing.assert_allclose(frontal_assault(model, data, start).p, truth, rtol=1e-6)


def test_noisy_estimates_are_consistent_with_the_predicted_covariance():
    model = _chain()
    truth = np.array([1.05, 0.96])
    rng = np.random.default_rng(4)
    draws = 60
    nees = 0.0
    for _ in range(draws):
        res = frontal_assault(model, _data(model, truth, 0.02, 1e-3, rng), [1.0, 1.0])
        e = res.p - truth
        nees += e @ np.linalg.solve(res.covariance, e)
    # Σ eᵀ P⁻¹ e over the draws ~ χ²(2 × draws) at first order; two-sided 0.1 %
    assert chi2.ppf(5e-4, 2 * draws) < nees < chi2.ppf(1 - 5e-4, 2 * draws)


def test_halving_never_raises_the_cost_and_the_basin_map_marks_the_truth():
    model = _chain()
    truth = np.array([1.0, 1.0])
    data = _data(model, truth)
    res = frontal_assault(model, data, [1.5, 0.6], step_control="halving")
    assert all(b <= a for a, b in zip(res.cost, res.cost[1:]))
    b = basin(model, data, truth, [np.array([1.0, 0.0])], [0.01])
    assert b.tolist() == [[1.0]]


def test_bad_inputs_name_the_field():
    model = _chain()
    data = _data(model, np.ones(2))
    with pytest.raises(FieldError, match="step_control"):
        frontal_assault(model, data, [1.0, 1.0], step_control="line")
    with pytest.raises(FieldError, match="^p"):
        frontal_assault(model, data, [1.0])
    with pytest.raises(FieldError, match="frf_weight"):
        frontal_assault(model, data, [1.0, 1.0], frf_weight=0.0)
    with pytest.raises(FieldError, match="omega"):
        FRFData([1.0, 0.5], np.zeros((2, 3, 2)), 1.0)
    with pytest.raises(FieldError, match="K_parts"):
        FrontalAssaultModel(np.eye(2), np.eye(2), (), np.ones(2), np.ones(2))
    with pytest.raises(FieldError, match="B"):
        FrontalAssaultModel(np.eye(2), np.eye(2), (np.eye(2),), np.ones(3), np.ones(2))
    # one parameter cannot be told from a part that is all zero: rank-deficient Jacobian
    zero = FrontalAssaultModel(
        model.M, model.K0, (*model.K_parts, np.zeros_like(model.M)), model.B, model.H
    )
    with pytest.raises(FieldError, match="rank"):
        frontal_assault(zero, data, [1.0, 1.0, 1.0])


def test_data_frequencies_take_units():
    model = _chain()
    d = _data(model, np.ones(2))
    hz = FRFData([f"{w / (2 * np.pi)} Hz" for w in d.omega], d.frf, d.frf_sigma)
    np.testing.assert_allclose(hz.omega, d.omega, rtol=1e-14)
