"""Three-axis flexible spacecraft in hybrid coordinates (issue 10 acceptance, seed 003 F3):
linearised about rest it is the free-free modal model's state space; restricted to rotation
about one axis its frequencies are those of the planar hybrid plant of the same finite-element
structure; total angular momentum is conserved through a large-angle tumble; the analytic
Jacobian of the nonlinear force matches central differences; bad input is named."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

from flexsat.dynamics import FlexibleSpacecraft, RigidSpacecraft
from flexsat.dynamics import attitude as att
from flexsat.dynamics.hybrid import ModalHybrid
from flexsat.structures.fem import Structure
from flexsat.structures.modal_model import ModalModel
from flexsat.structures.sections import Material, Section

EPS = np.finfo(float).eps
ALU = Material(E=70e9, rho=2700.0)
TUBE = Section.tube(0.02, 0.002)
HUB_INERTIA = (1.0, 1.5, 2.0)  # kg m², lumped at the hub node 0


def spokes(with_hub: bool, clamp_hub: bool, arms=4, n_el=3, length=1.0, hub_radius=0.1):
    """A hub node at the origin with ``arms`` tube spokes in the XY plane (3-D frames, a 0.5 kg
    tip mass each): symmetric under a turn of 2π/arms, so the centre of mass is the hub."""
    s = Structure("spokes")
    s.add_node(0, (0.0, 0.0, 0.0))
    nid = 1
    for a in range(arms):
        e = np.array([np.cos(2 * np.pi * a / arms), np.sin(2 * np.pi * a / arms), 0.0])
        prev = 0
        for k in range(1, n_el + 1):
            s.add_node(nid, (hub_radius + length * k / n_el) * e)
            s.add_frame(prev, nid, ALU, TUBE)
            prev, nid = nid, nid + 1
        s.add_mass(prev, 0.5)
    if with_hub:
        s.add_mass(0, 20.0, inertia=HUB_INERTIA)
    if clamp_hub:
        s.clamp(0)
    return s.assemble()


@pytest.fixture(scope="module")
def free_modal():
    asm = spokes(with_hub=True, clamp_hub=False)
    # every mode: the free-free model complete (6 rigid + 72 elastic)
    return ModalModel.from_fe(asm.modes(asm.n_dofs, rigid_body_modes=6), damping=0.01)


FORCES = [(3, "y"), (6, "z"), (9, "x")]


def check_linearisation(modal, plant, torque_node, forces):
    """The plant's linear part against the modal model's state space (see the test below)."""
    n = plant.n_modes
    inputs = [modal.torque_input(torque_node, a) for a in "xyz"] + [
        modal.force_input(node, axis) for node, axis in forces
    ]
    outputs = [
        (modal.displacement_output(node, axis), "displacement")
        for node, axis in plant.displacements
    ]
    outputs += [
        (modal.rotation_output(node, axis), "displacement") for node, axis in plant.rotations
    ]
    ss = modal.to_statespace(inputs=inputs, outputs=outputs)
    A, B = plant.linear_part()
    Lr = modal.participation[:6]
    P = np.zeros((2 * (n + 6), plant.nx))
    P[:6, 7:10], P[:6, 1:4] = Lr[:, :3], 2 * Lr[:, 3:]
    P[n + 6 : n + 12, 10:13], P[n + 6 : n + 12, 4:7] = Lr[:, :3], Lr[:, 3:]
    P[6 : n + 6, plant._eta] = np.eye(n)
    P[n + 12 :, plant._eta_dot] = np.eye(n)
    assert np.abs(P @ A - ss.A @ P).max() <= 1e-12 * np.abs(ss.A).max()
    assert np.abs(P @ B - ss.B).max() <= 1e-12 * np.abs(ss.B).max()
    # the node outputs are the elastic deflection: the modal model's rows on the elastic modes
    C = np.vstack(
        [
            plant.output_matrices(ch.name)[0]
            for ch in plant.outputs
            if ch.name.startswith(("displacement_", "rotation_"))
        ]
    )
    np.testing.assert_allclose(
        C[:, plant._eta], ss.C[:, 6 : n + 6], rtol=0, atol=1e-15 * np.abs(ss.C).max()
    )
    # and the nonlinear force is second order at rest: its Jacobian vanishes there
    Jx, Ju = plant.force_jacobian(plant.initial_state(1), np.zeros((1, B.shape[1])))
    assert np.abs(Jx).max() == 0 and np.abs(Ju).max() == 0


@pytest.mark.numerics
def test_linearised_about_rest_it_is_the_free_free_modal_state_space(free_modal):
    # The free-free modal model's state space [η_r, η_e, η̇_r, η̇_e] with inputs torques at the
    # CG (the hub node) and point forces, against the plant's linear part mapped by
    # η_r = L_t r + L_θ θ (θ = 2β_v the small rotation, L the rigid modes' participation: the
    # rigid shapes are R M_rr⁻¹ Lᵀ), η̇_r = L_t v + L_θ ω. Both are built from the same modes
    # by a few products, so they agree to round-off of the largest entry (ω_max² ~ 1e9):
    # 1e-12 relative. The torquers sit on the hub node (the CG): a torque there loads the
    # modes by the hub's rotational shapes, as in the modal model.
    plant = FlexibleSpacecraft(
        free_modal,
        forces=FORCES,
        displacements=[(3, "y"), (9, "z")],
        rotations=[(6, "z")],
        torque_node=0,
        translation=True,
    )
    assert plant.n_modes == 72 and np.allclose(free_modal.center_of_mass, 0.0, atol=1e-15)
    check_linearisation(free_modal, plant, 0, FORCES)


@pytest.mark.numerics
def test_the_eps_model_linearised_is_its_modal_state_space():
    # seed 003: the EPS with its first 45 elastic modes (0.5 % damping), torquers at the CG
    # node and the five point forces of the first actuator set (69X, 66X, 63X, 60X, 88X,
    # F13); the model's reference is its CG, which node 95 holds (to 1e-13 m)
    from flexsat.cases.eps import eps

    modal = eps().modal_model(45)
    forces = [(69, "x"), (66, "x"), (63, "x"), (60, "x"), (88, "x")]
    plant = FlexibleSpacecraft(
        modal,
        forces=forces,
        displacements=[(69, "x"), (88, "z")],
        rotations=[(69, "y")],
        torque_node=95,
        translation=True,
    )
    assert plant.n_modes == 45
    assert [c.name for c in plant.inputs][1:] == [
        "force_69X",
        "force_66X",
        "force_63X",
        "force_60X",
        "force_88X",
    ]
    check_linearisation(modal, plant, 95, forces)


@pytest.mark.numerics
def test_one_axis_frequencies_equal_the_planar_hybrid_plant_of_the_same_structure(free_modal):
    # The planar hybrid plant: the spokes cantilevered at the hub (hub clamped, no hub mass),
    # every cantilever mode kept, and the hub's inertia about z: M = [[I_hub + I_app, Lᵀ],
    # [L, I]], K = diag(0, ω²). Its modes with a hub rotation are the vehicle's modes with the
    # hub turning about z and not translating (the spoke pattern is symmetric under a quarter
    # turn, so those modes never move the hub) - exactly the modes of the free-free plant
    # restricted to rotation about z that turn the hub. With every mode kept both are exact
    # reductions of one FE model, so they agree to the eigen-solvers' accuracy,
    # ~eps·λ_max/λ = eps (ω_max/ω)² ≲ 1e-9 here (measured 5.7e-11 on the six turning modes,
    # 8.8 Hz to 2.0 kHz).
    clamped = spokes(with_hub=False, clamp_hub=True)
    cantilevered = ModalModel.from_fe(clamped.modes(clamped.n_dofs))
    hybrid = ModalHybrid(cantilevered, HUB_INERTIA[2], axis="z")
    lam, vec = eigh(hybrid.stiffness_matrix, hybrid.mass_matrix)
    turns = np.abs(vec[0]) > 1e-4 * np.abs(vec[0, 0])  # as for the plant below
    hybrid_w = np.sqrt(lam[turns][1:])  # the rigid rotation (λ = 0) first

    plant = FlexibleSpacecraft(free_modal)
    # restricted to rotation about z: coordinates (θ_z, η), M = [[J_zz, Δ_zᵀ], [Δ_z, I]]
    keep = np.r_[2, 3 : 3 + plant.n_modes]
    M = plant.rotation_mass[np.ix_(keep, keep)]
    K = np.diag(np.r_[0.0, plant.stiffness])
    lam, vec = eigh(K, M)
    hub_turn = np.r_[1.0, plant.modal.shapes[:, 0, 5]] @ vec  # rigid θ_z + elastic ψ_hub,z
    # a mode turns the hub by ≥ 1e-2 of the rigid rotation's turn (mass-normalised); the
    # quarter-turn-antisymmetric modes 2e-5 away in frequency (spokes alternating, hub still)
    # pick up ≤ 5e-7 of it from the eigen-solver's mixing of near-degenerate pairs
    turns = np.abs(hub_turn) > 1e-4 * np.abs(hub_turn[0])
    plant_w = np.sqrt(lam[turns][1:])
    assert plant_w.size == hybrid_w.size == 3 * 1 + 3  # in-plane bending of 3-element spokes
    np.testing.assert_allclose(plant_w, hybrid_w, rtol=1e-8)


def coupled_modal():
    """A free model whose elastic modes carry rotational participation (as a truncated or
    measured model does): the rigid–elastic coupling Δ and the gyroscopic Δᵀη̇ are live."""
    J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
    rigid = np.zeros((6, 6))
    rigid[:3, :3] = 300.0 * np.eye(3)
    rigid[3:, 3:] = J
    w = 2 * np.pi * np.array([0.4, 0.9, 1.7, 2.3])
    participation = np.zeros((4, 6))
    participation[:, 3:] = [[3.0, 0.5, 0.0], [0.0, 4.0, 1.0], [1.0, 0.0, 5.0], [2.0, 2.0, 2.0]]
    rng = np.random.default_rng(3)
    shapes = 0.1 * rng.standard_normal((4, 3, 6))
    return ModalModel(
        node_ids=[1, 2, 3],
        coordinates=[[2.0, 0, 0], [0, 3.0, 0], [0, 0, -1.0]],
        frequencies=w,
        damping=0.02,
        shapes=shapes,
        rigid_mass=rigid,
        participation=participation,
    )


@pytest.mark.numerics
def test_angular_momentum_is_conserved_through_a_large_angle_tumble():
    # No load, ~1 rad/s about all axes (the body turns through several revolutions in 20 s),
    # modes excited, 2 % damping (it dissipates energy but exerts no external moment), the
    # coupling Δ on. DOP853 on the full right-hand side at rtol = 1e-12, atol = 1e-13: its
    # global error over the run is a few hundred local errors of 1e-12 relative, bounded by
    # ~1e-10 of |H|; we allow 1e-9 (measured 4e-15: 1018 steps). With ζ = 0 the energy is
    # conserved too, ω × h doing no work (measured 3e-14 of E).
    for zeta in (0.02, 0.0):
        modal = coupled_modal()
        if zeta == 0.0:
            modal = ModalModel(
                **{**{f: getattr(modal, f) for f in modal.__dataclass_fields__}, "damping": 0.0}
            )
        plant = FlexibleSpacecraft(modal, forces=[(1, "y")], translation=True)
        x0 = plant.initial_state(1)[0]
        x0[:4] = att.principal_rotation_to_quaternion([1.0, 2.0, 2.0] / np.float64(3), 2.5)
        x0[4:7] = [0.9, -1.1, 0.7]
        x0[10:13] = [0.1, 0.0, -0.2]
        x0[plant._eta] = [0.05, -0.02, 0.03, 0.01]
        x0[plant._eta_dot] = [0.2, 0.1, -0.3, 0.1]
        u = np.zeros(4)
        sol = solve_ivp(
            lambda t, x, plant=plant, u=u: plant.rhs(x, u),
            (0.0, 20.0),
            x0,
            method="DOP853",
            rtol=1e-12,
            atol=1e-13,
            dense_output=True,
        )
        assert sol.success
        x = sol.sol(np.linspace(0.0, 20.0, 401)).T
        H = plant.momentum(x)
        _, phi = att.quaternion_to_principal_rotation(
            x[:, :4] / np.linalg.norm(x[:, :4], axis=-1, keepdims=True)
        )
        assert np.ptp(np.unwrap(phi)) > 1.0  # a large-angle motion
        assert np.abs(H - H[0]).max() <= 1e-9 * np.linalg.norm(H[0])
        E = plant.energy(x)
        if zeta == 0.0:
            assert np.abs(E - E[0]).max() <= 1e-9 * E[0]
        else:
            assert E[-1] < E[0] and np.all(np.diff(E) <= 1e-9 * E[0])


def central_jacobian(fun, z, h):
    cols = [(fun(z + h * e) - fun(z - h * e)) / (2 * h) for e in np.eye(z.size)]
    return np.stack(cols, -1)


@pytest.mark.numerics
def test_force_jacobian_matches_central_differences():
    # f is a polynomial of degree ≤ 3 in (x, u) (quaternion-rate products, ω × (Jω + Δᵀη̇),
    # Cᵀ(β) F): central differences err by h²/6 |f'''| ~ 1e-12 and round-off eps|f|/h ~ 1e-10
    # at h = 1e-6; tolerance 1e-8 of the largest entry
    plant = FlexibleSpacecraft(coupled_modal(), forces=[(1, "y"), (3, "x")], translation=True)
    rng = np.random.default_rng(7)
    x = rng.standard_normal(plant.nx)
    x[:4] /= np.linalg.norm(x[:4])
    u = rng.standard_normal(5)
    Jx, Ju = plant.force_jacobian(x, u)
    Jx_fd = central_jacobian(lambda z: plant.nonlinear_force(z, u), x, 1e-6)
    Ju_fd = central_jacobian(lambda z: plant.nonlinear_force(x, z), u, 1e-6)
    assert np.abs(Jx - Jx_fd).max() <= 1e-8 * np.abs(Jx).max()
    assert np.abs(Ju - Ju_fd).max() <= 1e-8 * max(np.abs(Ju).max(), 1.0)
    # vectorised over leading axes
    Jx2, _ = plant.force_jacobian(np.stack([x, x]), np.stack([u, u]))
    np.testing.assert_allclose(Jx2[1], Jx, rtol=1e-14, atol=1e-14 * np.abs(Jx).max())


@pytest.mark.numerics
@pytest.mark.numerics
def test_rigid_limit_is_eulers_equations(free_modal):
    # With the elastic coordinates at rest and free-free modes (Δ = 0 to round-off) a torque
    # leaves η at round-off and the rotation is the rigid body's (seed 003 F3 validation):
    # equal to the rigid plant's motion within the two DOP853 solutions' error (rtol 1e-11)
    plant = FlexibleSpacecraft(free_modal.truncate(12))
    rigid = RigidSpacecraft(plant.inertia)
    u = np.array([0.5, -0.2, 0.3])
    x0 = plant.initial_state(1)[0]
    x0[4:7] = [0.3, 0.1, -0.2]
    opts = dict(method="DOP853", rtol=1e-11, atol=1e-13)
    flex = solve_ivp(lambda t, x: plant.rhs(x, np.r_[u]), (0, 10), x0, **opts)
    rig = solve_ivp(lambda t, x: rigid.rhs(x, u), (0, 10), x0[:7], **opts)
    np.testing.assert_allclose(flex.y[:7, -1], rig.y[:, -1], rtol=0, atol=1e-9)
    # η's exact value is round-off (Δ ~ ε |J|); what DOP853 returns is its own error, at most
    # atol per accepted step (the BLAS kernel decides its sign and size: 1.7e-12 measured on
    # Haswell, 2e-17 on SkylakeX)
    assert np.abs(flex.y[plant._eta, -1]).max() <= opts["atol"] * flex.t.size


def test_channels_and_outputs(free_modal):
    plant = FlexibleSpacecraft(
        free_modal.truncate(20), forces=FORCES, displacements=[(3, "y")], rotations=[(6, "Z")]
    )
    assert [c.name for c in plant.inputs] == ["torque", "force_3Y", "force_6Z", "force_9X"]
    assert plant.n_inputs == 6 and plant.integrator == "exp_rk4"
    names = [c.name for c in plant.outputs]
    assert names == [
        "attitude",
        "rate",
        "euler123",
        "mrp",
        "displacement_3Y",
        "rotation_6Z",
        "elastic",
    ]
    x = plant.initial_state(2)
    x[:, :4] = att.dcm_to_quaternion(att.euler123_to_dcm([1.0, 1.0, 1.0]))
    x[:, plant._eta] = np.arange(plant.n_modes) * 1e-3
    u = np.zeros((2, 6))
    np.testing.assert_allclose(plant.output("euler123", x, u), np.ones((2, 3)), atol=1e-14)
    d = plant.output("displacement_3Y", x, u)
    assert d.shape == (2,)
    np.testing.assert_allclose(d, plant.modal.shapes[:, 3, 1] @ x[0, plant._eta], rtol=1e-14)
    with pytest.raises(ValueError, match="has no output channel 'tip'"):
        plant.output("tip", x, u)


def test_the_elastic_output_is_the_modal_state_and_a_reduced_model_reads_its_first_modes(
    free_modal,
):
    # ``elastic`` = [η, η̇] (2n wide), a linear output (C picks the state rows, no
    # feedthrough), so the compiled loop and the Python loop read the same numbers; and a
    # 20-mode plant and a 5-mode plant of one ModalModel share their first 5 modes exactly
    # (truncation keeps the leading modes), so a law designed on the 5-mode model reads the
    # first 5 of the 20-mode plant's η and the first 5 of its η̇
    big = FlexibleSpacecraft(free_modal, forces=FORCES, n_modes=20)
    small = FlexibleSpacecraft(free_modal, forces=FORCES, n_modes=5)
    assert dict((c.name, c.size) for c in big.outputs)["elastic"] == 40
    assert np.array_equal(big.modal.frequencies[:5], small.modal.frequencies)
    assert np.array_equal(big.modal.shapes[:5], small.modal.shapes)
    assert np.array_equal(big.torque_modal[:5], small.torque_modal)
    assert np.array_equal(big.force_modal[:5], small.force_modal)
    rng = np.random.default_rng(3)
    x = big.initial_state(2) + rng.standard_normal((2, big.nx)) * 1e-2
    u = rng.standard_normal((2, big.n_inputs))
    y = big.output("elastic", x, u)
    assert y.shape == (2, 40)
    np.testing.assert_array_equal(y, np.concatenate([x[:, big._eta], x[:, big._eta_dot]], 1))
    C, D, _ = big.output_matrices("elastic")
    np.testing.assert_array_equal(x @ C.T + u @ D.T, y)
    n = small.n_modes
    np.testing.assert_array_equal(
        np.concatenate([y[:, :n], y[:, 20 : 20 + n]], 1),
        small.output(
            "elastic",
            np.concatenate([x[:, :7], x[:, big._eta][:, :n], x[:, big._eta_dot][:, :n]], 1),
            u[:, : small.n_inputs],
        ),
    )


def test_the_reduced_plant_is_the_same_spacecraft_on_its_first_modes(free_modal):
    # a design model for a law on the first modes: same channels, inertia and input maps,
    # first n modes exactly; more modes than the plant has is refused
    big = FlexibleSpacecraft(
        free_modal,
        forces=FORCES,
        displacements=[(3, "x")],
        n_modes=20,
        torque_node=int(free_modal.node_ids[0]),
    )
    small = big.reduced(5)
    assert small.n_modes == 5
    assert [c.name for c in small.inputs] == [c.name for c in big.inputs]
    assert [c.name for c in small.outputs if c.name != "elastic"] == [
        c.name for c in big.outputs if c.name != "elastic"
    ]
    np.testing.assert_array_equal(small.inertia, big.inertia)
    np.testing.assert_array_equal(small.torque_modal, big.torque_modal[:5])
    np.testing.assert_array_equal(small.force_modal, big.force_modal[:5])
    np.testing.assert_array_equal(small.modal.shapes, big.modal.shapes[:5])
    with pytest.raises(ValueError, match="n_modes: at most the plant's 20 elastic modes"):
        big.reduced(21)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"forces": [(99, "x")]}, r"forces\[0\]: unknown node 99"),
        ({"forces": [(3, "w")]}, r"forces\[0\]: axis must be 'x', 'y' or 'z'"),
        ({"forces": [(3, "x"), (3, "X")]}, r"forces\[1\]: \(3, 'x'\) given twice"),
        ({"displacements": [3]}, r"displacements\[0\]: must be a pair"),
        ({"torque_node": 99}, r"torque_node: unknown node 99"),
    ],
)
def test_bad_input_is_named(free_modal, kwargs, message):
    with pytest.raises(ValueError, match=message):
        FlexibleSpacecraft(free_modal, **kwargs)


def test_a_cantilevered_model_is_refused():
    clamped = spokes(with_hub=False, clamp_hub=True)
    with pytest.raises(ValueError, match="modal: must be free-free"):
        FlexibleSpacecraft(ModalModel.from_fe(clamped.modes(6)))


@pytest.mark.numerics
def test_a_pd_slew_settles_and_the_momentum_balance_holds(free_modal):
    # A continuous quaternion PD slew of 90° about a skew axis on the spokes (first 4 elastic
    # modes, 1 % damping), torquers on the hub, plus a point force pulse at a tip: along the
    # DOP853 solution (rtol 1e-11) the inertial momentum changes by exactly the applied moment,
    # H(t) − H(0) = ∫ Cᵀ(β)(u + G F) dt (the integral carried in the state), to the
    # integrator's error, ≲ 1e-9 of the peak |H| (measured 1e-15); and the slew settles.
    from flexsat.control import QuaternionPD

    plant = FlexibleSpacecraft(free_modal, forces=[(3, "y")], torque_node=0, n_modes=4)
    J = plant.inertia
    target = att.principal_rotation_to_quaternion([1.0, 2.0, 2.0] / np.float64(3), np.pi / 2)
    # critically damped per axis, J θ'' + Kd θ' + (Kp/2) θ = J (θ'' + 2ω_n θ' + ω_n² θ) with
    # δβ ≈ θ/2: from π/2 the error is (1 + ω_n t) e^{−ω_n t} π/2 = 7e-6 rad at 15 s
    wn = 1.0  # rad/s, well below the first elastic mode (35 rad/s)
    law = QuaternionPD(Kp=2 * wn**2 * np.diag(J), Kd=2 * wn * np.diag(J), beta_target=target)
    G = plant.force_moments[:, 0]

    def rhs(t, z):
        x = z[:-3]
        u = law(t, {"attitude": x[None, :4], "rate": x[None, 4:7]}, {})[0][0]
        F = 5.0 * np.sin(np.pi * t) ** 2 if t < 1.0 else 0.0  # a smooth 1 s pulse, N
        moment = np.einsum(
            "ji,j->i", att.quaternion_to_dcm(x[:4] / np.linalg.norm(x[:4])), u + G * F
        )
        return np.concatenate([plant.rhs(x, np.r_[u, F]), moment])

    z0 = np.concatenate([plant.initial_state(1)[0], np.zeros(3)])
    sol = solve_ivp(
        rhs, (0.0, 15.0), z0, method="DOP853", rtol=1e-11, atol=1e-13, dense_output=True
    )
    z = sol.sol(np.linspace(0.0, 15.0, 151)).T
    H = plant.momentum(z[:, :-3])
    assert np.abs(H - H[0] - z[:, -3:]).max() <= 1e-9 * np.abs(H).max()
    err = law.error(z[-1, :4] / np.linalg.norm(z[-1, :4]))
    assert 2 * np.arccos(min(err[0], 1.0)) < 1e-4 and np.abs(z[-1, 4:7]).max() < 1e-4
