"""Trade surfaces of the smoothed bang-bang maneuver (flexsat.design.trade_surfaces), seed 000
Att. 3 Eqs. 12-16, 22 (Junkins, Pollock & Rahman 1990)."""

import numpy as np
import pytest

from flexsat.cases import tamu
from flexsat.design.trade_surfaces import (
    maneuver_time_surface,
    residual_energy_surface,
    tracking_bound,
    tracking_bound_surface,
)
from flexsat.sim import SimConfig, simulate
from flexsat.sim.open_loop import open_loop_response
from flexsat.units import to_si

ALPHA = np.array([0.0, 0.1, 0.2, 0.25])
G1, G2 = to_si("3000 ozf*in/rad", "N*m/rad"), to_si("800 ozf*in*s/rad", "N*m*s/rad")


@pytest.fixture(scope="module")
def case():
    return tamu()


@pytest.fixture(scope="module")
def model(case):
    return case.model()


def test_maneuver_time_is_eq_16_on_the_grid(case):
    """T = sqrt(I Δθ / (u_max (1/4 − α/2 + α²/10))), axis 0 α, axis 1 u_max; published units
    are converted (one rounding of the square root: 4 ulp)."""
    u = ["100 ozf*in", "400 ozf*in"]
    T = maneuver_time_surface("40 deg", "2128 ozf*in*s**2", ALPHA, u)
    I, dth = to_si("2128 ozf*in*s**2", "kg*m**2"), np.radians(40)
    um = np.array([to_si(v, "N*m") for v in u])
    c = 0.25 - ALPHA / 2 + ALPHA**2 / 10
    assert T.shape == (4, 2)
    assert np.allclose(T, np.sqrt(I * dth / (um[None, :] * c[:, None])), rtol=4e-16 * 4, atol=0)


def test_residual_energy_converges_to_the_held_torque_simulation(case, model):
    """simulate applies u_ref held over each control period; its vibration energy after the
    maneuver tends to the exact continuous-torque response as the period shrinks (first order
    in dt: the held torque is the continuous one plus a sawtooth of amplitude |u'| dt/2),
    within 1e-3 at 1200 Hz for the smooth (α > 0) torques. After T both responses are free, so
    the comparison is made at the last sample, where the exact state is the free continuation
    of the one E(T) is computed from."""
    alpha = ALPHA[1:]
    shape = case.reference(alpha=alpha)
    E_T = residual_energy_surface(
        model, case.angle, case.reference_inertia, alpha, [case.max_torque]
    )[:, 0]
    at_T = open_loop_response(model, shape, shape.duration[None, :])[0]
    assert np.array_equal(E_T, model.vibration_energy(at_T))
    errors = []
    for rate in (300.0, 1200.0):
        run = simulate(
            model,
            case.law_ii(0.0, 0.0, 0.0, alpha=alpha),
            SimConfig(duration=6.0, control_rate=rate),
        )
        t_end = run.dataset.time.values[-1]
        E = model.vibration_energy(open_loop_response(model, shape, np.array([t_end]))[0])
        errors.append(np.abs(run.dataset.vibration_energy.values[:, -1] / E - 1))
    assert np.all(errors[1] <= 1e-3)
    assert np.all(errors[1] < errors[0] / 2)


def test_energy_falls_by_orders_of_magnitude_with_alpha(case, model):
    """Att. 3 (L1158): 'significantly reduced for any given u_max by increasing α'."""
    u = [to_si(f"{v} ozf*in", "N*m") for v in (100, 400, 600)]
    E = residual_energy_surface(model, case.angle, case.reference_inertia, ALPHA, u)
    assert np.all(E[-1] < 1e-3 * E[0])
    assert np.all(E >= 0)


def test_mu_vanishes_with_the_flexibility(case):
    """μ measures how far the rigid reference is from satisfying the flexible equations of
    motion (Att. 3 L1197): with the reference designed on the model's own inertia, stiffening
    the appendages 10⁴× shrinks μ_max by orders of magnitude (the modes move 100× up)."""
    out = []
    for modulus in (case.modulus, 1e4 * case.modulus):
        c = tamu(modulus=modulus)
        m = c.model()
        out.append(
            tracking_bound_surface(
                m,
                c.angle,
                m.total_inertia,
                [0.2],
                [c.max_torque],
                G1,
                G2,
                0.0,
                c.params.appendage_inertia,
                n_samples=4001,
            )[0, 0]
        )
    assert out[1] < 1e-2 * out[0]


def test_mu_is_eq_22_of_the_two_open_loop_motions(case, model):
    """At t = 0 both motions are at rest at θ0 and their root loads come from the same torque
    (0 at t = 0); after T the rigid reference is at rest on the target, so μ = |g1 (θ_r − θ_f)
    + g2 θ'_r + g3 R_r| / g2: the flexible motion's residual alone."""
    shape = case.reference(alpha=np.array([0.1, 0.2]))
    T = shape.duration
    t = np.stack([np.zeros(2), T + 0.3])
    mu = tracking_bound(model, shape, t, G1, G2, 1.5, case.params.appendage_inertia)
    assert np.all(mu[0] == 0)
    x = open_loop_response(model, shape, t[1:])[0]
    R = model.output("root_torque", x, np.zeros((2, 1)))
    expect = np.abs(G1 * (x[:, 0] - case.angle) + G2 * x[:, model.ndof] + 1.5 * R) / G2
    assert mu[1] == pytest.approx(expect, rel=1e-12)


def test_mu_max_sampling_error_is_within_its_bound(case, model):
    """2001 samples over T ≈ 4.9 s put ≈ 120 samples in a 3.4 Hz period: the sampled maximum
    is within (π/120)²/2 ≈ 3.4e-4 of the maximum found with 4× the samples."""
    args = (
        model,
        case.angle,
        case.reference_inertia,
        [0.05, 0.2],
        [case.max_torque],
        G1,
        G2,
        0.0,
        case.params.appendage_inertia,
    )
    coarse = tracking_bound_surface(*args, n_samples=2001)
    fine = tracking_bound_surface(*args, n_samples=8001)
    assert np.all(coarse <= fine * (1 + 1e-12))
    assert np.allclose(coarse, fine, rtol=3.4e-4, atol=0)


def test_bad_input_names_the_field(case, model):
    with pytest.raises(ValueError, match="alpha, u_max: give 1-D grids"):
        maneuver_time_surface(case.angle, 1.0, [[0.1]], [1.0])
    with pytest.raises(ValueError, match="alpha: out of range"):
        maneuver_time_surface(case.angle, 1.0, [0.3], [1.0])
    with pytest.raises(ValueError, match="u_max"):
        residual_energy_surface(model, case.angle, 1.0, [0.1], [-1.0])
    with pytest.raises(ValueError, match="g2: must be > 0"):
        tracking_bound(model, case.reference(), [1.0], G1, 0.0)
    with pytest.raises(ValueError, match="g3: must be > -4"):
        tracking_bound(model, case.reference(), [1.0], G1, G2, -4.0)
    with pytest.raises(ValueError, match="plant: the exact open-loop response needs a linear"):
        residual_energy_surface(tamu(stiffening=True).model(), case.angle, 1.0, [0.1], [1.0])
