"""Positive position feedback on the Agrawal–Bang L structure (Agrawal & Bang 1996, Acta
Astronautica, §2, with the misprints that flexsat.control.ppf names repaired)."""

import numpy as np
import pytest
import scipy.linalg as sl

import control as ct
from flexsat.cases.agrawal_bang import agrawal_bang
from flexsat.control import (
    PPFBank,
    PPFController,
    PPFModel,
    PPFProblem,
    initial_second_moment,
    ppf_closed_loop,
    ppf_cost_gradient,
    ppf_feedback,
    ppf_stiffness,
)
from flexsat.control.lqg import zoh
from flexsat.sim import simulate
from flexsat.sim.config import SimConfig
from flexsat.units import UnitError, ureg

EPS = np.finfo(float).eps
M = 3  # modes retained (seed 004 L291)
ZETA_F = 0.1  # filter damping: not published; a common PPF choice


@pytest.fixture(scope="module")
def case():
    return agrawal_bang()


@pytest.fixture(scope="module")
def model(case):
    modal = case.modal_model(M)
    return PPFModel.from_pairs(modal.frequencies, modal.damping, case.piezo_pairs(M))


@pytest.fixture(scope="module")
def bank(model):
    return PPFBank.tuned(model, ZETA_F)


def first_mode_x0(amplitude=1e-3):
    """First flexible mode displaced, at rest (Tables 1–3 (a), amplitude not published)."""
    x0 = np.zeros(2 * M)
    x0[0] = amplitude
    return x0


def tip_problem(case, model, bank, w=(100.0, 100.0), Q_u=1.0, X0=None):
    """Eq. 35 as the state weight: ζ_t = T η, Q_s = Tᵀ Q̄ T on η."""
    X0 = initial_second_moment(first_mode_x0()) if X0 is None else X0
    return PPFProblem.from_output_weight(
        model, bank, case.tip_outputs(M), case.tip_weight(*w), Q_u, X0
    )


def central_difference(f, g, rel):
    cols = []
    for k in range(g.size):
        h = rel * abs(g[k])
        e = np.zeros(g.size)
        e[k] = h
        cols.append((np.asarray(f(g + e)) - np.asarray(f(g - e))) / (2 * h))
    return np.stack(cols, axis=-1)


def bisect(stable, lo, hi, n=80):
    """Boundary of a predicate true at lo and false at hi (relative width 2⁻⁸⁰ of hi − lo)."""
    assert stable(lo) and not stable(hi)
    for _ in range(n):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return 0.5 * (lo + hi)


# -- Eq. 35: the tip weight -------------------------------------------------------------------
def test_tip_weight_is_the_hessian_of_the_integrand(case):
    """Q̄ = ½ ∇²f for f = (y_1ᵗ)² + w_1 (l_2 α + y_2ᵗ)² + w_2 (α + β)² (Eq. 35).

    tests/cases/test_agrawal_bang.py::test_tip_outputs_and_weight checks ζᵀQ̄ζ = f at one
    random point, which does not fix Q̄; here every entry. f is quadratic, so the central
    second difference with h = 1 is exact but for round-off, 16 eps × |f| on the stencil."""
    w1, w2 = 500.0, 100.0
    l2 = case.beam2_length

    def f(z):
        y1, a, y2, b = z
        return y1**2 + w1 * (l2 * a + y2) ** 2 + w2 * (a + b) ** 2

    I4 = np.eye(4)
    H = np.array(
        [
            [
                (f(I4[i] + I4[j]) - f(I4[i] - I4[j]) - f(-I4[i] + I4[j]) + f(-I4[i] - I4[j])) / 4
                for j in range(4)
            ]
            for i in range(4)
        ]
    )
    scale = max(
        abs(f(s * I4[i] + t * I4[j]))
        for i in range(4)
        for j in range(4)
        for s in (-1, 1)
        for t in (-1, 1)
    )
    np.testing.assert_allclose(case.tip_weight(w1, w2), H / 2, rtol=0, atol=16 * EPS * scale)


