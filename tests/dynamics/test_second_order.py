"""SecondOrderModel: conversions agree with the models of #2 and #3, modal form and truncation
preserve the input-output behaviour they claim to, bad inputs name their field."""

import numpy as np
import pytest
import scipy.linalg

from flexsat.cases import nps
from flexsat.dynamics.second_order import SecondOrderModel
from flexsat.structures.modal_model import ModalModel


def freqresp(A, B, C, D, w):
    """C (jωI − A)⁻¹ B + D."""
    return C @ np.linalg.solve(1j * w * np.eye(A.shape[0]) - A, B) + D


def random_model(n=6, m=2, p=3, seed=0, proportional=True, rigid=False):
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((n, n))
    M = X @ X.T + n * np.eye(n)
    Y = rng.standard_normal((n, n))
    K = Y @ Y.T + np.eye(n)
    if rigid:
        v = rng.standard_normal(n)
        P = np.eye(n) - np.outer(v, v) / (v @ v)
        K = P @ K @ P  # K v = 0: one rigid mode
    if proportional:
        D = 0.01 * M + 0.002 * K
    else:
        Z = rng.standard_normal((n, n))
        D = 0.05 * (Z @ Z.T)
    return SecondOrderModel(
        M,
        D,
        K,
        rng.standard_normal((n, m)),
        rng.standard_normal((p, n)),
        rng.standard_normal((p, n)),
    )


@pytest.fixture(scope="module")
def nps_case():
    return nps()


