"""H∞ synthesis: γ_opt of a scalar problem against its closed form, the achieved closed-loop
H∞ norm inside the bisection's bracket on random plants with cross terms and on the TAMU hub,
the central compensator's norm below γ, the same γ as python-control's hinfsyn where slycot is
installed, infeasible γ refused naming the condition, and the law on the engine and the
conformance suite.

Tolerances: the bracket [γ_lower, γ] is the bisection's (rtol); the achieved norm is computed
by hinf_norm to a relative 1e-8 bracket, so "inside" allows 1e-7 on top (the central compensator
at γ ≈ γ_opt reaches ‖T‖∞ ≈ γ, from below in exact arithmetic)."""

import numpy as np
import pytest

import control as ct
from flexsat.analysis.norms import hinf_norm
from flexsat.control.generalized_plant import GeneralizedPlant, closed_loop
from flexsat.control.hinf_synthesis import (
    HinfController,
    InfeasibleGamma,
    hinf_central,
    hinfsyn,
)
from flexsat.input_checks import FieldError
from flexsat.testing import check_controller
from flexsat.testing.checks import CHECK_RATE
from synthesis_plants import random_plant, tamu_design, tamu_generalized

SLACK = 1e-7  # hinf_norm's bracket and the round-off of the closed loop (module docstring)


def scalar_plant(a):
    return ct.ss(a, [[1.0, 0.0, 1.0]], [[1.0], [0.0], [1.0]], [[0, 0, 0], [0, 0, 1], [0, 1, 0]])


@pytest.mark.numerics
@pytest.mark.parametrize("a", [-1.0, 0.5, 2.0])
def test_scalar_gamma_opt_is_the_closed_form(a):
    """ẋ = a x + w1 + u, z = [x; u], y = x + w2: X∞ = Y∞ solve (γ⁻² − 1)X² + 2aX + 1 = 0 and
    the coupling ρ(X∞Y∞) = X∞² < γ² binds first; X∞(γ) = γ gives γ² − 2aγ − 2 = 0, so
    γ_opt = a + √(a² + 2) (√3 − 1 for a = −1, python-control's hinfsyn example)."""
    s = hinfsyn(scalar_plant(a), 1, 1, rtol=1e-8)
    opt = a + np.sqrt(a * a + 2)
    assert s.gamma_lower <= opt * (1 + 1e-9) and s.gamma >= opt * (1 - 1e-9)
    assert s.gamma - s.gamma_lower <= 1e-8 * s.gamma
    assert s.gamma_lower * (1 - SLACK) <= s.achieved <= s.gamma * (1 + SLACK)


@pytest.mark.numerics
@pytest.mark.parametrize("seed", range(4))
def test_achieved_norm_is_inside_the_bracket_on_random_plants(seed):
    G = random_plant(seed)
    s = hinfsyn(G, rtol=1e-5)
    T = closed_loop(G, s.controller)
    assert np.all(np.linalg.eigvals(T.A).real < 0)
    assert s.gamma - s.gamma_lower <= 1e-5 * s.gamma
    assert s.gamma_lower * (1 - SLACK) <= hinf_norm(T).value <= s.gamma * (1 + SLACK)
    with pytest.raises(InfeasibleGamma, match="^gamma: "):
        hinf_central(G, 0.999 * s.gamma_lower)
    # at a larger γ the central compensator is feasible, stabilizing and strictly below γ
    for g in (1.5 * s.gamma, 4 * s.gamma):
        Tg = closed_loop(G, hinf_central(G, g).controller)
        assert hinf_norm(Tg).value < g


@pytest.mark.numerics
def test_tamu_hub_norm_matches_gamma_and_beats_h2():
    """On the TAMU LQG weights the H∞ design reaches its γ, and no compensator (the H2 one
    included) does better than γ_lower."""
    from flexsat.control.h2_synthesis import h2syn

    G = tamu_generalized(3)
    s = hinfsyn(G, rtol=1e-4)
    assert s.gamma_lower * (1 - SLACK) <= s.achieved <= s.gamma * (1 + SLACK)
    h2 = hinf_norm(closed_loop(G, h2syn(G).controller)).value
    assert h2 > s.gamma_lower


def test_law_conforms_and_regulates_on_the_engine():
    from flexsat.sim import simulate

    case, plant, *_ = tamu_design(3)
    synthesis = hinfsyn(tamu_generalized(3), rtol=1e-3)
    check_controller(HinfController(synthesis, 1 / CHECK_RATE), plant)
    cfg = case.sim_config(duration=12.0, friction=False, noise=False)
    law = HinfController(synthesis, cfg.dt, references={"theta": 0.3})
    theta = simulate(plant, law, cfg, initial_state=plant.state_from(theta=0.0))
    assert abs(theta.dataset.theta.values[0, -1] - 0.3) < np.radians(0.05)


def test_bad_input_names_the_field():
    G = GeneralizedPlant.from_statespace(scalar_plant(1.0), 1, 1)
    with pytest.raises(FieldError, match="^gamma: must be a positive finite number"):
        hinf_central(G, -1.0)
    with pytest.raises(InfeasibleGamma, match="^gamma: coupling"):
        hinf_central(G, 2.0)  # below γ_opt = 1 + √3, above where X∞ and Y∞ exist
    with pytest.raises(FieldError, match="^rtol: must be a number in"):
        hinfsyn(G, rtol=0.0)
    with pytest.raises(FieldError, match="^gamma_max: must be a positive number"):
        hinfsyn(G, gamma_max=float("nan"))
    with pytest.raises(FieldError, match="^synthesis: must be an HinfSynthesis"):
        HinfController(object(), 0.1)


def test_same_gamma_as_python_control_hinfsyn_when_slycot_is_installed():
    pytest.importorskip("slycot")
    for seed in range(3):
        G = random_plant(seed)
        _, _, gamma, _ = ct.hinfsyn(G.statespace(), 2, 2)
        ours = hinfsyn(G, rtol=1e-6)
        # slycot's own γ iteration stops within its tolerance (~1e-5 relative) above γ_opt
        assert ours.gamma_lower * (1 - 1e-9) <= gamma <= ours.gamma * (1 + 1e-4)
