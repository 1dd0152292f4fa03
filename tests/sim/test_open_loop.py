"""The exact open-loop response to a piecewise-polynomial torque (flexsat.sim.open_loop)."""

import numpy as np
import pytest
from scipy.linalg import expm

from flexsat.cases import tamu
from flexsat.maneuvers import PseudoSquare, SmoothBangBang
from flexsat.sim import SimConfig, simulate
from flexsat.sim.open_loop import open_loop_response, piecewise_polynomial_response, torque_pieces


@pytest.fixture(scope="module")
def case():
    return tamu()


@pytest.fixture(scope="module")
def model(case):
    return case.model()


def _augmented_expm(A, B, breaks, coeffs, t):
    """Independent exact reference: [x; p, p', p'', p'''] in σ is linear with the nilpotent
    shift on the polynomial, so one matrix exponential per piece propagates it."""
    n = A.shape[0]
    N = np.diag(np.ones(3), 1)
    x = np.zeros(n)
    for j in range(breaks.size - 1):
        h = breaks[j + 1] - breaks[j]
        a = coeffs[j]
        if h > 0:
            M = np.zeros((n + 4, n + 4))
            M[:n, :n], M[:n, n], M[n:, n:] = A * h, B * h, N
            z = np.concatenate([x, [a[0], a[1], 2 * a[2], 6 * a[3]]])
            x = (expm(M * min(max(t - breaks[j], 0.0), h) / h) @ z)[:n]
        if t < breaks[j + 1]:
            return x
    return expm(A * (t - breaks[-1])) @ x


def test_smoothed_bang_bang_pieces_are_eq_12(case):
    """Att. 3 Eq. 12: u = u_max f on [0, T] with the smoothstep rise, plateaus and reversal; the
    pieces evaluated at their σ give the shape's own torque to rounding."""
    shape = case.reference(alpha=np.array([0.0, 0.1, 0.25]))
    breaks, coeffs = torque_pieces(shape)
    T = shape.duration
    assert np.allclose(breaks[:, -1], T, rtol=0, atol=0)
    t = np.linspace(0, 1, 997)[:, None] * T * (1 - 1e-12)
    u = shape(t).u
    for c in range(3):
        j = np.clip(np.searchsorted(breaks[c], t[:, c], side="right") - 1, 0, 4)
        h = np.diff(breaks[c])[j]
        sigma = np.where(h > 0, (t[:, c] - breaks[c, j]) / np.where(h > 0, h, 1), 0)
        mine = sum(coeffs[c, j, k] * sigma**k for k in range(4))
        # a cubic of unit scale rounded twice: a few ulps of u_max
        assert np.allclose(mine, u[:, c], rtol=0, atol=1e-13 * shape.u_max[c])


def test_exact_response_equals_the_augmented_matrix_exponential(case, model):
    """Two exact methods (modal Duhamel integral vs augmented expm): equal to round-off times
    the largest phase ω_max t ≈ 3e4 rad of the 10-mode model (relative 1e-10)."""
    shape = case.reference(alpha=np.array([0.0, 0.05, 0.2, 0.25]))
    breaks, coeffs = torque_pieces(shape)
    A, B = model.linear_part()
    t = np.array([0.05, 0.9, 2.4, 3.3, 4.9, breaks[:, -1].max() + 0.7])
    X = open_loop_response(model, shape, t)
    for c in range(4):
        for k, tk in enumerate(t):
            ref = _augmented_expm(A, B[:, 0], breaks[c], coeffs[c], tk)
            assert np.abs(X[k, c] - ref).max() <= 1e-10 * np.abs(ref).max()


def test_held_torque_reproduces_simulate_exactly(case, model):
    """simulate propagates the zero-order-held command exactly (matrix exponential of the
    linear plant); the same held torque as degree-0 pieces gives the same states to round-off
    accumulated over the 600 steps (1e-9 of the state's scale)."""
    law = case.law_ii(0.0, 0.0, 0.0, alpha=0.15)  # all gains 0: the open-loop u_ref, held
    run = simulate(model, law, SimConfig(duration=8.0), record_states=True)
    t = run.dataset.time.values
    u = run.dataset.torque.values[0]
    X = run.dataset.state.values[0]
    breaks = t[None, :]  # piece k holds u_k over [t_k, t_k+1)
    coeffs = u[None, :-1, None]
    A, B = model.linear_part()
    mine = piecewise_polynomial_response(A, B, breaks, coeffs, t)[:, 0]
    assert np.abs(mine - X).max(axis=0).max() <= 1e-9 * np.abs(X).max()


def test_rest_to_rest_rigid_part_lands_on_the_model_angle(case, model):
    """With zero net impulse the momentum at T is zero, so E(T) is all vibration; the hub
    lands at angle · I_ref/I_model (the reference is designed with 2128 oz-in-s², the model
    has 2213.6) up to the elastic deflection of the hub."""
    shape = case.reference(alpha=0.25)
    x = open_loop_response(model, shape, np.array([shape.duration]))[0, 0]
    assert abs(model.momentum(x)) <= 1e-12 * shape.u_max * shape.duration
    assert model.energy(x) == pytest.approx(model.vibration_energy(x), rel=1e-9)
    ratio = case.reference_inertia / model.total_inertia
    assert x[0] == pytest.approx(case.angle * ratio, rel=1e-3)


def test_bad_input_names_the_field(case, model):
    with pytest.raises(ValueError, match="shape: .*piecewise-polynomial"):
        open_loop_response(model, PseudoSquare(1.0, 1.0, u_max=1.0, rise_time=0.2), [1.0])
    A, B = model.linear_part()
    with pytest.raises(ValueError, match="breaks: must be non-decreasing"):
        piecewise_polynomial_response(A, B, [[0.0, 2.0, 1.0]], np.zeros((1, 2, 1)), [0.5])
    with pytest.raises(ValueError, match="times: must not precede"):
        piecewise_polynomial_response(A, B, [[1.0, 2.0]], np.zeros((1, 1, 1)), [0.5])
    with pytest.raises(ValueError, match=r"times: need shape \(n_t,\) or \(n_t, 1\)"):
        piecewise_polynomial_response(A, B, [[0.0, 2.0]], np.zeros((1, 1, 1)), np.ones((2, 3)))
    with pytest.raises(ValueError, match="coeffs: need"):
        piecewise_polynomial_response(A, B, [[0.0, 2.0]], np.zeros((1, 2, 1)), [0.5])
    spring = np.array([[0.0, 1.0], [0.0, 0.0]])  # a double integrator is a rigid block: fine
    x = piecewise_polynomial_response(spring, [0.0, 1.0], [[0.0, 1.0]], [[[2.0]]], [1.0])
    assert x[0, 0] == pytest.approx([1.0, 2.0], rel=1e-14)  # x = t², x' = 2t at t = 1
    triple = np.diag([1.0, 1.0], 1)  # a triple integrator is not A_r² = 0
    with pytest.raises(ValueError, match="A: the zero eigenvalues"):
        piecewise_polynomial_response(triple, [0, 0, 1.0], [[0.0, 1.0]], [[[1.0]]], [1.0])
    assert isinstance(case.reference(), SmoothBangBang)
