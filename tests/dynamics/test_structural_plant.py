"""StructuralPlant: any M, D, K structure as a plant with named force, torque and moment-pair
inputs and displacement, rotation and strain outputs (issue #10; seed 004 Eqs. 36-37)."""

import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp

from flexsat.dynamics.plant import Channel
from flexsat.dynamics.second_order import SecondOrderModel
from flexsat.dynamics.structural import Actuator, Sensor, StructuralPlant
from flexsat.structures.fem import Structure
from flexsat.structures.modal_model import ModalModel
from flexsat.structures.sections import Material, Section

EPS = np.finfo(float).eps


def _random_model(n=5, seed=3):
    """SPD M, general (non-symmetric) D, PSD K with one rigid mode."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, n))
    M = X @ X.T + n * np.eye(n)
    Y = rng.normal(size=(n, n - 1))
    K = Y @ Y.T  # rank n - 1: one rigid mode
    D = 0.05 * (K + M) + 0.01 * rng.normal(size=(n, n))
    return M, D, K


def _cantilever(n_el=10, length=1.0):
    """Clamped aluminium strip (beam2d, x axis), nodes 1..n_el+1; patch ends 3 and 5."""
    s = Structure("cantilever")
    for i in range(n_el + 1):
        s.add_node(i + 1, (length * i / n_el, 0.0, 0.0))
    mat = Material(E=68.9e9, rho=2700.0, nu=0.33)
    sec = Section.rectangle(0.003, 0.05)
    for i in range(1, n_el + 1):
        s.add_beam2d(i, i + 1, mat, sec)
    s.clamp(1)
    return s.assemble()


def test_channels_carry_names_units_and_kinds():
    M, D, K = _random_model()
    plant = StructuralPlant.from_second_order(
        SecondOrderModel(M, D, K, np.zeros((5, 1)), np.zeros((1, 5))),
        [
            Actuator("push", "force", 0),
            Actuator("twist", "torque", 4),
            Actuator("piezo", "moment_pair", (2, 3), gain=0.5, unit="V"),
        ],
        [
            Sensor("x0", "displacement", 0),
            Sensor("th4", "rotation", 4),
            Sensor("strain", "strain", (2, 3), gain=0.1),
            Sensor("v0", "displacement", 0, rate=True),
            Sensor("w4", "rotation", 4, rate=True),
        ],
    )
    assert [(c.name, c.unit) for c in plant.inputs] == [
        ("push", "N"),
        ("twist", "N*m"),
        ("piezo", "V"),
    ]
    assert [(c.name, c.unit) for c in plant.outputs[:-1]] == [
        ("x0", "m"),
        ("th4", "rad"),
        ("strain", ""),
        ("v0", "m/s"),
        ("w4", "rad/s"),
    ]
    assert plant.nx == 10 and plant.n_inputs == 3 and not plant.nonlinear
    np.testing.assert_array_equal(plant.model.B[:, 2], [0, 0, -0.5, 0.5, 0])
    C, Dy, Df = plant.output_matrices("strain")
    np.testing.assert_array_equal(C, [[0, 0, -0.1, 0.1, 0, 0, 0, 0, 0, 0]])
    assert Dy.shape == (1, 3) and not Dy.any() and Df is None
    np.testing.assert_array_equal(plant.output_matrices("w4")[0][0], np.eye(10)[9])
    # outputs and energy keep the leading time x case axes
    x = np.random.default_rng(0).normal(size=(7, 4, 10))
    assert plant.output("th4", x, np.zeros((7, 4, 3))).shape == (7, 4)
    np.testing.assert_array_equal(plant.output("th4", x, np.zeros((7, 4, 3))), x[..., 4])
    assert plant.energy(x).shape == (7, 4)
    assert plant.modal_blocks is None  # M ≠ I: not decoupled


def test_linear_part_is_the_second_order_first_order_form():
    """Against SecondOrderModel.first_order / to_statespace of the same M, D, K, B, C (one code
    path: equal to the last bit) and against an independent LU solve of M⁻¹[K D B] (both
    backward stable: agreement to cond(M)·n·eps relative to the largest entry)."""
    M, D, K = _random_model()
    B = np.zeros((5, 2))
    B[1, 0], B[3, 1], B[0, 1] = 1.0, 2.0, -2.0
    Cq = np.zeros((2, 5))
    Cq[0, 2] = 1.0
    Cv = np.zeros((2, 5))
    Cv[1, 4] = 1.0
    plant = StructuralPlant.from_second_order(
        SecondOrderModel(M, D, K, np.zeros((5, 1)), np.zeros((1, 5))),
        [Actuator("f1", "force", 1), Actuator("pair", "moment_pair", (0, 3), gain=2.0)],
        [Sensor("q2", "displacement", 2), Sensor("v4", "displacement", 4, rate=True)],
    )
    ref = SecondOrderModel(M, D, K, B, Cq, Cv)
    A_ref, B_ref, C_ref, _ = ref.first_order()
    A, Bx = plant.linear_part()
    np.testing.assert_array_equal(A, A_ref)
    np.testing.assert_array_equal(Bx, B_ref)
    C = np.vstack([plant.output_matrices(c.name)[0] for c in plant.outputs[:-1]])
    np.testing.assert_array_equal(C, C_ref)
    ss = ref.to_statespace()
    np.testing.assert_array_equal(A, ss.A)
    np.testing.assert_array_equal(Bx, ss.B)
    lu = np.linalg.solve(M, np.hstack([K, D, B]))
    bound = np.linalg.cond(M) * 5 * EPS * np.abs(lu).max()
    assert np.abs(A[5:, :5] + lu[:, :5]).max() <= bound
    assert np.abs(A[5:, 5:] + lu[:, 5:10]).max() <= bound
    assert np.abs(Bx[5:] - lu[:, 10:]).max() <= bound


def test_modal_model_plant_and_its_2x2_blocks():
    """From a cantilevered ModalModel: the influence vectors are the model's (force_input,
    torque_input, moment_pair and the collocated outputs), the first-order form is
    ModalModel.to_statespace's, and exp(hA) restricted to mode i's pair (η_i, η̇_i) is the
    exponential of its 2×2 block [[0, 1], [−ω², −2ζω]] and zero elsewhere (to the round-off of
    scipy's expm, whose scaling and squaring amplify eps: 100 eps of ‖e^{hA}‖)."""
    asm = _cantilever()
    modal = ModalModel.from_fe(asm.modes(6), damping=[0.01, 0.02, 0.005, 0.0, 0.01, 0.03])
    plant = StructuralPlant.from_modal_model(
        modal,
        [
            Actuator("tipforce", "force", 11, "y"),
            Actuator("tiptorque", "torque", 11, "z"),
            Actuator("patch", "moment_pair", (3, 5), "z", gain=2.5),
        ],
        [
            Sensor("tip", "displacement", 11, "y"),
            Sensor("slope", "rotation", 11, "z"),
            Sensor("patch_strain", "strain", (3, 5), "z", gain=0.4),
            Sensor("tip_rate", "displacement", 11, "y", rate=True),
        ],
    )
    cols = [
        modal.force_input(11, "y"),
        modal.torque_input(11, "z"),
        2.5 * modal.moment_pair(3, 5, "z"),
    ]
    rows = [
        (modal.displacement_output(11, "y"), "displacement"),
        (modal.rotation_output(11, "z"), "displacement"),
        (0.4 * modal.strain_output(3, 5, "z"), "displacement"),
        (modal.displacement_output(11, "y"), "velocity"),
    ]
    ss = modal.to_statespace(cols, rows)
    A, B = plant.linear_part()
    np.testing.assert_array_equal(A, ss.A)
    np.testing.assert_array_equal(B, ss.B)
    np.testing.assert_array_equal(
        np.vstack([plant.output_matrices(c.name)[0] for c in plant.outputs[:-1]]), ss.C
    )
    blocks = plant.modal_blocks
    np.testing.assert_array_equal(blocks.frequencies, modal.frequencies)
    np.testing.assert_allclose(blocks.damping, modal.damping, rtol=1e-15)
    assert blocks.n_rigid == 0
    h, n = 0.01, modal.n_modes
    E = scipy.linalg.expm(h * A)
    tol = 100 * EPS * np.abs(E).max()
    for i, (w, z) in enumerate(zip(blocks.frequencies, blocks.damping)):
        Ei = scipy.linalg.expm(h * np.array([[0.0, 1.0], [-w * w, -2 * z * w]]))
        idx = [i, n + i]
        assert np.abs(E[np.ix_(idx, idx)] - Ei).max() <= tol
        others = [j for j in range(2 * n) if j not in idx]
        assert np.abs(E[np.ix_(idx, others)]).max() <= tol


def test_moment_pair_is_the_fe_load_vector_and_bends_only_the_patch():
    """Seed 004 F1: a piezo pair is +a₁ at θ_b and −a₁ at θ_a, the finite-element load vector
    of two equal and opposite nodal moments; its modal form is Φᵀ f. Statically, Euler-Bernoulli
    elements carry the pair's constant moment exactly: the cantilever bends only between the
    patch ends (nodes 3-5): rotations 0 before, a constant after, curvature a₁/EI in between
    (K⁻¹ f to cond(K)·eps)."""
    asm = _cantilever()
    a1 = 0.7
    plant = StructuralPlant.from_fe(
        asm.M,
        asm.K,
        [Actuator("piezo", "moment_pair", ((3, "rz"), (5, "rz")), gain=a1)],
        [Sensor("strain", "strain", ((3, "rz"), (5, "rz")))],
        dofs=asm.dofs,
    )
    f = np.zeros(asm.n_dofs)
    f[asm.index(5, "rz")], f[asm.index(3, "rz")] = a1, -a1
    np.testing.assert_array_equal(plant.model.B[:, 0], f)
    np.testing.assert_array_equal(plant.model.Cq[0], f / a1)  # collocated: Fᵀ (seed 004 L45)
    modes = asm.modes(5)
    modal = ModalModel.from_fe(modes)
    m_plant = StructuralPlant.from_modal_model(
        modal, [Actuator("piezo", "moment_pair", (3, 5), "z", gain=a1)]
    )
    np.testing.assert_allclose(
        m_plant.model.B[:, 0],
        modes.shapes.T @ f,
        rtol=0,
        atol=1e-12 * np.abs(modes.shapes.T @ f).max(),
    )
    Kd = asm.K.toarray()
    q = np.linalg.solve(Kd, f)
    tol = np.linalg.cond(Kd) * EPS * np.abs(q).max()
    rz = {node: q[asm.index(node, "rz")] for node in range(2, 12)}
    uy = {node: q[asm.index(node, "uy")] for node in range(2, 12)}
    assert max(abs(rz[2]), abs(rz[3]), abs(uy[2]), abs(uy[3])) <= tol  # before the patch
    assert max(abs(rz[k] - rz[5]) for k in range(6, 12)) <= tol  # rigid after it
    EI = 68.9e9 * 0.003**3 * 0.05 / 12
    assert rz[5] == pytest.approx(a1 / EI * 0.2, rel=1e-10)  # curvature a₁/EI over 0.2 m


def test_energy_rate_is_input_power_less_dissipation():
    """dE/dt = q̇ᵀ(Bu) − q̇ᵀDq̇ along an exact trajectory: x(t) from the exponential of the
    augmented matrix [[A, Bu], [0, 0]] (u held), E(T) − E(0) against ∫P dt by 40-point
    Gauss-Legendre on [0, T] (T = 0.3 s ≈ 0.6 of the fastest period: quadrature error far below
    round-off; tolerance 1e-11 of the energy scale, from expm's ~1e-14 relative error)."""
    M, D, K = _random_model()
    D = 0.5 * (D + D.T)  # viscous damping: the dissipation q̇ᵀDq̇
    plant = StructuralPlant.from_second_order(
        SecondOrderModel(M, D, K, np.zeros((5, 1)), np.zeros((1, 5))),
        [Actuator("f", "force", 1), Actuator("pair", "moment_pair", (2, 4), gain=0.3)],
    )
    A, B = plant.linear_part()
    u = np.array([1.5, -2.0])
    aug = np.zeros((11, 11))
    aug[:10, :10], aug[:10, 10] = A, B @ u
    x0 = np.random.default_rng(1).normal(size=10)
    T = 0.3
    nodes, weights = np.polynomial.legendre.leggauss(40)
    ts = 0.5 * T * (nodes + 1)
    xs = np.array([(scipy.linalg.expm(t * aug) @ np.append(x0, 1.0))[:10] for t in ts])
    xT = (scipy.linalg.expm(T * aug) @ np.append(x0, 1.0))[:10]
    work = 0.5 * T * weights @ plant.power(xs, np.broadcast_to(u, (40, 2)))
    dE = plant.energy(xT) - plant.energy(x0)
    scale = plant.energy(x0) + abs(work)
    assert abs(dE - work) <= 1e-11 * scale
    assert abs(dE) > 1e-3 * scale  # the check is not vacuous
    # and the right-hand side is the plant's: solve_ivp at rtol 1e-12 lands on xT
    sol = solve_ivp(
        lambda t, x: plant.derivative(x, u), (0, T), x0, method="DOP853", rtol=1e-12, atol=1e-14
    )
    np.testing.assert_allclose(sol.y[:, -1], xT, rtol=0, atol=1e-10 * np.abs(xT).max())


def test_rigid_modes_are_counted():
    M = np.eye(3)
    K = np.diag([0.0, 4.0, 9.0])
    plant = StructuralPlant.from_second_order(
        SecondOrderModel(M, np.diag([0.0, 0.4, 0.6]), K, np.zeros((3, 1)), np.zeros((1, 3))),
        [Actuator("f", "force", 0)],
        [Sensor("x", "displacement", 0)],
    )
    blocks = plant.modal_blocks
    assert blocks.n_rigid == 1
    np.testing.assert_array_equal(blocks.frequencies, [0.0, 2.0, 3.0])
    np.testing.assert_allclose(blocks.damping, [0.0, 0.1, 0.1], rtol=1e-15)
    damped_rigid = StructuralPlant.from_second_order(
        SecondOrderModel(M, np.diag([0.1, 0.4, 0.6]), K, np.zeros((3, 1)), np.zeros((1, 3)))
    )
    assert damped_rigid.modal_blocks is None  # ζ undefined at ω = 0


def _model3():
    return SecondOrderModel(
        np.eye(3), np.zeros((3, 3)), np.eye(3), np.zeros((3, 1)), np.zeros((1, 3))
    )


@pytest.mark.parametrize(
    "inputs, outputs, message",
    [
        ([Actuator("f", "force", 0), Actuator("f", "torque", 1)], [], r"^f: duplicate input"),
        ([Actuator("f", "pull", 0)], [], r"^f: kind must be one of force, torque, moment_pair"),
        ([Actuator("f", "force", 3)], [], r"^f: dof 3 out of range"),
        ([Actuator("pz", "moment_pair", 1)], [], r"^pz: a moment_pair needs a pair of rotation"),
        ([Actuator("pz", "moment_pair", (1, 1))], [], r"^pz: the two dofs of a moment_pair must"),
        (
            [Actuator("f", "force", [1.0, 2.0])],
            [],
            r"^f: an influence vector must have shape \(3,\)",
        ),
        ([Actuator("f", "force", 0, gain=0.0)], [], r"^f: gain must be non-zero"),
        ([Actuator("f", "force", 0, gain=np.nan)], [], r"^f: gain: must be finite"),
        ([Actuator("f", "force", 0, unit="furlongs/fortnite")], [], r"^f: unit"),
        ([Actuator("f", "force", 0, axis="z")], [], r"^f: axis applies to modal coordinates"),
        ([Actuator("not valid", "force", 0)], [], r"channel name: must be an identifier"),
        ([], [Sensor("y", "stress", 0)], r"^y: kind must be one of displacement, rotation, strain"),
        ([], [Sensor("y", "strain", (0, "x"))], r"^y: unknown dof 'x'"),
        (
            [],
            [Sensor("y", "rotation", 0), Sensor("y", "rotation", 1, rate=True)],
            r"^y: duplicate output",
        ),
        (["force"], [], r"^inputs\[0\]: must be a Actuator"),
    ],
)
def test_bad_channel_specs_name_the_channel(inputs, outputs, message):
    with pytest.raises(ValueError, match=message):
        StructuralPlant.from_second_order(_model3(), inputs, outputs)


def test_bad_modal_specs_name_the_channel():
    modal = ModalModel.from_fe(_cantilever().modes(3))
    with pytest.raises(ValueError, match=r"^tip: node: unknown node 99"):
        StructuralPlant.from_modal_model(modal, [Actuator("tip", "force", 99, "y")])
    with pytest.raises(ValueError, match=r"^tip: give the axis"):
        StructuralPlant.from_modal_model(modal, [Actuator("tip", "force", 11)])
    with pytest.raises(ValueError, match=r"^pz: needs a node pair"):
        StructuralPlant.from_modal_model(modal, [Actuator("pz", "moment_pair", 3, "z")])
    with pytest.raises(ValueError, match=r"^s: node_b: must differ"):
        StructuralPlant.from_modal_model(modal, outputs=[Sensor("s", "strain", (3, 3), "z")])


def test_fixed_dofs_and_bad_constructor_arguments():
    asm = _cantilever()
    plant = StructuralPlant.from_fe(
        asm.M,
        asm.K,
        [Actuator("root", "moment_pair", ((1, "rz"), (3, "rz")))],
        dofs=asm.dofs,
        fixed=[(1, "rz")],
    )
    np.testing.assert_array_equal(plant.model.B[:, 0], np.eye(asm.n_dofs)[asm.index(3, "rz")])
    with pytest.raises(ValueError, match=r"^root: dof \(1, 'rz'\) is fixed"):
        StructuralPlant.from_fe(
            asm.M, asm.K, [Actuator("root", "torque", (1, "rz"))], dofs=asm.dofs, fixed=[(1, "rz")]
        )
    with pytest.raises(ValueError, match=r"^pz: both dofs of the moment_pair are fixed"):
        StructuralPlant.from_fe(
            asm.M,
            asm.K,
            [Actuator("pz", "moment_pair", ((1, "rz"), (1, "uy")))],
            dofs=asm.dofs,
            fixed=[(1, "rz"), (1, "uy")],
        )
    with pytest.raises(ValueError, match=r"^dofs: 3 labels for 30 coordinates"):
        StructuralPlant.from_fe(asm.M, asm.K, dofs=asm.dofs[:3])
    with pytest.raises(ValueError, match=r"^model: must be a SecondOrderModel"):
        StructuralPlant.from_second_order(np.eye(2))
    with pytest.raises(ValueError, match=r"^inputs: 0 size-1 channels for 1 columns"):
        StructuralPlant(_model3(), (), ())
    with pytest.raises(ValueError, match=r"^x: .*no output channel 'x'"):
        StructuralPlant(
            _model3()._replace(B=np.zeros((3, 0)), Cq=np.zeros((0, 3)), Cv=None, Dff=None), (), ()
        ).output_matrices("x")
    assert Channel("ok", "m").name == "ok"


def test_energy_is_the_quadratic_form_of_the_energy_matrix():
    """E = ½ xᵀ Q x, Q = blockdiag(K, M) (what the compiled loop evaluates per sample); to
    16 eps of the energy scale ½ |x|² ‖Q‖ n (two orders of summation of n_x products)."""
    M, D, K = _random_model()
    plant = StructuralPlant.from_second_order(
        SecondOrderModel(M, D, K, np.zeros((5, 1)), np.zeros((1, 5))), [Actuator("f", "force", 1)]
    )
    Q = plant.energy_matrix
    assert np.array_equal(Q, Q.T)
    x = np.random.default_rng(2).normal(size=(4, 10))
    scale = 0.5 * np.abs(Q).max() * (x**2).sum(axis=-1) * 10
    got = 0.5 * np.einsum("ci,ij,cj->c", x, Q, x)
    assert np.all(np.abs(got - plant.energy(x)) <= 16 * EPS * scale)


def test_the_energy_matrix_is_read_only():
    """Q = blockdiag(K, M) follows from the model: assigning it is an AttributeError naming
    the field."""
    M, D, K = _random_model()
    plant = StructuralPlant.from_second_order(
        SecondOrderModel(M, D, K, np.zeros((5, 1)), np.zeros((1, 5))),
        [Actuator("f", "force", 1)],
    )
    with pytest.raises(AttributeError, match=r"^energy_matrix: StructuralPlant"):
        plant.energy_matrix = np.eye(10)
