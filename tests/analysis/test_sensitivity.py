"""Eigen and SVD sensitivities: Junkins & Kim 1990 (Att. 5 of Junkins, Pollock & Rahman 1990),
Eqs. 15-27 and 40-44.

Every analytic derivative is checked against central finite differences at 1e-7 relative on
seeded random well-conditioned cases; second derivatives against central differences of the
analytic first derivatives."""

import numpy as np
import pytest

from flexsat.analysis.sensitivity import (
    condition_number_derivatives,
    eig_derivatives,
    eigensolve,
    eigenvector_condition_derivatives,
    modal_derivatives,
    svd_derivatives,
)

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels

H = 1e-5  # central-difference step
RTOL = 1e-7


def rel(analytic, fd):
    return np.linalg.norm(np.asarray(analytic) - fd) / np.linalg.norm(fd)


def central(fun, p0, h=H):
    """Stack of (fun(p + h e_k) − fun(p − h e_k)) / 2h over k."""
    out = []
    for k in range(p0.size):
        e = np.zeros_like(p0)
        e[k] = h
        out.append((fun(p0 + e) - fun(p0 - e)) / (2 * h))
    return np.array(out)


# -- random parameterised pencils ----------------------------------------------------------------
class Pencil:
    """A(p) = A0 + Σ p_k A_k + ½ Σ p_k p_l A_kl, likewise B(p); non-symmetric, real or complex."""

    def __init__(self, seed, n=5, P=3, complex_=False, generalized=True):
        rng = np.random.default_rng(seed)

        def draw(*shape):
            x = rng.normal(size=shape)
            return x + 1j * rng.normal(size=shape) if complex_ else x

        self.A0, self.Ak = draw(n, n), draw(P, n, n)
        self.Akl = draw(P, P, n, n)
        self.Akl = self.Akl + self.Akl.transpose(1, 0, 2, 3)
        self.generalized = generalized
        self.B0 = 3 * np.eye(n) + 0.3 * draw(n, n)
        self.Bk = 0.3 * draw(P, n, n)
        self.Bkl = 0.3 * draw(P, P, n, n)
        self.Bkl = self.Bkl + self.Bkl.transpose(1, 0, 2, 3)
        self.p0 = 0.1 * rng.normal(size=P)

    def A(self, p):
        return (
            self.A0
            + np.einsum("k,kij->ij", p, self.Ak)
            + 0.5 * np.einsum("k,l,klij->ij", p, p, self.Akl)
        )

    def dA(self, p):
        return self.Ak + np.einsum("l,klij->kij", p, self.Akl)

    def B(self, p):
        if not self.generalized:
            return None
        return (
            self.B0
            + np.einsum("k,kij->ij", p, self.Bk)
            + 0.5 * np.einsum("k,l,klij->ij", p, p, self.Bkl)
        )

    def dB(self, p):
        return self.Bk + np.einsum("l,klij->kij", p, self.Bkl) if self.generalized else None

    def derivs(self, p, order=1):
        kw = {}
        if order == 2:
            kw = dict(d2A=self.Akl, d2B=self.Bkl if self.generalized else None)
        return eig_derivatives(self.A(p), self.dA(p), self.B(p), self.dB(p), order=order, **kw)


def _aligned(ref, new):
    """Permutation of new's eigenvalues onto ref's, and ± signs aligning the eigenvectors."""
    order = np.array([np.argmin(np.abs(new.eigenvalues - lam)) for lam in ref.eigenvalues])
    assert np.unique(order).size == order.size
    sign = np.sign(np.sum(ref.right.conj() * new.right[:, order], axis=0).real)
    return order, sign


def _well_conditioned(d):
    lam = d.eigenvalues
    gap = np.abs(lam[:, None] - lam[None, :]) + np.eye(lam.size) * 1e9
    assert gap.min() > 0.05, "test case not well separated; pick another seed"
    assert np.linalg.cond(d.right) < 1e3


CASES = [
    dict(seed=1),
    dict(seed=2, complex_=True),
    dict(seed=3, generalized=False),
    dict(seed=4, n=6, P=2, complex_=True, generalized=False),
]


