"""The cantilever-tube reference problem's own claims (flexsat.design.reference_problems)."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.design.kkt import kkt_conditions
from flexsat.design.reference_problems import (
    CANTILEVER_BETA1_L,
    CantileverTube,
    cantilever_tube_optimum,
)
from flexsat.input_checks import FieldError

EPS = np.finfo(float).eps


def test_mass_and_frequency_are_the_tube_formulas_written_from_a_and_i():
    """m = ρ L A and ω₁ = (β₁L)²/L² √(E I / (ρ A)) with the tube's A = π(D² − d²)/4 and
    I = π(D⁴ − d⁴)/64, d = D − 2t (Roark, Table A.1), computed here without the module's
    I/A simplification: equal to a few ε."""
    tube = CantileverTube()
    for t, D in [(1e-3, 0.05), (4e-3, 0.12), (9e-3, 0.2)]:
        d = D - 2 * t
        A, inertia = np.pi * (D**2 - d**2) / 4, np.pi * (D**4 - d**4) / 64
        r = tube.responses(np.array([t, D]))
        assert r["mass"][0] == pytest.approx(tube.density * tube.length * A, rel=10 * EPS)
        omega = (CANTILEVER_BETA1_L / tube.length) ** 2 * np.sqrt(
            tube.youngs_modulus * inertia / (tube.density * A)
        )
        assert r["omega"][0] == pytest.approx(omega, rel=10 * EPS)


def test_mass_grows_with_both_dimensions_and_the_frequency_falls_with_the_wall():
    """The monotonicity the closed form rests on: ∂m/∂t, ∂m/∂D, ∂ω₁/∂D > 0 > ∂ω₁/∂t over the
    bounds (so the wall sits at t_min and the floor is met by D)."""
    tube = CantileverTube()
    for t in np.linspace(1e-3, 10e-3, 7):
        for D in np.linspace(25e-3, 0.2, 7):
            r = tube.responses(np.array([t, D]))
            (dm_t, dm_d), (dw_t, dw_d) = r["mass"][1], r["omega"][1]
            assert dm_t > 0 and dm_d > 0 and dw_d > 0 and dw_t < 0


def test_the_closed_form_optimum_satisfies_kkt_with_its_own_multipliers():
    """At (t_min, D*) the floor is met exactly and the least-squares multipliers equal the
    closed-form λ, μ: checked by the KKT report, with no optimiser in the loop. Tolerance:
    D* and ω₁(D*) agree to a few ε relative; the multipliers solve a 2 × 2 system (cond ~
    scale ratio) to ~1e-12."""
    tube = CantileverTube()
    exact = cantilever_tube_optimum(tube)
    x = np.array([exact["t"], exact["D"]])
    assert tube.responses(x)["omega"][0] == pytest.approx(tube.omega_min, rel=20 * EPS)
    rep = kkt_conditions(tube.problem(), x)
    assert rep.residual <= 1e-12
    assert set(rep.active) == {"frequency floor", "t >= lower"}
    for name in ("frequency floor", "t >= lower"):
        assert rep.multipliers[name] == pytest.approx(exact[name], rel=1e-12)


def test_a_floor_out_of_reach_is_refused_by_name():
    with pytest.raises(FieldError, match="diameter_bounds: the closed-form D"):
        cantilever_tube_optimum(CantileverTube(omega_min=2 * np.pi * 200.0))
    with pytest.raises(FieldError, match="thickness_bounds"):
        CantileverTube(thickness_bounds=(2e-3, 1e-3))
