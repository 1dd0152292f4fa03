"""Attitude kinematics: the seed-003 target attitude to its printed digits, round trips of every
representation to a bound derived from eps, the kinematic rates against finite differences
along an exactly known rotation, Shepperd's method at 180°, and bad input named."""

import re

import numpy as np
import pytest

from flexsat.dynamics import attitude as att

EPS = np.finfo(float).eps
N = 500  # random rotations per batched check


def random_quaternions(n=N, seed=0):
    b = np.random.default_rng(seed).standard_normal((n, 4))
    return b / np.linalg.norm(b, axis=-1, keepdims=True)


def same_attitude(b1, b2):
    """Distance between two quaternions up to the sign (β and −β are the same attitude)."""
    return np.minimum(np.abs(b1 - b2).max(-1), np.abs(b1 + b2).max(-1))


def test_seed003_target_attitude_to_the_printed_digits():
    # seed 003 §1.3: 1 rad about each axis, 1-2-3 sequence; printed to 6 decimals, so the
    # computed values must agree to half a unit in the last printed digit
    beta = att.dcm_to_quaternion(att.euler123_to_dcm([1.0, 1.0, 1.0]))
    half_ulp = 0.5e-6 + 1e-15
    assert np.abs(beta - [0.565676, 0.570941, 0.167519, 0.570941]).max() <= half_ulp
    axis, angle = att.quaternion_to_principal_rotation(beta)
    assert abs(angle - 1.939088) <= half_ulp
    assert np.abs(axis - [0.692363, 0.203145, 0.692363]).max() <= half_ulp
    # and back: the principal rotation gives the same quaternion
    back = att.principal_rotation_to_quaternion(axis, angle)
    assert np.abs(back - beta).max() <= 4 * EPS


@pytest.mark.numerics
def test_dcm_is_orthonormal_and_round_trips_through_shepperd():
    beta = random_quaternions()
    C = att.quaternion_to_dcm(beta)
    # each entry is a sum of four products of unit-norm numbers: a few eps
    assert np.abs(C @ np.swapaxes(C, -1, -2) - np.eye(3)).max() <= 8 * EPS
    assert np.abs(np.linalg.det(C) - 1).max() <= 8 * EPS
    back = att.dcm_to_quaternion(C)
    assert np.all(back[:, 0] >= 0)
    # C carries ~4 eps per entry; Shepperd divides by the largest parameter, never below ½
    assert same_attitude(back, beta).max() <= 16 * EPS


@pytest.mark.numerics
def test_shepperd_is_robust_at_and_near_180_degrees():
    rng = np.random.default_rng(1)
    axis = rng.standard_normal((200, 3))
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    for angle in (np.pi, np.pi - 1e-9, np.pi + 1e-7, 1e-12):
        beta = att.principal_rotation_to_quaternion(axis, np.full(200, angle))
        back = att.dcm_to_quaternion(att.quaternion_to_dcm(beta))
        assert same_attitude(back, beta).max() <= 16 * EPS, angle
        assert np.abs(np.linalg.norm(back, axis=-1) - 1).max() <= 4 * EPS


def test_composition_matches_the_dcm_product():
    b1, b2 = random_quaternions(seed=2), random_quaternions(seed=3)
    C = att.quaternion_to_dcm(att.quaternion_multiply(b2, b1))
    assert np.abs(C - att.quaternion_to_dcm(b2) @ att.quaternion_to_dcm(b1)).max() <= 16 * EPS
    # the composition is not commutative: the claim above is about this order
    C_swapped = att.quaternion_to_dcm(att.quaternion_multiply(b1, b2))
    assert np.abs(C_swapped - att.quaternion_to_dcm(b2) @ att.quaternion_to_dcm(b1)).max() > 1e-3


@pytest.mark.numerics
def test_euler123_round_trip_away_from_gimbal_lock():
    rng = np.random.default_rng(4)
    # θ2 kept 0.1 rad from ±90°: the recovered θ1, θ3 lose ~eps/cos θ2 <= 10 eps
    angles = np.stack(
        [rng.uniform(-np.pi, np.pi, N), rng.uniform(-1.47, 1.47, N), rng.uniform(-np.pi, np.pi, N)],
        -1,
    )
    assert np.abs(att.dcm_to_euler123(att.euler123_to_dcm(angles)) - angles).max() <= 64 * EPS
    # the definition C = R3 R2 R1, written out for single-axis rotations
    c, s = np.cos(0.3), np.sin(0.3)
    assert np.allclose(att.euler123_to_dcm([0.3, 0, 0]), [[1, 0, 0], [0, c, s], [0, -s, c]])
    assert np.allclose(att.euler123_to_dcm([0, 0.3, 0]), [[c, 0, -s], [0, 1, 0], [s, 0, c]])
    assert np.allclose(att.euler123_to_dcm([0, 0, 0.3]), [[c, s, 0], [-s, c, 0], [0, 0, 1]])