# -- Eq. 8: the closed loop -------------------------------------------------------------------
def test_closed_loop_is_the_papers_block_matrix_and_the_plant_loop(case, model, bank):
    """Ā (Eq. 8, with the (4,1) block a_2 Ω_f C, spec OCR fix) equals the paper's blocks built
    from C = E Fᵀ Φ, a_1, a_2 (a_2 = 1: the sensor rows are Fᵀ Φ; a_1 = the pair ratio), and
    its poles are those of the plant in positive feedback with the bank (python-control).
    Tolerances: a few eps × the largest entry (the same products in another order) and
    the eigenvalue round-off, eps × ‖Ā‖ × the modes' condition number (≲ 1e3 here)."""
    pr = tip_problem(case, model, bank)
    g = np.linspace(50.0, 900.0, 9)
    A = pr.closed_loop_matrix(g)
    E, G = bank.E, np.diag(g)
    C = E @ model.sensors  # a_2 = 1
    a1 = model.ratio[0]
    assert np.allclose(model.ratio, a1, rtol=1e-14)  # one patch geometry and one gain pair
    Om, D = np.diag(model.omega**2), np.diag(2 * model.zeta * model.omega)
    Wf = np.diag(bank.omega_f.ravel() ** 2)
    Df = np.diag(2 * bank.zeta_f.ravel() * bank.omega_f.ravel())
    Z, I, Zf, If, Zmf = (np.zeros((M, M)), np.eye(M), np.zeros((9, 9)), np.eye(9), np.zeros((M, 9)))
    paper = np.block(
        [
            [Z, I, Zmf, Zmf],
            [-Om, -D, a1 * C.T @ G, Zmf],
            [Zmf.T, Zmf.T, Zf, If],
            [Wf @ C, Zmf.T, -Wf, -Df],
        ]
    )
    np.testing.assert_allclose(A, paper, rtol=0, atol=8 * EPS * np.abs(paper).max())

    plant = case.to_statespace(M)
    loop = ct.feedback(plant, PPFController(bank, g, dt=0.01).system, sign=+1)
    expect = np.sort_complex(np.linalg.eigvals(loop.A))
    got = np.sort_complex(pr.closed_loop_poles(g))
    np.testing.assert_allclose(got, expect, rtol=0, atol=1e3 * EPS * np.abs(A).max())


# -- Eq. 6: stability ---------------------------------------------------------------------------
def test_stiffness_boundary_is_the_stability_boundary_for_positive_gains(case, model, bank):
    """G = g I, g > 0: S loses definiteness and Ā loses stability at the same gain (spec §2
    [VERIFIED]; acceptance ±1 %). They coincide exactly: Ā x = 0 forces η̇ = ξ̇ = 0,
    ξ = E C_s η and S η = 0, so Ā is singular exactly when S is; the bisections agree to
    their width and the eigenvalue round-off (1e-9 relative)."""
    pr = tip_problem(case, model, bank)
    one = np.ones(9)
    g_S = bisect(lambda g: pr.stiffness_eigenvalues(g * one)[0] > 0, 0.0, 1e7)
    g_A = bisect(lambda g: pr.closed_loop_poles(g * one)[0].real < 0, 0.0, 1e7)
    assert g_A == pytest.approx(g_S, rel=1e-9)
    print(f"uniform positive gains: S boundary {g_S:.6g}, eigenvalue boundary {g_A:.6g}")
    below, above = pr.stability(0.99 * g_S * one), pr.stability(1.01 * g_S * one)
    assert below.decided_by == above.decided_by == "stiffness"
    assert below.stable and below.max_real_pole < 0
    assert not above.stable and not above.stiffness_positive and above.max_real_pole > 0


def test_negative_gain_instability_that_the_stiffness_test_misses(case, model, bank):
    """G = g I, g < 0: S stays positive definite (−a_1 a_2 Cᵀ G C adds stiffness) but the loop
    goes unstable (spec §2 (6) [DERIVED]: G enters the 'mass' matrix, so (6) needs G > 0);
    the report then lets the eigenvalues decide."""
    pr = tip_problem(case, model, bank)
    one = np.ones(9)
    g_neg = -bisect(lambda g: pr.closed_loop_poles(-g * one)[0].real < 0, 0.0, 1e7)
    print(f"uniform negative gains: unstable below g = {g_neg:.6g}")
    report = pr.stability(1.01 * g_neg * one)
    assert report.stiffness_positive and not report.gains_positive
    assert report.decided_by == "eigenvalues"
    assert not report.stable and report.max_real_pole > 0
    assert pr.stiffness_eigenvalues(1.01 * g_neg * one)[0] > pr.stiffness_eigenvalues(0 * one)[0]
    with pytest.raises(ValueError, match=r"^gains: the closed loop is unstable"):
        pr.cost(1.01 * g_neg * one)
    ok = pr.stability(0.99 * g_neg * one)
    assert ok.stable and ok.decided_by == "eigenvalues"