# ------------------------------------------------------------------------------------------------
# conversions from the models of #2 and #3
def test_from_hub_appendage_matches_the_model_state_space(tamu_model):
    model = SecondOrderModel.from_hub_appendage(tamu_model)
    A, B, C, D = model.first_order()
    ref = tamu_model.to_statespace()
    np.testing.assert_allclose(A, ref.A, rtol=0, atol=1e-9 * np.abs(ref.A).max())
    np.testing.assert_allclose(B, ref.B, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(C, ref.C)
    np.testing.assert_allclose(model.frequencies()[1:], tamu_model.frequencies(), rtol=1e-10)
    assert model.frequencies()[0] == 0.0


def test_from_hybrid_reproduces_nps_eq18_and_round_trips(nps_case):
    model = SecondOrderModel.from_hybrid(nps_case.modal_model(), nps_case.hub_inertia_value)
    A, B, C, D = model.first_order()
    A18, B18, C18, _ = nps_case.statespace_eq18()
    assert np.abs(A - A18).max() < 1e-12 * np.abs(A18).max()
    assert np.abs(B - B18).max() < 1e-12 * np.abs(B18).max()
    np.testing.assert_array_equal(C, C18)
    # Eq. 18's M⁻¹K is not symmetric: from_statespace needs the mass matrix
    M, Cd, K = nps_case.hybrid_matrices()
    with pytest.raises(ValueError, match="give the mass matrix M"):
        SecondOrderModel.from_statespace(nps_case.to_statespace())
    back = SecondOrderModel.from_statespace(nps_case.to_statespace(), M=M)
    np.testing.assert_allclose(back.K, K, atol=1e-10 * np.abs(K).max())
    np.testing.assert_allclose(back.D, Cd, atol=1e-12)
    np.testing.assert_allclose(back.frequencies()[1:], nps_case.system_frequencies(), rtol=1e-10)


def test_from_hybrid_extra_inputs_and_outputs(nps_case):
    modal = nps_case.modal_model()
    f = modal.force_input(nps_case.reflector_node, "y")
    rows = [(np.eye(7)[0], "displacement"), (np.concatenate([[0.0], f]), "velocity")]
    model = SecondOrderModel.from_hybrid(
        modal, nps_case.hub_inertia_value, inputs=[f], outputs=rows
    )
    assert (model.n_inputs, model.n_outputs) == (2, 2)
    np.testing.assert_array_equal(model.B[1:, 1], f)
    np.testing.assert_array_equal(model.Cv[1, 1:], f)
    with pytest.raises(ValueError, match=r"inputs\[0\]"):
        SecondOrderModel.from_hybrid(modal, 1.0, inputs=[np.ones(3)])
    with pytest.raises(ValueError, match=r"outputs\[0\]"):
        SecondOrderModel.from_hybrid(modal, 1.0, outputs=[(np.ones(7), "acceleration")])


def test_from_modal_model_matches_its_state_space(tamu_model):
    modal = ModalModel.from_hub_appendage(tamu_model)
    node = int(modal.node_ids[-1])
    inputs = [modal.force_input(node, "y")]
    outputs = [
        (modal.displacement_output(node, "y"), "displacement"),
        (modal.rotation_output(node, "z"), "velocity"),
    ]
    model = SecondOrderModel.from_modal_model(modal, inputs, outputs)
    ref = modal.to_statespace(inputs, outputs)
    for got, want in zip(model.first_order(), (ref.A, ref.B, ref.C, ref.D)):
        np.testing.assert_allclose(got, want, rtol=1e-14, atol=0)
    assert model.is_modal()


def test_statespace_round_trip_identity_mass():
    rng = np.random.default_rng(3)
    n = 5
    Y = rng.standard_normal((n, n))
    model = SecondOrderModel(
        np.eye(n),
        0.1 * np.eye(n),
        Y @ Y.T,
        rng.standard_normal((n, 2)),
        rng.standard_normal((1, n)),
        rng.standard_normal((1, n)),
        rng.standard_normal((1, 2)),
    )
    back = SecondOrderModel.from_statespace(model.to_statespace())
    for name in ("M", "D", "K", "B", "Cq", "Cv", "Dff"):
        np.testing.assert_allclose(getattr(back, name), getattr(model, name), atol=1e-14)
    sys = model.to_statespace()
    assert sys.state_labels[0] == "q[0]" and sys.state_labels[n] == "q_dot[0]"


# ------------------------------------------------------------------------------------------------
# modal form, truncation, discretisation
@pytest.mark.parametrize("proportional", [True, False])
def test_modal_form_preserves_the_transfer_function(proportional):
    model = random_model(proportional=proportional, rigid=True)
    modal = model.modal()
    assert modal.is_modal()
    np.testing.assert_allclose(
        np.diag(modal.K), model.frequencies() ** 2, atol=1e-12 * model.frequencies().max() ** 2
    )
    Dm = modal.D
    off = np.abs(Dm - np.diag(np.diag(Dm))).max()
    if proportional:
        assert off < 1e-12 * np.abs(Dm).max()
    else:
        assert off > 1e-3 * np.abs(Dm).max()
    for w in (0.05, 0.7, 3.0):
        np.testing.assert_allclose(
            freqresp(*modal.first_order(), w), freqresp(*model.first_order(), w), rtol=1e-9
        )
    w, Phi = model.modes()
    np.testing.assert_allclose(Phi.T @ model.M @ Phi, np.eye(6), atol=1e-12)
    assert w[0] == 0.0


def test_diagonal_damping_drops_the_coupling_only():
    model = random_model(proportional=False)
    full, diag = model.modal(), model.modal(diagonal_damping=True)
    np.testing.assert_array_equal(np.diag(diag.D), np.diag(full.D))
    assert np.count_nonzero(diag.D - np.diag(np.diag(diag.D))) == 0


def test_truncate_and_residualize():
    model = random_model(n=8, m=1, p=2, seed=5)
    full = model.truncate(8)
    for w in (0.1, 1.0):
        np.testing.assert_allclose(
            freqresp(*full.first_order(), w), freqresp(*model.first_order(), w), rtol=1e-9
        )
    cut = model.truncate(3)
    res = model.truncate(3, method="residualize")
    assert cut.n_dof == res.n_dof == 3
    np.testing.assert_allclose(np.diag(cut.K), model.frequencies()[:3] ** 2, rtol=1e-10)
    dc = freqresp(*model.first_order(), 0.0)
    assert np.abs(freqresp(*res.first_order(), 0.0) - dc).max() < 1e-10 * np.abs(dc).max()
    assert np.abs(freqresp(*cut.first_order(), 0.0) - dc).max() > 1e-3 * np.abs(dc).max()
    with pytest.raises(ValueError, match="n_modes"):
        model.truncate(9)
    with pytest.raises(ValueError, match="method"):
        model.truncate(2, method="balanced")
    with pytest.raises(ValueError, match="rigid"):  # two rigid modes, one would be dropped
        SecondOrderModel(
            np.eye(2), np.zeros((2, 2)), np.zeros((2, 2)), np.ones(2), np.ones((1, 2))
        ).truncate(1, method="residualize")


def test_discretize_zoh_is_the_matrix_exponential(tamu_model):
    model = SecondOrderModel.from_hub_appendage(tamu_model).truncate(4)
    dt = 1 / 75
    sysd = model.discretize(dt)
    A, B, _, _ = model.first_order()
    assert sysd.dt == dt
    np.testing.assert_allclose(sysd.A, scipy.linalg.expm(A * dt), atol=1e-12)
    blk = scipy.linalg.expm(np.block([[A, B], [np.zeros((1, A.shape[0] + 1))]]) * dt)
    np.testing.assert_allclose(sysd.B, blk[: A.shape[0], A.shape[0] :], atol=1e-14)
    assert model.discretize(dt, method="tustin").dt == dt
    with pytest.raises(ValueError, match="dt"):
        model.discretize(0.0)


# ------------------------------------------------------------------------------------------------
# validation: one test per rule
GOOD = dict(M=np.eye(2), D=np.zeros((2, 2)), K=np.diag([0.0, 4.0]), B=np.ones((2, 1)), Cq=np.eye(2))


@pytest.mark.parametrize(
    "change, match",
    [
        (dict(M=[[1.0, 0.5], [0.0, 1.0]]), "M: must be symmetric"),
        (dict(M=np.diag([1.0, -1.0])), "M: must be positive definite"),
        (dict(M=np.ones((2, 3))), "M: must be a non-empty square"),
        (dict(K=np.diag([1.0, -1.0])), "K: must be positive semi-definite"),
        (dict(K=[[0.0, 1.0], [0.0, 0.0]]), "K: must be symmetric"),
        (dict(K=np.eye(3)), "K: must have shape"),
        (dict(D=np.eye(3)), "D: must have shape"),
        (dict(B=np.ones((3, 1))), "B: must have shape"),
        (dict(Cq=np.ones((1, 3))), "Cq: must have shape"),
        (dict(Cv=np.ones((1, 2))), "Cv: must have shape"),
        (dict(Dff=np.ones((2, 2))), "Dff: must have shape"),
        (dict(D=[[np.nan, 0.0], [0.0, 0.0]]), "D: must be finite"),
        (dict(M="1 kg"), "M: must be a number in SI units"),
    ],
)
def test_bad_inputs_name_the_field(change, match):
    with pytest.raises(ValueError, match=match):
        SecondOrderModel(**{**GOOD, **change})


def test_from_statespace_rejects_other_realisations():
    A = np.array([[0.0, 1.0], [-1.0, -0.1]])
    T = np.array([[1.0, 1.0], [0.0, 1.0]])
    with pytest.raises(ValueError, match=r"sys: not in \[q, q̇\] form"):
        SecondOrderModel.from_statespace(
            (T @ A @ np.linalg.inv(T), T @ [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]])
        )
    with pytest.raises(ValueError, match="n_dof"):
        SecondOrderModel.from_statespace((np.eye(3), np.ones((3, 1)), np.ones((1, 3)), [[0.0]]))
    import control

    with pytest.raises(ValueError, match="continuous-time"):
        SecondOrderModel.from_statespace(control.ss(A, [[0.0], [1.0]], [[1.0, 0.0]], 0, 0.1))


