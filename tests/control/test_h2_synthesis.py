"""H2 synthesis: the optimal cost against a closed form (scalar plant), the achieved closed-loop
H2 norm equals the predicted cost, the compensator equals LQG for the LQG weights, the same as
python-control's h2syn where slycot is installed, and the law runs on the engine and passes the
conformance suite.

Tolerances: the predicted cost and the achieved norm are two Lyapunov/Riccati evaluations of one
number, each backward stable, so they agree to the Riccati residual times the conditioning:
1e-9 relative on the small random plants, 1e-6 on the TAMU model whose modes span 21–3,000
rad/s (‖A‖ ~ 1e7, the Lyapunov equations lose ~ε‖A‖‖X‖/‖B1ᵀXB1‖)."""

import numpy as np
import pytest

import control as ct
from flexsat.analysis.norms import h2_norm
from flexsat.control.estimation import kalman
from flexsat.control.generalized_plant import closed_loop
from flexsat.control.h2_synthesis import H2Controller, h2syn
from flexsat.control.lqr import lqr
from flexsat.input_checks import FieldError
from flexsat.sim import simulate
from flexsat.testing import check_controller
from flexsat.testing.checks import CHECK_RATE
from synthesis_plants import TAMU_RN, random_plant, tamu_design, tamu_generalized


def scalar_plant(a):
    """ẋ = a x + w1 + u, z = [x; u], y = x + w2 (Doyle et al. 1989's normalized problem)."""
    return ct.ss(a, [[1.0, 0.0, 1.0]], [[1.0], [0.0], [1.0]], [[0, 0, 0], [0, 0, 1], [0, 1, 0]])


@pytest.mark.numerics
@pytest.mark.parametrize("a", [-1.0, 0.0, 2.0])
def test_scalar_cost_is_the_closed_form(a):
    """Both Riccati equations read 2aX − X² + 1 = 0, X = Y = a + √(a² + 1), F = L = −X, and the
    cost is tr(B1ᵀXB1) + tr(F Y Fᵀ) = X + X³."""
    s = h2syn(scalar_plant(a), 1, 1)
    X = a + np.sqrt(a * a + 1)
    assert s.cost == pytest.approx(np.sqrt(X + X**3), rel=1e-13)
    assert h2_norm(closed_loop(s.plant, s.controller)) == pytest.approx(s.cost, rel=1e-12)
    np.testing.assert_allclose(s.F, [[-X]], rtol=1e-13)


@pytest.mark.numerics
@pytest.mark.parametrize("seed", range(5))
def test_achieved_norm_equals_cost_on_random_plants_with_cross_terms(seed):
    G = random_plant(seed)
    s = h2syn(G)
    T = closed_loop(G, s.controller)
    assert np.all(np.linalg.eigvals(T.A).real < 0)
    assert h2_norm(T) == pytest.approx(s.cost, rel=1e-9)
    # optimality: perturbing the compensator's gains raises the cost
    for scale in (0.95, 1.05):
        K = ct.ss(s.controller.A, s.controller.B, scale * s.controller.C, s.controller.D)
        Tp = closed_loop(G, K)
        if np.all(np.linalg.eigvals(Tp.A).real < 0):
            assert h2_norm(Tp) > s.cost


@pytest.mark.numerics
def test_h2_equals_lqg_for_the_lqg_weights():
    """With z = [Q^½x; R^½u], w = [Qn^½ w; Rn^½ v] the H2 compensator is the LQG one:
    F = −K_lqr, L = −L_kalman (same Riccati equations, solved by the same solver: to the
    solver's round-off)."""
    _, _, A, B, C, Q = tamu_design(3)
    G = tamu_generalized(3)
    s = h2syn(G)
    K = lqr(A, B, Q, np.eye(1)).gain
    L = kalman(A, B, C, np.eye(1), TAMU_RN * np.eye(1)).gain
    np.testing.assert_allclose(s.F, -K, rtol=1e-9)
    np.testing.assert_allclose(s.L, -L, rtol=1e-9)
    np.testing.assert_allclose(
        s.controller.A, A - B @ K - L @ C, rtol=1e-9, atol=1e-9 * np.abs(A).max()
    )
    T = closed_loop(G, s.controller)
    assert h2_norm(T) == pytest.approx(s.cost, rel=1e-6)


def test_law_conforms_and_slews_the_tamu_hub_on_the_engine():
    case, plant, *_ = tamu_design(3)
    cfg = case.sim_config(duration=12.0, friction=False, noise=False)
    synthesis = h2syn(tamu_generalized(3))
    check_controller(H2Controller(synthesis, 1 / CHECK_RATE), plant)
    law = H2Controller(synthesis, cfg.dt, references={"theta": 0.3})
    x0 = plant.state_from(theta=0.0)
    theta = simulate(plant, law, cfg, initial_state=x0).dataset.theta.values[0]
    assert abs(theta[-1] - 0.3) < np.radians(0.05)


def test_bad_input_names_the_field():
    with pytest.raises(FieldError, match="^nmeas: give nmeas and ncon"):
        h2syn(scalar_plant(1.0))
    with pytest.raises(FieldError, match="^synthesis: must be an H2Synthesis"):
        H2Controller("no", 0.1)
    P = ct.ss(-1.0, [[1.0, 1.0]], [[1.0], [1.0]], [[0.0, 0.0], [0.0, 0.0]])
    with pytest.raises(FieldError, match="^P.D12: must have full column rank"):
        h2syn(P, 1, 1)


def test_equals_python_control_h2syn_when_slycot_is_installed():
    pytest.importorskip("slycot")
    rng = np.random.default_rng(7)
    P = ct.ss(
        rng.normal(size=(4, 4)),
        rng.normal(size=(4, 4)),
        rng.normal(size=(4, 4)),
        np.block(
            [
                [np.zeros((2, 2)), rng.normal(size=(2, 2))],
                [rng.normal(size=(2, 2)), np.zeros((2, 2))],
            ]
        ),
    )
    ours = h2syn(P, 2, 2)
    theirs = ct.h2syn(P, 2, 2)
    for w in (0.1, 1.0, 10.0):
        np.testing.assert_allclose(ours.controller(1j * w), theirs(1j * w), rtol=1e-7)