# -- Eqs. 10–14, 26: cost and gradients ---------------------------------------------------------
def printed_gradient(pr, g):
    """Eq. 13 as printed: tr[V P_s ∂Ā] + tr[V (P_u B − Gᵀ Q_u) ∂G] with u = −G x (G = −K),
    P_s, P_u of Eq. 12 and V of Eq. 14 solved here independently (scipy)."""
    A = pr.closed_loop_matrix(g)
    K = ppf_feedback(g, pr.E, M)
    Ps = sl.solve_continuous_lyapunov(A.T, -pr.Q_s)
    Pu = sl.solve_continuous_lyapunov(A.T, -K.T @ pr.Q_u @ K)
    V = sl.solve_continuous_lyapunov(A, -pr.X0)
    out = []
    for k in range(g.size):
        dK = ppf_feedback(np.eye(g.size)[k], pr.E, M)
        dG, dA = -dK, pr.B @ dK
        out.append(np.trace(V @ Ps @ dA) + np.trace(V @ (Pu @ pr.B + K.T @ pr.Q_u) @ dG))
    return np.array(out)


def test_repaired_gradient_matches_finite_differences_and_the_printed_one_does_not(
    case, model, bank
):
    """Q_u = 1 (acceptance; the paper's 1e-8 hides the control term). Gains ≈ 1e3, where the
    control term is about half of J. Central differences, relative step 1e-3: truncation
    h²J'''/6 and the Lyapunov round-off over h together ≈ 5e-7 here; acceptance 1e-5. The
    printed form's error is O(1) (spec: 2.28 on its notional model)."""
    pr = tip_problem(case, model, bank, Q_u=1.0)
    g = 1e3 * (1 + 0.5 * np.random.default_rng(4).random(9))
    assert pr.stability(g).stable
    J, dJ = pr.cost_and_gradient(g)
    assert J == pytest.approx(pr.cost(g), rel=1e-14)
    np.testing.assert_array_equal(pr.gradient(g), dJ)
    fd = central_difference(pr.cost, g, 1e-3)
    err = np.linalg.norm(dJ - fd) / np.linalg.norm(fd)
    printed = printed_gradient(pr, g)
    err_printed = np.linalg.norm(printed - fd) / np.linalg.norm(fd)
    print(f"gradient vs central differences: repaired {err:.2e}, printed {err_printed:.3g}")
    assert err <= 1e-5
    assert err_printed > 0.5


def test_stiffness_eigenvalue_sensitivities(case, model, bank):
    """Eq. 26 against central differences. S is linear in g, so the difference error is the
    eigenvalues' curvature h² (∂S)²/gap (gaps ≥ 290 here) plus round-off eps ‖S‖/h: ≈ 5e-11
    at step 1e-3 relative; acceptance 1e-7."""
    pr = tip_problem(case, model, bank)
    g = 1e3 * (1 + 0.5 * np.random.default_rng(5).random(9))
    lam = pr.stiffness_eigenvalues(g)
    assert np.all(np.diff(lam) > 0)
    dl = pr.stiffness_eigenvalue_gradients(g)
    assert dl.shape == (M, 9)
    fd = central_difference(pr.stiffness_eigenvalues, g, 1e-3)
    err = np.abs(dl - fd).max() / np.abs(fd).max()
    print(f"eigenvalue sensitivities vs central differences: {err:.2e}")
    assert err <= 1e-7
    # G > 0 only lowers the stiffness: every sensitivity is ≤ 0 (−r_i (φᵀ C_s[i])²)
    assert np.all(dl <= 0)