@pytest.mark.parametrize("case", CASES)
def test_eigen_first_derivatives_match_central_differences(case):
    pen = Pencil(**case)
    d = pen.derivs(pen.p0, order=2)
    _well_conditioned(d)

    def at(p, what):
        new = pen.derivs(p)
        order, sign = _aligned(d, new)
        return {
            "lam": new.eigenvalues[order],
            "phi": new.right[:, order] * sign,
            "psi": new.left[:, order] * sign,
            "dlam": new.eigenvalue_gradient[:, order],
            "dphi": new.right_gradient[:, :, order] * sign,
        }[what]

    assert rel(d.eigenvalue_gradient, central(lambda p: at(p, "lam"), pen.p0)) < RTOL
    assert rel(d.right_gradient, central(lambda p: at(p, "phi"), pen.p0)) < RTOL
    assert rel(d.left_gradient, central(lambda p: at(p, "psi"), pen.p0)) < RTOL
    # second order (Eq. 44): central differences of the analytic first derivatives
    assert rel(d.eigenvalue_hessian, central(lambda p: at(p, "dlam"), pen.p0)) < RTOL
    assert rel(d.right_hessian, central(lambda p: at(p, "dphi"), pen.p0)) < RTOL
    # symmetry of the second derivatives in (k, l)
    assert np.allclose(d.right_hessian, d.right_hessian.transpose(1, 0, 2, 3), atol=1e-10)


def test_normalisation_and_biorthogonality_eqs_40_41():
    pen = Pencil(seed=1)
    A, B = pen.A(pen.p0), pen.B(pen.p0)
    d = pen.derivs(pen.p0)
    phi, psi, lam = d.right, d.left, d.eigenvalues
    assert np.allclose(np.einsum("ji,jk,ki->i", phi, B, phi), 1, atol=1e-12)  # plain transpose
    assert np.allclose(psi.T @ B @ phi, np.eye(5), atol=1e-12)
    assert np.allclose(psi.T @ A @ phi, np.diag(lam), atol=1e-11)
    assert np.allclose(A.T @ psi, B.T @ psi * lam, atol=1e-11)  # left: λ Bᵀψ = Aᵀψ
    # the derivative of the normalisation vanishes
    B_k = pen.dB(pen.p0)
    dn = 2 * np.einsum("kji,jl,li->ki", d.right_gradient, (B + B.T) / 2, phi) + np.einsum(
        "ji,kjl,li->ki", phi, B_k, phi
    )
    assert np.abs(dn).max() < 1e-11
    # ∂Φ/∂p = Φ C^k
    assert np.allclose(np.einsum("ij,kjl->kil", phi, d.coefficients), d.right_gradient)
    assert d.eigenvalue_hessian is None and d.right_hessian is None


def test_single_matrix_derivative_is_one_parameter():
    pen = Pencil(seed=1)
    d = eig_derivatives(pen.A(pen.p0), pen.Ak[0])
    assert d.eigenvalue_gradient.shape == (1, 5) and d.right_gradient.shape == (1, 5, 5)


def test_eigenvalue_derivative_of_a_known_matrix():
    """A(p) = [[p, 1], [0, 2]]: λ = p, 2; ∂λ/∂p = 1, 0."""
    d = eig_derivatives([[0.5, 1.0], [0.0, 2.0]], [[1.0, 0.0], [0.0, 0.0]])
    order = np.argsort(d.eigenvalues.real)
    assert np.allclose(d.eigenvalue_gradient[0, order], [1.0, 0.0], atol=1e-14)


# -- symmetric modal problem, Nelson's method ----------------------------------------------------
def _spd(rng, n, shift):
    X = rng.normal(size=(n, n))
    return X @ X.T + shift * np.eye(n)


def _sym(rng, *shape):
    X = rng.normal(size=shape)
    return X + np.swapaxes(X, -1, -2)


def _modal_case(seed=5, n=6, P=3, rigid=False):
    rng = np.random.default_rng(seed)
    K0, M0 = _spd(rng, n, 1.0), _spd(rng, n, n)
    if rigid:  # one rigid-body mode: K r = 0 along r
        r = rng.normal(size=n)
        Pr = np.eye(n) - np.outer(r, r) / (r @ r)
        K0 = Pr @ K0 @ Pr
    Kk, Mk = 0.3 * _sym(rng, P, n, n), 0.1 * _sym(rng, P, n, n)
    if rigid:
        Kk = np.einsum("ij,kjl,lm->kim", Pr, Kk, Pr)
    return K0, M0, Kk, Mk, 0.1 * rng.normal(size=P)


