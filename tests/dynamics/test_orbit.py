"""BeamInOrbit: Bainum & Reddy's beam in orbit, seed 002 Ch. II eqs 1-2 (pitch and bending
with gravity gradient), in seconds, split into its linearisation and a nonlinear remainder."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from flexsat.dynamics.orbit import BeamInOrbit

EPS = np.finfo(float).eps
WC = 1.11577e-3  # rad/s, the 250 n.mi. orbit of seed 002
F = np.array([3200.0, 28800.0])


def _beam(**kw):
    G = {"f1": [59.52, 20.0, 20.0], "f2": [-59.52, 20.0, -20.0]}
    stations = {"end": [2.0, 2.0], "mid": [-1.2156, 0.0]}
    return BeamInOrbit(WC, F, G, stations, **kw)


def _eqs_1_2_in_seconds(x, f):
    """Seed 002 eqs 1-2 as printed (τ = ω_c t), rewritten for d/dt: ẍ = ω_c² x''."""
    th, z1, z2, dth, dz1, dz2 = x
    G = np.array([[59.52, -59.52], [20.0, 20.0], [20.0, -20.0]])
    u = G @ f
    thp = dth / WC  # θ'
    acc = np.array(
        [
            -1.5 * np.sin(2 * th) + u[0],
            -(F[0] - (3 * np.sin(th) ** 2 - 1) - (thp - 1) ** 2) * z1 + u[1],
            -(F[1] - (3 * np.sin(th) ** 2 - 1) - (thp - 1) ** 2) * z2 + u[2],
        ]
    )
    return np.concatenate([[dth, dz1, dz2], WC**2 * acc])


def test_right_hand_side_is_eqs_1_and_2():
    """A x + B u + B_f f(x) equals eqs 1-2 (each term ~ω_c²·F·z; the split adds and removes
    ω_c²(3θ) and ω_c²F z, so agreement to a few eps of the largest term)."""
    plant = _beam()
    rng = np.random.default_rng(2)
    for _ in range(5):
        x = rng.normal(scale=[0.5, 0.01, 0.01, 2 * WC, 1e-3, 1e-3])
        f = rng.normal(size=2)
        ref = _eqs_1_2_in_seconds(x, f)
        scale = WC**2 * (F.max() * np.abs(x[1:3]).max() + 60 * np.abs(f).sum() + 3)
        assert np.abs(plant.derivative(x, f) - ref).max() <= 8 * EPS * scale


def test_linear_part_is_the_linearisation_at_rest():
    """A, B are eqs 5-6 in seconds; f vanishes at rest with its Jacobian (the orbital terms
    -(3 sin²θ - 1) - (θ' - 1)² cancel at θ = θ' = 0), so A is the Jacobian of eqs 1-2 there."""
    plant = _beam()
    A, B = plant.linear_part()
    n = 3
    np.testing.assert_array_equal(A[:n, n:], np.eye(n))
    np.testing.assert_allclose(np.diag(A[n:, :n]), -(WC**2) * np.array([3.0, *F]), rtol=1e-15)
    np.testing.assert_allclose(B[n:], WC**2 * plant.G, rtol=1e-15)
    x0 = np.zeros(6)
    np.testing.assert_array_equal(plant.nonlinear_force(x0, np.zeros(2)), np.zeros(3))
    Jx, Ju = plant.force_jacobian(x0, np.zeros(2))
    np.testing.assert_array_equal(Jx, np.zeros((3, 6)))
    assert Ju.shape == (3, 2) and not Ju.any()
    assert plant.force_matrix.shape == (6, 3) and plant.nonlinear
    # decoupled linear part: its 2x2 blocks are pitch libration √3 ω_c and the modes √F ω_c
    blocks = plant.modal_blocks
    np.testing.assert_allclose(blocks.frequencies**2, -np.diag(A[n:, :n]), rtol=2 * EPS)
    assert blocks.n_rigid == 0 and not blocks.damping.any()
    assert np.count_nonzero(A[n:, :n] - np.diag(np.diag(A[n:, :n]))) == 0


def test_force_jacobian_matches_central_differences():
    """Analytic ∂f/∂x against central differences with steps h_j = 1e-5·max(|x_j|, scale_j):
    truncation O(h²)·f''' and round-off eps·|f|/h, both below 1e-7 of the Jacobian's scale."""
    plant = _beam()
    rng = np.random.default_rng(5)
    scale = np.array([0.5, 0.01, 0.01, 2 * WC, 1e-3, 1e-3])
    xs = rng.normal(scale=scale, size=(4, 6))
    J, _ = plant.force_jacobian(xs, np.zeros((4, 2)))  # batched over the leading axis
    assert J.shape == (4, 3, 6)
    for x, Jx in zip(xs, J):
        fd = np.zeros((3, 6))
        for j in range(6):
            h = 1e-5 * max(abs(x[j]), scale[j])
            e = np.zeros(6)
            e[j] = h
            fd[:, j] = (plant.nonlinear_force(x + e) - plant.nonlinear_force(x - e)) / (2 * h)
        for i in range(3):  # rows have different scales (pitch vs modes)
            row = np.abs(Jx[i] * scale).max() + 1e-300
            assert np.all(np.abs((Jx[i] - fd[i]) * scale) <= 1e-7 * row), (i, Jx[i], fd[i])


def test_outputs_and_shapes():
    plant = _beam(length=120.0)
    names = [c.name for c in plant.outputs]
    assert names == [
        "pitch",
        "pitch_rate",
        "z1",
        "z2",
        "z1_rate",
        "z2_rate",
        "w_end",
        "w_mid",
        "state",
    ]
    units = {c.name: c.unit for c in plant.outputs}
    assert (units["pitch_rate"], units["z1"], units["w_end"]) == ("rad/s", "", "m")
    x = np.random.default_rng(0).normal(size=(5, 3, 6))  # time × case × state
    u = np.zeros((5, 3, 2))
    np.testing.assert_array_equal(plant.output("pitch_rate", x, u), x[..., 3])
    np.testing.assert_array_equal(plant.output("z2_rate", x, u), x[..., 5])
    np.testing.assert_allclose(
        plant.output("w_mid", x, u), 120.0 * (-1.2156) * x[..., 1], rtol=1e-15
    )
    np.testing.assert_array_equal(plant.output("state", x, u), x)
    assert plant.output("state", x, u).shape == (5, 3, 6)
    assert plant.nonlinear_force(x, u).shape == (5, 3, 3)
    assert plant.derivative(x, u).shape == (5, 3, 6)
    assert plant.n_inputs == 2 and [c.unit for c in plant.inputs] == ["N", "N"]


def test_initial_values_by_output_name():
    """Outputs that read one state coordinate double as initial values."""
    plant = _beam(length=120.0)
    assert plant.initial_values == (
        "state",
        "pitch",
        "pitch_rate",
        "z1",
        "z2",
        "z1_rate",
        "z2_rate",
    )
    x0 = plant.state_from(pitch=0.1, z2_rate=-0.02)
    np.testing.assert_array_equal(x0, [0.1, 0, 0, 0, 0, -0.02])
    with pytest.raises(ValueError, match=r"w_mid: not an initial value of BeamInOrbit"):
        plant.state_from(w_mid=1.0)
    with pytest.raises(ValueError, match=r"state: must have 6 entries"):
        plant.state_from(state=[1.0, 2.0])


def test_small_motion_follows_the_linear_part():
    """From θ = z = amp (rates zero), the nonlinear trajectory over one pitch period differs
    from the exact linear one (matrix exponential) by at most O(amplitude) relative (the
    leading remainder 2θ'z of the mode equations is quadratic, sin 2θ - 2θ cubic): 8e-6 at
    amp = 0.01 (checked < 1e-4) and shrinking at least in proportion to the amplitude (ratio
    <= 0.55 for half the amplitude, measured 0.25; DOP853 at rtol 1e-12 is far below these
    differences)."""
    from scipy.linalg import expm

    plant = _beam()
    A, _ = plant.linear_part()
    T = 2 * np.pi / (np.sqrt(3) * WC)
    rel = []
    for amp in (1e-2, 5e-3):
        x0 = np.array([amp, amp, amp, 0, 0, 0])
        sol = solve_ivp(
            lambda t, x: plant.derivative(x, np.zeros(2)),
            (0, T),
            x0,
            method="DOP853",
            rtol=1e-12,
            atol=1e-20,
            t_eval=[T],
        )
        rel.append(np.abs(sol.y[:3, -1] - (expm(T * A) @ x0)[:3]) / amp)
    assert rel[0].max() < 1e-4
    assert np.all(rel[1] <= 0.55 * rel[0])


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"orbit_rate": 0.0}, r"^orbit_rate: must be > 0"),
        ({"frequency_ratios": [3200.0, -1.0]}, r"^frequency_ratios: must be a 1-D list"),
        ({"actuators": {}}, r"^actuators: must be a non-empty"),
        ({"actuators": {"f1": [1.0, 2.0]}}, r"^f1: its column of G must have 1 \+ 2 = 3"),
        ({"actuators": {"f 1": [1.0, 2.0, 3.0]}}, r"channel name: must be an identifier"),
        ({"stations": {"tip": [1.0]}}, r"^w_tip: station shape values must have 2"),
        ({"length": -1.0}, r"^length: must be > 0"),
    ],
)
def test_bad_input_names_the_field(kwargs, message):
    args = {"orbit_rate": WC, "frequency_ratios": F, "actuators": {"f1": [1.0, 2.0, 3.0]}}
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        BeamInOrbit(**args)
    with pytest.raises(ValueError, match=r"^gyro: .*no output channel 'gyro'"):
        _beam().output_matrices("gyro")