def test_cost_over_an_initial_condition_distribution(case, model, bank):
    """F10: J is linear in X₀, so J(E[x₀x₀ᵀ]) is the weighted mean of the single-x₀ costs
    (to the Lyapunov round-off, 1e-10 relative), and the gradient likewise; a (2m, 2m) moment
    starts the filters at rest, as a full one with zero filter rows does."""
    rng = np.random.default_rng(7)
    samples = rng.standard_normal((4, 2 * M)) * 1e-3
    weights = np.array([1.0, 2.0, 3.0, 4.0])
    g = np.full(9, 300.0)
    X0 = initial_second_moment(samples, weights)
    pr = tip_problem(case, model, bank, X0=X0)
    singles = [
        tip_problem(case, model, bank, X0=np.outer(x, x)).cost_and_gradient(g) for x in samples
    ]
    p = weights / weights.sum()
    J, dJ = pr.cost_and_gradient(g)
    assert J == pytest.approx(sum(pi * s[0] for pi, s in zip(p, singles)), rel=1e-10)
    np.testing.assert_allclose(
        dJ, sum(pi * s[1] for pi, s in zip(p, singles)), rtol=0, atol=1e-10 * np.abs(dJ).max()
    )
    full = sl.block_diag(X0, np.zeros((18, 18)))
    assert tip_problem(case, model, bank, X0=full).cost(g) == J


def test_kernels_take_a_leading_case_axis(case, model, bank):
    """Gains (n_cases, n_g): each case's cost, gradient, Ā and S equal the one-case results
    (the same operations per case: bitwise for Ā and S, 1e-12 for the Lyapunov solves, which
    run case by case through the same code)."""
    pr = tip_problem(case, model, bank)
    G = np.stack([np.full(9, 100.0), np.linspace(10.0, 2e3, 9)])
    J, dJ = ppf_cost_gradient(pr.A0, pr.B, pr.E, M, G, pr.Q_s, pr.Q_u, pr.X0)
    A = ppf_closed_loop(pr.A0, pr.B, ppf_feedback(G, pr.E, M))
    S = ppf_stiffness(model.omega, model.actuators, model.sensors, pr.E, G)
    for c, g in enumerate(G):
        Jc, dJc = pr.cost_and_gradient(g)
        assert J[c] == pytest.approx(Jc, rel=1e-12)
        np.testing.assert_allclose(dJ[c], dJc, rtol=1e-12)
        np.testing.assert_array_equal(A[c], pr.closed_loop_matrix(g))
        np.testing.assert_array_equal(S[c], pr.stiffness(g))


# -- F3: tuning -------------------------------------------------------------------------------
def test_single_mode_ppf_damps_most_when_tuned(case):
    """One mode (the first, pair 1), one filter, ω_f/ω swept over 0.5–2: the least-damped
    closed-loop pole is best damped near ω_f = ω (seed 004 L61; spec F3). At small gain the
    first-order shift of the structural pole, Re δ = −k ζ_f ω_f³ / |ω_f² − ω² + 2jζ_f ω_f ω|²
    (k = a_1 a_2 g), peaks at ω_f/ω ≈ 1 + ζ_f²/2 = 1.005; at 1 % of the stiffness limit the
    structural and filter poles coalesce near there. Grid step 0.0025."""
    modal = case.modal_model(1)
    p = case.piezo_pairs(1)[0]
    model = PPFModel(modal.frequencies, modal.damping, p.actuator[:, None], p.sensor[None, :])
    w = model.omega[0]
    g_limit = w**2 / (model.actuators[0, 0] * model.sensors[0, 0])  # S = ω² − k = 0
    ratios = np.linspace(0.5, 2.0, 601)

    def least_damping(frac):
        out = []
        for r in ratios:
            pr = PPFProblem(model, PPFBank([[r * w]], ZETA_F), np.eye(2), 0.0, np.eye(2))
            lam = pr.closed_loop_poles([frac * g_limit])
            out.append(np.min(-lam.real / np.abs(lam)))
        return np.array(out)

    theory = ratios**3 / ((ratios**2 - 1) ** 2 + 4 * ZETA_F**2 * ratios**2)
    for frac, lo, hi in ((1e-3, 1.0, 1.01), (1e-2, 0.99, 1.02)):
        d = least_damping(frac)
        best = ratios[np.argmax(d)]
        print(
            f"g = {frac:g} × stiffness limit: best ω_f/ω = {best:.4f}, damping "
            f"{d.max():.4f} (open loop {model.zeta[0]:.4f})"
        )
        assert lo <= best <= hi
        assert d.max() > model.zeta[0]
    assert ratios[np.argmax(theory)] == pytest.approx(1 + ZETA_F**2 / 2, abs=0.0025)


