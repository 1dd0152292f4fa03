"""Single-gimbal CMG pyramid kernels (issue 14, V1, V2): the zero-momentum gain of the preferred
set, saturation along +x on the envelope, the stored preferred-set table (recomputed by the
back integration of :mod:`flexsat.cases.cmg_pyramid`, whose runs V3-V8 are tested in
tests/cases/test_cmg_pyramid.py); the Jacobian is ∂h/∂σ; the envelope bounds every reachable
momentum; the steering and null-projector kernels; bad input named."""

import numpy as np
import pytest

from flexsat.cases import cmg_pyramid
from flexsat.dynamics import cmg

DEG = np.deg2rad
EPS = np.finfo(float).eps
SKEW = DEG(54.74)
MAGIC = np.arccos(1.0 / np.sqrt(3.0))  # 54.7356°: the skew at which the paper's sets sum to 0
PAPER_X = np.array([-1.0, 0.0, 0.0])  # the paper's unit +x demand ḣ as the spacecraft torque


def test_v1_preferred_set_has_the_papers_zero_momentum_gain():
    sigma = DEG([-60.0, 60.0, 120.0, -120.0])
    # the paper prints 4 digits: 1.1854 ± half a unit of the last
    assert cmg.gain(sigma) == pytest.approx(1.1854, abs=5e-5)
    # h_x = √3 cosδ − 1 = −h_y, h_z = 0 in closed form: zero only at the magic angle
    # arccos(1/√3) = 54.7356°, so 54.74° leaves 1.1e-4 (the notes' "h = 0 to 1e-4")
    r = np.sqrt(3.0) * np.cos(SKEW) - 1.0
    np.testing.assert_allclose(cmg.momentum(sigma), [r, -r, 0.0], atol=10 * EPS)
    assert abs(r) < 1.1e-4
    np.testing.assert_allclose(cmg.momentum(sigma, MAGIC), 0.0, atol=10 * EPS)
    # the other zero-momentum sets of the notes (§8.3): 0.5928 and 1.1848, 4 digits
    assert cmg.gain(DEG([45.0, -45.0, 45.0, -45.0])) == pytest.approx(0.5928, abs=5e-5)
    assert cmg.gain(np.zeros(4)) == pytest.approx(1.1848, abs=5e-5)


def test_v2_saturation_along_x_is_the_envelope():
    sigma = DEG([-90.0, 180.0, 90.0, 0.0])
    h_sat = 2.0 * np.cos(SKEW) + 2.0
    np.testing.assert_allclose(cmg.momentum(sigma), [h_sat, 0.0, 0.0], atol=10 * EPS)
    assert h_sat == pytest.approx(3.1545, abs=1e-4)  # printed value, 5 digits (3.15458)
    value, sigma_env = cmg.envelope([1.0, 0.0, 0.0])
    assert value == pytest.approx(h_sat, rel=10 * EPS)
    np.testing.assert_allclose(cmg.momentum(sigma_env), [h_sat, 0.0, 0.0], atol=10 * EPS)
    # saturation is an external singularity: the gain vanishes, all units add along +x
    sing = cmg.classify_singularity(sigma)
    assert sing.singular and not sing.internal
    np.testing.assert_array_equal(sing.signs, [1, 1, 1, 1])
    assert sing.margin == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("direction, stored", cmg.PREFERRED_SETS)
def test_stored_preferred_sets_are_the_back_integration_and_saturate(direction, stored):
    # the table is computed data: recomputed here; stored to 0.01°, so ±0.005° of rounding plus
    # the back integration's error (rtol 1e-10 on σ, far below)
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    got = np.rad2deg(cmg_pyramid.preferred_angles(u))
    np.testing.assert_allclose(got, stored, atol=0.005 + 1e-6)
    # the stored set runs forward under the unit demand ḣ = u to the envelope, not internally
    # singular (within V5's 1e-3 on the momentum along u)
    run = cmg_pyramid.integrate_gimbals(DEG(stored), -u, 10.0)
    assert run.singular and not cmg.classify_singularity(run.sigma[-1], threshold=1e-5).internal
    assert run.h[-1] @ u == pytest.approx(cmg.envelope(u)[0], abs=1e-3)
    np.testing.assert_allclose(cmg.preferred_set(2.0 * u), DEG(stored), atol=1e-15)


def test_preferred_set_picks_the_nearest_stored_direction():
    np.testing.assert_allclose(cmg.preferred_set([1.0, 0.1, -0.05]), DEG(cmg.PREFERRED_SETS[0][1]))
    np.testing.assert_allclose(cmg.preferred_set([0.1, 0.2, 1.0]), DEG(cmg.PREFERRED_SETS[4][1]))
    with pytest.raises(ValueError, match="direction: must be a nonzero"):
        cmg.preferred_set([0.0, 0.0, 0.0])


@pytest.mark.parametrize(
    "n_units, skew", [(3, DEG(30.0)), (4, SKEW), (5, DEG(60.0)), (6, DEG(75.0))]
)
def test_jacobian_is_the_derivative_of_the_momentum(n_units, skew):
    rng = np.random.default_rng(14)
    sigma = rng.uniform(-np.pi, np.pi, (5, n_units))  # a case axis of 5 gimbal sets
    c = cmg.jacobian(sigma, skew, n_units)
    assert c.shape == (5, 3, n_units)
    step = 1e-5  # central differences: truncation step²/6 ≈ 2e-11, round-off eps/step ≈ 2e-11
    for i in range(n_units):
        e = np.zeros(n_units)
        e[i] = step
        fd = (cmg.momentum(sigma + e, skew, n_units) - cmg.momentum(sigma - e, skew, n_units)) / (
            2 * step
        )
        np.testing.assert_allclose(c[..., i], fd, atol=1e-8)
    # gain = det(CCᵀ) of the same C
    np.testing.assert_allclose(
        cmg.gain(sigma, skew, n_units), np.linalg.det(c @ np.swapaxes(c, -1, -2)), rtol=1e-12
    )


