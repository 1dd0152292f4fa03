"""Claims about the structure + control reference problem (``design.reference_problems.
HubBoomCodesign``): its analytic gradients, and two independent optimisers agreeing on it.

Finite-difference reference: the five-point central difference with h = 1e-3 |p|, truncation
h⁴ |J⁽⁵⁾|/30 ≲ 1e-12 |J| on these smooth responses and round-off ≈ 1.5 ε_J |J| / h with
ε_J ≈ 1e-13 (the Riccati/Lyapunov and eigen-solver residuals of a 13-dof, 8-state problem),
i.e. ≲ 1e-9 |J|, both below the issue-23 bound 1e-6 relative to max(|∂J|, |J| / |p|).
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.design.optimize import optimize_design
from flexsat.design.reference_problems import HubBoomCodesign
from flexsat.input_checks import FieldError

ACCEPT = 1e-6
KKT = 1e-6


def central(f, p, h):
    return (-f(p + 2 * h) + 8 * f(p + h) - 8 * f(p - h) + f(p - 2 * h)) / (12.0 * h)


@pytest.mark.parametrize("response", ["lq_cost", "mass", "frequency_hz"])
def test_analytic_gradients_match_central_differences(response):
    hb = HubBoomCodesign()
    x0 = np.array([1.2e-3, 0.027])
    value, grad = hb.responses(x0)[response]
    for k in range(2):
        e = np.zeros(2)
        e[k] = 1.0

        def f(step, e=e):
            return hb.responses(x0 + step * e)[response][0]

        fd = central(f, 0.0, 1e-3 * x0[k])
        assert abs(grad[k] - fd) <= ACCEPT * max(abs(fd), abs(value) / x0[k]), (k, grad[k], fd)


@pytest.mark.numerics
@pytest.mark.parametrize("response", HubBoomCodesign.MANEUVER_RESPONSES)
@pytest.mark.parametrize("x", [(2e-3, 0.04), (1.2e-3, 0.027)], ids=["start", "thin"])
def test_maneuver_gradients_match_central_differences(response, x):
    """The sampled slew's metrics (engine run, discrete adjoint, FE chain) against five-point
    central differences with h = 5e-6 |p|: the terminal metrics of the lightly damped modes
    vary fast with (t, D) (phase ω_i T of modes up to 400 Hz over T = 3 s: |J⁽⁵⁾| ≲
    (ω T/|p| · ∂ω/∂p · |p|/ω)⁵ |J|), so the step is small: truncation (5e-6 · 2π·400·3)⁴/30
    ≈ 4e-8 relative; round-off 1.5 ε_J |J| / h with ε_J ≈ 1e-13 (eigen and DARE solves) is
    3e-8 |J|/|p| · |p|, both below the 1e-6 bound relative to max(|∂J|, |J| / |p|)."""
    hb = HubBoomCodesign(maneuver=True)
    x0 = np.array(x)
    value, grad = hb.responses(x0)[response]
    for k in range(2):
        e = np.zeros(2)
        e[k] = 1.0

        def f(step, e=e):
            return hb.responses(x0 + step * e)[response][0]

        fd = central(f, 0.0, 5e-6 * x0[k])
        assert abs(grad[k] - fd) <= ACCEPT * max(abs(fd), abs(value) / x0[k]), (k, grad[k], fd)


def test_maneuver_responses_leave_the_others_unchanged():
    x = np.array([1.2e-3, 0.027])
    base = HubBoomCodesign().responses(x)
    both = HubBoomCodesign(maneuver=True).responses(x)
    assert set(both) == set(base) | set(HubBoomCodesign.MANEUVER_RESPONSES)
    for name, (v, g) in base.items():
        assert both[name][0] == v
        np.testing.assert_array_equal(both[name][1], g)
    assert 0 < both["soft_settling"][0] < HubBoomCodesign.maneuver_time


def test_the_structural_mass_is_one_tube_boom_and_its_tip_mass():
    # the half model carries one boom: ρ A L plus the tip mass (the hub inertia has no mass)
    hb = HubBoomCodesign()
    t, D = 1e-3, 0.03
    area = np.pi * t * (D - t)
    mass, grad = hb.responses(np.array([t, D]))["mass"]
    assert mass == pytest.approx(hb.density * area * hb.length + hb.tip_mass, rel=1e-12)
    assert grad == pytest.approx(hb.density * hb.length * np.pi * np.array([D - 2 * t, t]))


def test_slsqp_and_trust_constr_agree_where_the_lq_gradient_sets_the_diameter():
    # frequency floor 6 Hz inactive: the wall sits at its lower bound (thin walls are the
    # efficient section) and the diameter is set by ∂(J_LQ + w_m m)/∂D = 0 -- stiffness
    # against slewed inertia, carried by the adjoint gradient
    hb = HubBoomCodesign(frequency_min_hz=6.0)
    a = optimize_design(hb.problem(), "slsqp")
    b = optimize_design(hb.problem(), "trust-constr")
    for res in (a, b):
        assert res.kkt.residual <= KKT, (res.method, res.kkt)
        assert res.active == ("t >= lower",)
        assert res.constraints["first frequency floor"] < -0.1  # clearly inactive
    assert hb.diameter_bounds[0] < a.x[1] < hb.diameter_bounds[1]
    assert np.allclose(a.x, b.x, rtol=0.01)
    assert abs(a.objective - b.objective) <= 0.01 * abs(a.objective)


@pytest.mark.parametrize(
    "second",
    ["trust-constr", pytest.param("homotopy", marks=pytest.mark.slow)],  # homotopy: ~900 calls
)
def test_two_optimisers_agree_when_the_first_frequency_floor_is_active(second):
    hb = HubBoomCodesign(frequency_min_hz=10.0)
    a = optimize_design(hb.problem(), "slsqp")
    b = optimize_design(hb.problem(), second)
    for res in (a, b):
        assert res.kkt.residual <= KKT, (res.method, res.kkt)
        assert set(res.active) == {"first frequency floor", "t >= lower"}
        assert res.multipliers["first frequency floor"] > 0
    assert abs(hb.responses(a.x)["frequency_hz"][0] - 10.0) <= 1e-8 * 10.0
    assert np.allclose(a.x, b.x, rtol=0.01)
    assert abs(a.objective - b.objective) <= 0.01 * abs(a.objective)
    lam_a, lam_b = a.multipliers["first frequency floor"], b.multipliers["first frequency floor"]
    assert abs(lam_a - lam_b) <= 0.01 * lam_a


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(length=-1.0), "length"),
        (dict(elements=0), "elements"),
        (dict(weights=(0.0, 1.0, 1.0)), "weights"),
        (dict(weights=(1.0, np.nan, 1.0)), "weights"),
        (dict(frequency_min_hz=0.0), "frequency_min_hz"),
    ],
)
def test_bad_codesign_data_is_refused_by_name(kwargs, field):
    with pytest.raises(FieldError) as exc:
        HubBoomCodesign(**kwargs)
    assert exc.value.field == field