# -- the law in the simulation core -------------------------------------------------------------
def test_ppf_controller_in_the_simulation_core(case, model, bank):
    """agrawal_bang().plant(3), first mode displaced: with g_ij = 1e3 the tip rotation α + β
    dies out far faster than in open loop; the compiled and Python loops both equal the exact
    sampled-data loop (plant and ZOH-discretised bank propagated by matrix exponentials) to
    round-off over n_t steps; the continuous loop exp(Ā t) differs by the bank's input hold,
    O(dt): the error halves when the rate doubles."""
    plant = case.plant(M)
    g = np.full(9, 1e3)
    x0 = first_mode_x0()
    T = case.tip_outputs(M)
    pr = tip_problem(case, model, bank)
    Abar = pr.closed_loop_matrix(g)
    Cy = np.vstack([plant.output_matrices(f"y{i}")[0] for i in (1, 2, 3)])
    Ap, Bp = plant.linear_part()

    def run(rate, gains, **kw):
        law = PPFController(bank, gains, dt=1 / rate)
        res = simulate(
            plant,
            law,
            SimConfig(duration=20.0, control_rate=rate),
            initial_state=x0,
            record_states=True,
            **kw,
        )
        return law, res.dataset

    errors = {}
    for rate in (200.0, 400.0):
        law, ds = run(rate, g)
        X = ds["state"].values[0]
        n_t = X.shape[0]
        Phi_p, Gam_p = zoh(Ap, Bp, 1 / rate)
        Ac, Bc, Cc, _ = law.matrices
        Phi = np.block([[Phi_p, Gam_p @ Cc], [Bc @ Cy, Ac]])
        z, Z = np.r_[x0, np.zeros(18)], np.empty((n_t, 24))
        for k in range(n_t):
            Z[k], z = z, Phi @ z
        scale = np.abs(X).max()
        assert ds.attrs["engine"] == "compiled"
        np.testing.assert_allclose(X, Z[:, :6], rtol=0, atol=4 * n_t * EPS * scale)
        step = sl.expm(Abar / rate)
        z, err = np.r_[x0, np.zeros(18)], 0.0
        for k in range(n_t):
            err = max(err, np.abs(z[:6] - X[k]).max() / scale)
            z = step @ z
        errors[rate] = err
        if rate == 200.0:
            _, py = run(rate, g, compiled=False)
            np.testing.assert_allclose(py["state"].values[0], X, rtol=0, atol=4 * n_t * EPS * scale)
            closed = X
            t = ds["time"].values
    print(
        f"sampled vs continuous loop: {errors[200.0]:.3g} at 200 Hz, {errors[400.0]:.3g} at 400 Hz"
    )
    assert 1.6 < errors[200.0] / errors[400.0] < 2.4

    _, ds0 = run(200.0, np.zeros(9))
    rot = (closed[:, :M] @ T.T) @ [0, 1, 0, 1]
    rot0 = (ds0["state"].values[0][:, :M] @ T.T) @ [0, 1, 0, 1]
    late = t >= 15.0
    print(
        f"tip rotation envelope over 15–20 s: PPF {np.abs(rot[late]).max():.3g}, open loop "
        f"{np.abs(rot0[late]).max():.3g} rad"
    )
    # open loop: ζ_1 = 0.005 keeps exp(−ζω t) ≈ 0.6 of the start at 15 s; the loop's slowest
    # pole (−0.35 1/s) leaves exp(−5) ≈ 0.007
    assert np.abs(rot[late]).max() < 0.05 * np.abs(rot0[late]).max()


# -- units and bad input ----------------------------------------------------------------------
def test_frequencies_and_period_take_units():
    """ω_f in any frequency unit (Hz → 2π rad/s, one rounding of pint's factor: 1e-15), the
    control period in any time unit; a wrong dimension is refused naming the field."""
    bank = PPFBank(np.array([[1.0, 2.0]]) * ureg("Hz"), 0.1)
    np.testing.assert_allclose(bank.omega_f, [[2 * np.pi, 4 * np.pi]], rtol=1e-15)
    assert PPFController(bank, [1.0, 2.0], dt="5 ms").dt == pytest.approx(5e-3, rel=1e-15)
    with pytest.raises(UnitError, match=r"^omega_f: incompatible units"):
        PPFBank(np.array([[1.0]]) * ureg("m"), 0.1)