@pytest.mark.parametrize("rigid", [False, True])
def test_nelson_modal_derivatives_match_central_differences(rigid):
    K0, M0, Kk, Mk, p0 = _modal_case(rigid=rigid)
    K = lambda p: K0 + np.einsum("k,kij->ij", p, Kk)  # noqa: E731
    M = lambda p: M0 + np.einsum("k,kij->ij", p, Mk)  # noqa: E731
    d = modal_derivatives(K(p0), M(p0), Kk, Mk)
    lam = d.eigenvalues
    assert np.diff(lam).min() > 0.01 * lam.max()

    def at(p, what):
        e = modal_derivatives(K(p), M(p), Kk, Mk)
        sign = np.sign(np.sum(d.modes * e.modes, axis=0))
        return {"lam": e.eigenvalues, "phi": e.modes * sign}[what]

    assert rel(d.eigenvalue_gradient, central(lambda p: at(p, "lam"), p0)) < RTOL
    assert rel(d.mode_gradient, central(lambda p: at(p, "phi"), p0)) < RTOL
    flexible = slice(1, None) if rigid else slice(None)
    assert np.allclose(
        d.frequency_gradient[:, flexible],
        d.eigenvalue_gradient[:, flexible] / (2 * d.frequencies[flexible]),
    )
    if rigid:
        assert d.frequencies[0] == 0 and np.all(np.isnan(d.frequency_gradient[:, 0]))
        assert np.allclose(d.eigenvalue_gradient[:, 0], 0, atol=1e-12)


def test_nelson_agrees_with_the_modal_expansion_and_selects_modes():
    K0, M0, Kk, Mk, p0 = _modal_case(seed=6)
    nelson = modal_derivatives(K0, M0, Kk, Mk, modes=[4, 1])
    assert list(nelson.indices) == [4, 1]
    full = eig_derivatives(K0, Kk, M0, Mk)  # Att. 5 Eqs. 42-43 with ψ = φ, B = M
    for col, _mode in enumerate([4, 1]):
        i = int(np.argmin(np.abs(full.eigenvalues - nelson.eigenvalues[col])))
        s = np.sign(full.right[:, i].real @ nelson.modes[:, col])
        assert np.allclose(
            full.eigenvalue_gradient[:, i].real, nelson.eigenvalue_gradient[:, col], rtol=1e-10
        )
        assert np.allclose(
            s * full.right_gradient[:, :, i].real,
            nelson.mode_gradient[:, :, col],
            rtol=1e-8,
            atol=1e-12,
        )


# -- SVD, Att. 5 Eqs. 15-27 ----------------------------------------------------------------------
class MatrixPath:
    """Φ(p) = Φ0 + Σ p_k Φ_k + ½ Σ p_k p_l Φ_kl (complex or real, any shape)."""

    def __init__(self, seed, shape=(5, 5), P=3, complex_=True):
        rng = np.random.default_rng(seed)

        def draw(*s):
            x = rng.normal(size=s)
            return x + 1j * rng.normal(size=s) if complex_ else x

        self.F0, self.Fk, self.Fkl = draw(*shape), draw(P, *shape), draw(P, P, *shape)
        self.Fkl = self.Fkl + self.Fkl.transpose(1, 0, 2, 3)
        self.p0 = 0.1 * rng.normal(size=P)

    def F(self, p):
        return (
            self.F0
            + np.einsum("k,kij->ij", p, self.Fk)
            + 0.5 * np.einsum("k,l,klij->ij", p, p, self.Fkl)
        )

    def dF(self, p):
        return self.Fk + np.einsum("l,klij->kij", p, self.Fkl)


SVD_CASES = [
    dict(seed=11),
    dict(seed=12, shape=(6, 4)),
    dict(seed=13, shape=(3, 5)),
    dict(seed=14, complex_=False),
    dict(seed=15, shape=(7, 3), complex_=False),
]


@pytest.mark.parametrize("case", SVD_CASES)
def test_svd_derivatives_match_central_differences(case):
    path = MatrixPath(**case)
    d = svd_derivatives(path.F(path.p0), path.dF(path.p0), path.Fkl, order=2)
    sig = d.singular_values
    assert np.diff(sig).max() < -0.05 * sig[0] and sig[-1] > 0.05 * sig[0]
    r = sig.size

    def at(p, what):
        U, s, Vh = np.linalg.svd(path.F(p))
        V = Vh.conj().T[:, :r]
        U = U[:, :r]
        # the gauge of svd_derivatives: V_iᴴ ∂V_i = 0, i.e. V_i(p0)ᴴ V_i(p) real positive
        phase = np.diag(d.V[:, :r].conj().T @ V)
        phase = phase / np.abs(phase)
        if what == "dsig":
            return svd_derivatives(path.F(p), path.dF(p)).singular_value_gradient
        return {"sig": s, "U": U / phase, "V": V / phase}[what]

    assert rel(d.singular_value_gradient, central(lambda p: at(p, "sig"), path.p0)) < RTOL
    assert rel(d.U_gradient, central(lambda p: at(p, "U"), path.p0)) < RTOL
    assert rel(d.V_gradient, central(lambda p: at(p, "V"), path.p0)) < RTOL
    # corrected Eq. 27
    assert rel(d.singular_value_hessian, central(lambda p: at(p, "dsig"), path.p0)) < RTOL
    assert np.allclose(d.singular_value_hessian, d.singular_value_hessian.transpose(1, 0, 2))