def test_model_is_read_only():
    model = SecondOrderModel(**GOOD)
    with pytest.raises(ValueError):
        model.K[0, 0] = 1.0
    assert "n_dof=2" in repr(model)


@pytest.mark.parametrize("field", ["M", "D", "K", "B", "Cq", "Cv", "Dff"])
def test_complex_matrices_are_refused_not_made_real(field):
    # a complex entry would lose its imaginary part in the float conversion (silently, before)
    good = {**GOOD, "Cv": np.zeros((2, 2)), "Dff": np.zeros((2, 1))}
    bad = np.asarray(good[field], dtype=complex)
    bad.flat[0] += 0.5j
    with pytest.raises(
        ValueError,
        match=rf"^{field}: must be a real number, got a complex "
        r"value \(largest \|imaginary part\| 0\.5, which would "
        r"be dropped\)",
    ):
        SecondOrderModel(**{**good, field: bad})
    # a complex array whose imaginary parts are all 0 is the real array it holds
    exact = SecondOrderModel(**{**good, field: np.asarray(good[field], dtype=complex)})
    np.testing.assert_array_equal(getattr(exact, field), getattr(SecondOrderModel(**good), field))


def test_stiff_model_keeps_its_low_elastic_modes():
    """A chain with stiffness spread 1e12 (a stiff FE model's λ_max/λ_1): the low elastic
    modes stay elastic, the rigid mode of the free chain is exactly 0."""
    n = 6
    k = np.array([1.0, 1e12, 1e12, 1e12, 1e12])
    K = np.zeros((n, n))
    for i, ki in enumerate(k):
        K[i : i + 2, i : i + 2] += ki * np.array([[1.0, -1.0], [-1.0, 1.0]])
    model = SecondOrderModel(np.eye(n), np.zeros((n, n)), K, np.ones(n), np.eye(n))
    w, _ = model.modes()
    # the soft spring between two masses, the rest nearly rigid: ω₁² ≈ k₁ (1/1 + 1/5); eigh
    # resolves λ₁ to n·ε·λ_max absolute, so ω₁ to ½ n ε λ_max / λ₁ relative (≈ 2e-3)
    lam_max = model.frequencies()[-1] ** 2
    np.testing.assert_allclose(
        w[1], np.sqrt(1.2), rtol=0.5 * n * np.finfo(float).eps * lam_max / 1.2
    )
    assert w[0] == 0.0