def test_bad_input_is_named(case, model, bank):
    pr = tip_problem(case, model, bank)
    with pytest.raises(ValueError, match=r"^gains: must have 9 = n_actuators × n_tuned"):
        pr.cost(np.ones(8))
    with pytest.raises(ValueError, match=r"^gains: must be finite"):
        pr.gradient(np.r_[np.ones(8), np.nan])
    with pytest.raises(ValueError, match=r"^gains: must have 9"):
        PPFController(bank, np.ones(3), dt=0.01)
    with pytest.raises(ValueError, match=r"^zeta_f: must be >= 0"):
        PPFBank.tuned(model, -0.1)
    with pytest.raises(ValueError, match=r"^n_tuned: must be 1 to 3, got 4"):
        PPFBank.tuned(model, 0.1, 4)
    with pytest.raises(ValueError, match=r"^omega_f: must be > 0"):
        PPFBank([[1.0, 0.0]], 0.1)
    with pytest.raises(ValueError, match=r"^omega_f: must have shape \(n_actuators, n_tuned\)"):
        PPFBank([1.0, 2.0], 0.1)
    with pytest.raises(ValueError, match=r"^zeta_f: must be a scalar or have the shape"):
        PPFBank([[1.0, 2.0]], [0.1, 0.1, 0.1])
    X0 = initial_second_moment(first_mode_x0())
    bad = X0.copy()
    bad[0, 1] = 1.0
    with pytest.raises(ValueError, match=r"^X0: must be symmetric"):
        tip_problem(case, model, bank, X0=bad)
    with pytest.raises(ValueError, match=r"^X0: must be positive semi-definite"):
        tip_problem(case, model, bank, X0=-X0)
    with pytest.raises(ValueError, match=r"^X0: must be 6 × 6 .* or 24 × 24"):
        tip_problem(case, model, bank, X0=np.eye(5))
    with pytest.raises(ValueError, match=r"^Q_u: must be 3 × 3"):
        tip_problem(case, model, bank, Q_u=np.eye(2))
    with pytest.raises(ValueError, match=r"^output_weight: must be 4 × 4"):
        PPFProblem.from_output_weight(model, bank, case.tip_outputs(M), np.eye(3), 1.0, X0)
    with pytest.raises(ValueError, match=r"^bank: has filters for 2 actuators"):
        PPFProblem(model, PPFBank(np.ones((2, 3)), 0.1), np.eye(6), 1.0, X0)
    # mismatched numbers of actuators, sensors and modes
    with pytest.raises(ValueError, match=r"^sensors: must have shape \(n_a, m\) = \(3, 3\)"):
        PPFModel(model.omega, model.zeta, model.actuators, model.sensors[:2])
    with pytest.raises(ValueError, match=r"^actuators: must have shape \(m, n_a\) = \(3, n_a\)"):
        PPFModel(model.omega, model.zeta, model.actuators[:2], model.sensors)
    with pytest.raises(ValueError, match=r"^zeta: must be a scalar or one ratio per mode"):
        PPFModel(model.omega, [0.1, 0.1], model.actuators, model.sensors)
    # a_2 = 0, non-collocated pairs, a pair with a_1 a_2 < 0
    S = model.sensors.copy()
    S[1] = 0
    with pytest.raises(
        ValueError, match=r"^sensors\[1\]: pair 2 has a zero sensor row \(a_2 = 0\)"
    ):
        PPFModel(model.omega, model.zeta, model.actuators, S)
    with pytest.raises(ValueError, match=r"^actuators\[:, 0\]: pair 1 is not collocated"):
        PPFModel(model.omega, model.zeta, model.actuators[:, [1, 0, 2]], model.sensors)
    B = model.actuators.copy()
    B[:, 2] *= -1
    with pytest.raises(ValueError, match=r"^actuators\[:, 2\]: pair 3 is not collocated"):
        PPFModel(model.omega, model.zeta, B, model.sensors)
    with pytest.raises(ValueError, match=r"^omega: must be > 0"):
        PPFModel(np.r_[0.0, model.omega[1:]], model.zeta, model.actuators, model.sensors)
    with pytest.raises(ValueError, match=r"^weights: must be 1 non-negative"):
        initial_second_moment(first_mode_x0(), [1.0, 1.0])