@pytest.mark.parametrize("n_units", [3, 4, 6])
def test_envelope_bounds_every_momentum_and_is_reached(n_units):
    rng = np.random.default_rng(7)
    u = rng.normal(size=(20, 3))
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    value, sigma = cmg.envelope(u, SKEW, n_units)
    h_env = cmg.momentum(sigma, SKEW, n_units)
    np.testing.assert_allclose(np.einsum("ij,ij->i", u, h_env), value, rtol=1e-12)
    # the envelope point is an external singularity along u
    sing = cmg.classify_singularity(sigma, SKEW, n_units)
    assert np.all(sing.singular) and not np.any(sing.internal)
    samples = cmg.momentum(rng.uniform(-np.pi, np.pi, (2000, n_units)), SKEW, n_units)
    assert np.all(samples @ u.T <= value + 1e-12)


def test_steering_inverts_the_jacobian_and_the_sr_inverse_passes_singularities():
    rng = np.random.default_rng(3)
    sigma = rng.uniform(-np.pi, np.pi, (4, 4))
    torque = rng.normal(size=(4, 3))
    rates = cmg.steering_rates(sigma, torque)
    c = cmg.jacobian(sigma)
    cond = np.linalg.cond(c @ np.swapaxes(c, -1, -2))
    err = np.abs(np.einsum("...ij,...j->...i", c, rates) + torque).max(axis=-1)
    assert np.all(err <= 100 * cond * EPS * np.abs(torque).max(axis=-1))  # ḣ = −torque
    # minimum norm: the rates lie in the row space of C (orthogonal to null motion)
    null = np.linalg.svd(c)[2][:, 3:]  # (case, n − 3, n): rows spanning the null space of C
    assert np.abs(np.einsum("ckn,cn->ck", null, rates)).max() < 1e-10
    saturated = DEG([-90.0, 180.0, 90.0, 0.0])
    with pytest.raises(ValueError, match="singular"):
        cmg.steering_rates(saturated, [0.0, 0.0, 1.0])
    sr = cmg.steering_rates(saturated, PAPER_X, alpha=1e-3)
    assert np.all(np.isfinite(sr))
    # along the singular direction the SR inverse gives no rate: Cσ̇ has no x component
    assert abs((cmg.jacobian(saturated) @ sr)[0]) < 1e-12


def test_null_projector_is_a_projector_onto_torque_free_motion():
    rng = np.random.default_rng(8)
    sigma = rng.uniform(-np.pi, np.pi, (6, 5))
    c = cmg.jacobian(sigma, SKEW, 5)
    tau = cmg.null_projector(sigma, SKEW, 5)
    # τ² = τ, τᵀ = τ, Cτ = 0 (Eq. 14), to round-off of the solve (cond(CCᵀ) × eps)
    tol = 100 * np.linalg.cond(c @ np.swapaxes(c, -1, -2)).max() * EPS
    np.testing.assert_allclose(tau @ tau, tau, atol=tol)
    np.testing.assert_allclose(tau, np.swapaxes(tau, -1, -2), atol=tol)
    np.testing.assert_allclose(c @ tau, 0.0, atol=tol)
    # the SR form (Eq. 17) leaves Cτ = α(CCᵀ + αI)⁻¹C
    alpha = 1e-3
    tau_sr = cmg.null_projector(sigma, SKEW, 5, alpha)
    cct = c @ np.swapaxes(c, -1, -2)
    np.testing.assert_allclose(
        c @ tau_sr, alpha * np.linalg.solve(cct + alpha * np.eye(3), c), atol=tol
    )
    with pytest.raises(ValueError, match="singular"):
        cmg.null_projector(DEG([-90.0, 180.0, 90.0, 0.0]))


def test_angles_accept_units():
    np.testing.assert_allclose(
        cmg.momentum(["-90 deg", "180 deg", "90 deg", "0 deg"], "54.74 deg"),
        [2 * np.cos(SKEW) + 2, 0.0, 0.0],
        atol=1e-12,
    )


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: cmg.gain(np.zeros(4), DEG(90.0)), "skew: must lie in"),
        (lambda: cmg.gain(np.zeros(4), 0.0), "skew: must lie in"),
        (lambda: cmg.gain(np.zeros(2), n_units=2), "n_units: must be an integer >= 3"),
        (lambda: cmg.momentum(np.zeros(3)), "sigma: last axis must hold the 4"),
        (lambda: cmg.jacobian([0.0, np.nan, 0.0, 0.0]), "sigma: must be finite"),
        (lambda: cmg.envelope([0.0, 0.0, 0.0]), "direction: must be nonzero"),
        (lambda: cmg.steering_rates(np.zeros(4), [1.0, 0.0]), "torque: last axis"),
        (lambda: cmg.steering_rates(np.zeros(4), [1.0, 0.0, 0.0], alpha=-1.0), "alpha: must be"),
    ],
)
def test_bad_input_is_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()