@pytest.mark.numerics
def test_gibbs_and_mrp_round_trips_and_the_shadow_set():
    beta = random_quaternions(seed=5)
    beta[beta[:, 0] < 0] *= -1
    # Gibbs: |β0| >= 0.1 here, so |q| <= 10 and β_i/β0 carries <= ~20 eps of relative error
    far = beta[beta[:, 0] >= 0.1]
    q = att.quaternion_to_gibbs(far)
    assert np.abs(att.gibbs_to_quaternion(q) - far).max() <= 32 * EPS
    sigma = att.quaternion_to_mrp(beta)
    assert np.all(np.linalg.norm(sigma, axis=-1) <= 1 + 4 * EPS)
    assert np.abs(att.mrp_to_quaternion(sigma) - beta).max() <= 16 * EPS
    # the shadow set is the same attitude with −β: the same DCM
    shadow = att.mrp_shadow(sigma)
    C = att.quaternion_to_dcm(att.mrp_to_quaternion(shadow))
    assert np.abs(C - att.quaternion_to_dcm(beta)).max() <= 64 * EPS
    assert np.abs(att.mrp_shadow(shadow) - sigma).max() <= 16 * EPS


def test_conversions_work_on_several_leading_axes():
    beta = random_quaternions(24, seed=10).reshape(2, 3, 4, 4)
    C = att.quaternion_to_dcm(beta)
    assert C.shape == (2, 3, 4, 3, 3)
    flat = att.quaternion_to_dcm(beta.reshape(-1, 4)).reshape(C.shape)
    assert np.array_equal(C, flat)  # elementwise arithmetic: identical, not just close
    assert att.dcm_to_euler123(C).shape == (2, 3, 4, 3)
    assert att.quaternion_to_mrp(np.abs(beta)).shape == (2, 3, 4, 3)


def test_omega_and_rate_matrices_agree():
    beta = random_quaternions(seed=6)
    w = np.random.default_rng(7).standard_normal((N, 3))
    lhs = (att.omega_matrix(w) @ beta[..., None])[..., 0]
    rhs = (att.quaternion_rate_matrix(beta) @ w[..., None])[..., 0]
    assert np.abs(lhs - rhs).max() <= 4 * EPS
    assert np.allclose(
        att.cross_matrix(w) @ beta[:, 1:, None], np.cross(w, beta[:, 1:])[..., None], atol=4 * EPS
    )


def exact_rotation(w, beta0, t):
    """β(t) = exp(ω t) ⊗ β0 for a constant body rate ω: the exact solution of β̇ = Ω(ω)β."""
    return att.quaternion_multiply(att.quaternion_exp(w * t), beta0)


@pytest.mark.numerics
def test_kinematic_rates_equal_finite_differences_along_an_exact_rotation():
    rng = np.random.default_rng(8)
    w = rng.standard_normal((50, 3))
    beta0 = random_quaternions(50, seed=9)
    beta0[beta0[:, 0] < 0] *= -1
    t, h = 0.3, 1e-5
    # central differences: truncation h²/6 |x'''| ~ 2e-11 |x'''| and round-off eps |x| / h
    # ~ 2e-11 |x|. Gibbs parameters with |β0| down to 0.2 reach |q| ~ 5, |q̇| ~ 12 and
    # |q'''| ~ 1e3 (measured FD error 1.2e-8; 5e-11 for MRPs and β): 1e-8 relative to the
    # largest rate keeps a 10x margin and is far below any formula error (a wrong sign or
    # factor is O(1))
    b = {s: exact_rotation(w, beta0, t + s * h) for s in (-1, 0, 1)}
    keep = np.abs(b[0][:, 0]) > 0.2  # Gibbs parameters stay moderate, 1 + β0 > 0 for MRPs
    pairs = ((att.quaternion_to_gibbs, att.gibbs_rate), (att.quaternion_to_mrp, att.mrp_rate))
    for to, rate in pairs:
        x = {s: to(np.where(b[0][:, :1] < 0, -b[s], b[s])[keep]) for s in b}
        fd = (x[1] - x[-1]) / (2 * h)
        exact = rate(x[0], w[keep])
        assert np.abs(fd - exact).max() <= 1e-8 * max(1.0, np.abs(exact).max()), to.__name__
    fd = (b[1] - b[-1]) / (2 * h)
    exact = (att.omega_matrix(w) @ b[0][..., None])[..., 0]
    assert np.abs(fd - exact).max() <= 1e-8


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda: att.quaternion_to_dcm([1.0, 0.0, 0.0]), "beta: last axes must have shape (4,)"),
        (lambda: att.quaternion_to_dcm([1.0, np.nan, 0.0, 0.0]), "beta: must be finite"),
        (lambda: att.quaternion_to_dcm([0.99, 0.0, 0.0, 0.0]), "beta: must be a unit quaternion"),
        (lambda: att.dcm_to_quaternion(np.eye(3) * 1.01), "dcm: must be orthonormal"),
        (lambda: att.dcm_to_quaternion(-np.eye(3)), "dcm: must be a proper rotation"),
        (lambda: att.euler123_to_dcm(np.zeros((2, 2))), "angles: last axes must have shape (3,)"),
        (
            lambda: att.principal_rotation_to_quaternion([1.0, 1.0, 0.0], 0.1),
            "axis: must be a unit",
        ),
        (
            lambda: att.quaternion_to_gibbs([0.0, 1.0, 0.0, 0.0]),
            "beta: the Gibbs vector is singular",
        ),
        (lambda: att.quaternion_to_mrp([-1.0, 0.0, 0.0, 0.0]), "beta: the MRP vector is singular"),
        (lambda: att.mrp_shadow([0.0, 0.0, 0.0]), "sigma: the shadow set of σ = 0"),
        (lambda: att.gibbs_rate([0.0, 0.0, 0.0], [np.inf, 0.0, 0.0]), "w: must be finite"),
        (lambda: att.omega_matrix("fast"), "w: must be a numeric array"),
        (
            lambda: att.quaternion_multiply(np.ones((2, 4)) / 2, np.ones((3, 4)) / 2),
            "second, first: leading (case) axes must broadcast",
        ),
        (lambda: att.mrp_rate(np.zeros((2, 3)), np.zeros((5, 3))), "sigma, w: leading (case) axes"),
    ],
)
def test_bad_input_names_the_field(call, field):
    with pytest.raises(ValueError, match=re.escape(field)):
        call()