def test_second_order_singular_values_by_second_differences():
    """The paper's own check (report body L266): second finite differences of σ(p)."""
    path = MatrixPath(seed=21)
    d = svd_derivatives(path.F(path.p0), path.dF(path.p0), path.Fkl, order=2)
    h = 1e-4
    s = lambda p: np.linalg.svd(path.F(p), compute_uv=False)  # noqa: E731
    e0, e1 = np.array([h, 0, 0]), np.array([0, h, 0])
    fd00 = (s(path.p0 + e0) - 2 * s(path.p0) + s(path.p0 - e0)) / h**2
    fd01 = (
        s(path.p0 + e0 + e1) - s(path.p0 + e0 - e1) - s(path.p0 - e0 + e1) + s(path.p0 - e0 - e1)
    ) / (4 * h**2)
    assert rel(d.singular_value_hessian[0, 0], fd00) < 1e-6
    assert rel(d.singular_value_hessian[0, 1], fd01) < 1e-6


def test_selected_indices_only_need_to_be_distinct():
    # σ = 3, 1, 1 (repeated middle-bottom pair) but σ_1 = 3 is simple
    Phi = np.diag([3.0, 1.0, 1.0])
    dPhi = np.zeros((1, 3, 3))
    dPhi[0, 0, 0] = 1.0
    d = svd_derivatives(Phi, dPhi, indices=[0])
    assert d.singular_value_gradient.shape == (1, 1)
    assert d.singular_value_gradient[0, 0] == pytest.approx(1.0)
    with pytest.raises(ValueError, match=r"^singular values: .*1 and 2 are repeated"):
        svd_derivatives(Phi, dPhi)


@pytest.mark.parametrize("case", [dict(seed=31), dict(seed=32, shape=(6, 4), complex_=False)])
def test_condition_number_derivatives_match_central_differences(case):
    path = MatrixPath(**case)
    kappa, grad, hess = condition_number_derivatives(
        path.F(path.p0), path.dF(path.p0), path.Fkl, order=2
    )
    assert kappa == pytest.approx(np.linalg.cond(path.F(path.p0)), rel=1e-12)
    fd = central(lambda p: np.array(np.linalg.cond(path.F(p))), path.p0)
    assert rel(grad, fd) < RTOL
    fd2 = central(lambda p: condition_number_derivatives(path.F(p), path.dF(p))[1], path.p0)
    assert rel(hess, fd2) < RTOL


def test_modal_matrix_condition_number_chain():
    """Att. 5 Eq. 46 chain: SVD of the normalised modal matrix ← eigenvector derivatives."""
    pen = Pencil(seed=1)
    kappa, grad, hess, eig = eigenvector_condition_derivatives(
        pen.A(pen.p0), pen.dA(pen.p0), pen.B(pen.p0), pen.dB(pen.p0), pen.Akl, pen.Bkl, order=2
    )
    cond = lambda p: np.array(np.linalg.cond(eigensolve(pen.A(p), pen.B(p))[1]))  # noqa: E731
    assert kappa == pytest.approx(float(cond(pen.p0)), rel=1e-12)
    assert rel(grad, central(cond, pen.p0)) < RTOL
    g = lambda p: eigenvector_condition_derivatives(  # noqa: E731
        pen.A(p), pen.dA(p), pen.B(p), pen.dB(p)
    )[1]
    assert rel(hess, central(g, pen.p0)) < RTOL
    assert eig.right.shape == (5, 5)


# -- bad inputs ----------------------------------------------------------------------------------
def test_repeated_and_defective_eigenvalues_are_refused():
    with pytest.raises(ValueError, match=r"^eigenvalues: eigenvalue 0 and 1 are repeated"):
        eig_derivatives(np.eye(2), np.ones((2, 2)))
    with pytest.raises(ValueError, match="repeated"):  # Jordan block: defective
        eig_derivatives([[0.0, 1.0], [0.0, 0.0]], np.ones((2, 2)))
    with pytest.raises(ValueError, match=r"^eigenvalues: .*repeated"):
        modal_derivatives(np.diag([1.0, 1.0, 2.0]), np.eye(3), np.ones((3, 3)))
    # repeated modes elsewhere do not matter when only a simple mode is asked for
    d = modal_derivatives(np.diag([1.0, 1.0, 2.0]), np.eye(3), np.eye(3), modes=2)
    assert d.eigenvalue_gradient[0, 0] == pytest.approx(1.0)