def test_the_package_re_exports_every_kernel():
    from flexsat import dynamics
    from flexsat.dynamics import attitude_linearization, orbit, rigid_body, structural

    kernels = {*att.__all__, *rigid_body.__all__} - {"UNIT_TOL", "SINGULAR_TOL"}
    plants = {
        *structural.__all__,
        *orbit.__all__,
        "RigidSpacecraft",
        "FlexibleSpacecraft",
        "CmgSpacecraft",
        "GimbalCluster",
        "SpaceStation",
        "StateSpacePlant",
        "TetheredSubsatellite",
        "TetherScales",
    }
    linearisation = set(attitude_linearization.__all__) - {"COORDINATES"}
    assert kernels | plants | linearisation == set(dynamics.__all__)
    assert dynamics.dcm_to_quaternion is att.dcm_to_quaternion


def test_euler123_to_quaternion_is_the_rotation_of_euler123_to_dcm_and_continuous():
    """F4 (seed 003 §1.3): (1, 1, 1) rad gives the printed β_f to half a unit of its 6th digit;
    for random angles C(β) equals R3 R2 R1 to a few eps (products of unit quaternions); along a
    path of angles β moves continuously (no sign flip, unlike the β0 >= 0 of Shepperd's
    method), so a continuation in the angles can follow it."""
    beta = att.euler123_to_quaternion([1.0, 1.0, 1.0])
    assert np.abs(beta - [0.565676, 0.570941, 0.167519, 0.570941]).max() <= 0.5e-6 + 1e-15
    angles = np.random.default_rng(3).uniform(-3.0, 3.0, (50, 3))
    assert (
        np.abs(
            att.quaternion_to_dcm(att.euler123_to_quaternion(angles)) - att.euler123_to_dcm(angles)
        ).max()
        <= 16 * EPS
    )
    path = np.linspace(0.0, 1.0, 2001)[:, None] * np.array([3.0, 1.2, -3.1])
    steps = np.abs(np.diff(att.euler123_to_quaternion(path), axis=0)).max()
    assert steps <= 2 * np.abs(np.diff(path, axis=0)).max()  # |dβ/dθ_k| <= 1/2 per angle


def test_one_angle_about_many_axes_broadcasts_to_one_quaternion_per_axis():
    """Eqs. 9–10 per case: three axes and one angle give three quaternions, each equal to the
    single-axis call (the same arithmetic, so exactly)."""
    axes = np.eye(3)
    beta = att.principal_rotation_to_quaternion(axes, 0.3)
    assert beta.shape == (3, 4)
    for row, axis in zip(beta, axes):
        np.testing.assert_array_equal(row, att.principal_rotation_to_quaternion(axis, 0.3))
    many = att.principal_rotation_to_quaternion([0.0, 0.0, 1.0], [0.1, 0.2])
    assert many.shape == (2, 4)
    np.testing.assert_array_equal(many[1], att.principal_rotation_to_quaternion([0, 0, 1.0], 0.2))