def test_degenerate_svd_is_refused():
    with pytest.raises(ValueError, match=r"^singular values: σ_1 = 0 is zero"):
        svd_derivatives(np.diag([1.0, 0.0]), np.ones((2, 2)))
    with pytest.raises(ValueError, match=r"^singular values: singular value 0 and 1 are repeated"):
        svd_derivatives(np.eye(2), np.ones((2, 2)))
    with pytest.raises(ValueError, match=r"^Phi: a condition number needs at least 2"):
        condition_number_derivatives(np.ones((3, 1)), np.ones((3, 1)))


@pytest.mark.parametrize(
    "call,message",
    [
        (lambda: eig_derivatives(np.ones((2, 3)), np.ones((2, 3))), r"^A: must be square"),
        (lambda: eig_derivatives(np.diag([1.0, 2.0]), np.ones((3, 3))), r"^dA: must have shape"),
        (lambda: eig_derivatives([[1.0, np.nan], [0, 2]], np.ones((2, 2))), r"^A: must be finite"),
        (lambda: eig_derivatives("A", np.ones((2, 2))), r"^A: must be a numeric matrix"),
        (
            lambda: eig_derivatives(np.diag([1.0, 2.0]), np.ones((2, 2)), np.zeros((2, 2))),
            r"^B: must be non-singular",
        ),
        (
            lambda: eig_derivatives(np.diag([1.0, 2.0]), np.ones((2, 2)), np.eye(3)),
            r"^B: must have the shape of A",
        ),
        (
            lambda: eig_derivatives(np.diag([1.0, 2.0]), np.ones((2, 2)), dB=np.ones((3, 2, 2))),
            r"^dB: expected 1 parameters",
        ),
        (
            lambda: eig_derivatives(np.diag([1.0, 2.0]), np.ones((2, 2)), order=3),
            r"^order: must be 1 or 2",
        ),
        (
            lambda: eig_derivatives(
                np.diag([1.0, 2.0]), np.ones((2, 2)), d2A=np.ones((1, 1, 2, 2))
            ),
            r"^d2A: second derivatives are used only with order=2",
        ),
        (
            lambda: eig_derivatives(np.diag([1.0, 2.0]), np.ones((2, 2)), gap_rtol=-1),
            r"^gap_rtol: must be finite and >= 0",
        ),
        (
            lambda: eig_derivatives(
                np.diag([1.0, 2.0]), np.ones((2, 2, 2)), order=2, d2A=np.ones((2, 3, 2, 2))
            ),
            r"^d2A: must have shape|^d2A: the two parameter axes",
        ),
        (
            lambda: modal_derivatives([[1.0, 2.0], [0.0, 1.0]], np.eye(2), np.eye(2)),
            r"^K: must be symmetric",
        ),
        (
            lambda: modal_derivatives(np.diag([1.0, 2.0]), -np.eye(2), np.eye(2)),
            r"^M: must be positive definite",
        ),
        (
            lambda: modal_derivatives(np.diag([1.0, 2.0]), np.eye(2), np.eye(2), modes=[5]),
            r"^modes: must lie in 0",
        ),
        (
            lambda: modal_derivatives(np.diag([1.0, 2.0]), np.eye(2), np.eye(2) * 1j),
            r"^dK: must be real",
        ),
        (
            lambda: svd_derivatives(np.diag([2.0, 1.0]), np.ones((2, 2)), indices=[2]),
            r"^indices: must lie in 0",
        ),
        (lambda: svd_derivatives(np.zeros((0, 2)), np.ones((2, 2))), r"^Phi: must be a non-empty"),
    ],
)
def test_bad_inputs_name_the_field(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_plain_transpose_normalisation_impossible_is_refused():
    """A complex eigenvector with φᵀφ = 0 cannot be scaled to φᵀBφ = 1 (Eq. 41)."""
    v = np.array([1.0, 1j]) / np.sqrt(2)  # vᵀv = 0
    w = np.array([1.0, -1j]) / np.sqrt(2)
    Q = np.column_stack([v, w])
    A = Q @ np.diag([1.0, 2.0]) @ np.linalg.inv(Q)
    with pytest.raises(ValueError, match=r"^eigenvalues: eigenvector .* φᵀBφ ≈ 0"):
        eigensolve(A)
