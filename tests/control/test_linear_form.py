"""The compiled-loop form of the linear laws (issue #10): the LinearLaw arrays are checked, the
reference loop run_linear_law is the recursion it states, and every linear law's linear_form
reproduces the law called sample by sample (run_controller) over random measurements, batched.

Tolerances: a law without internal state sums a few products per command, so the two paths
differ by a few ulps of the largest summand (4 eps × (|u_ff| + Σ|D||e|)). An estimator law is
shifted by a deterministic sequence s (linear_form.absorb_affine); each step's rounding (a few
ulps of the largest of |x̂|, |s| times the gains) is carried by the compensator's own
dynamics, spectral radius < 1 here, so the bound is 4 eps × n_t × (max|u| + max|u_ff|), u_ff
being the shifted feedforward, the largest summand of the command.
"""

import numpy as np
import pytest

from flexsat.cases import nps
from flexsat.control import (
    PD,
    Controller,
    LinearLaw,
    LQGController,
    LyapunovRegulator,
    LyapunovTracker,
    frequency_shaped_lqr,
    kalman,
    run_linear_law,
)
from flexsat.control.linear_form import absorb_affine, run_controller
from flexsat.maneuvers import SmoothBangBang

EPS = np.finfo(float).eps
NC, NT, DT = 5, 300, 0.05
TIMES = DT * np.arange(NT)
RN = np.diag([1e-7, 5e-6])  # seed 001 Eq. 44


@pytest.fixture(scope="module")
def rng():
    return np.random.default_rng(20261202)


@pytest.fixture(scope="module")
def reference():
    """Per-case slews (one angle per case) ending inside the run."""
    return SmoothBangBang(np.linspace(0.2, 0.6, NC), 10.0, duration=5.0, alpha=0.2)


@pytest.fixture(scope="module")
def plant():
    """The NPS 14-state model with the paper's weights (seed 001 L375, as tests/test_lqg)."""
    sys = nps().to_statespace()
    w = np.full(14, 0.1)
    w[[0, 7]] = 1.0
    w[[1, 2, 8, 9]] = 0.5
    return sys.A, sys.B, sys.C, np.diag(w)


def empty_law(n_t=3, nk=1, p=2, m=1, **over):
    arrays = dict(
        Ak=np.zeros((1, 1, nk, nk)),
        Bk=np.zeros((1, 1, nk, p)),
        Ck=np.zeros((1, 1, m, nk)),
        Dk=np.zeros((1, 1, m, p)),
        y_ref=np.zeros((n_t, 1, p)),
        u_ff=np.zeros((n_t, 1, m)),
        K0=None,
        reads=tuple(f"y{i}" for i in range(p)),
        writes=tuple(f"u{i}" for i in range(m)),
        read_sizes=(1,) * p,
        write_sizes=(1,) * m,
    )
    arrays.update(over)
    return LinearLaw(**arrays)


# -- the arrays and the reference loop -----------------------------------------------------------
@pytest.mark.parametrize(
    "field,value,rule",
    [
        ("Ak", np.zeros((1, 1, 1, 2)), r"trailing axes must be \(2, 2\)"),
        ("Bk", np.zeros((1, 1, 1, 3)), r"trailing axes must be \(1, 2\)"),
        ("Dk", np.zeros((1, 1, 2)), "must have 4 axes"),
        ("Ck", np.zeros((2, 1, 1, 1)), "time axis must be 1 .* or n_t = 3"),
        ("u_ff", np.zeros((4, 1, 1)), "time axis must be n_t = 3"),
        ("y_ref", np.full((3, 1, 2), np.nan), "finite"),
        ("K0", np.zeros((1, 2, 2)), r"trailing axes must be \(1, 2\)"),
        ("read_sizes", (1, 0), "positive integers"),
        ("writes", ("u0", "u0"), "distinct"),
    ],
)
def test_bad_arrays_name_the_field(field, value, rule):
    with pytest.raises(ValueError, match=rf"^{field}: .*{rule}"):
        empty_law(**{field: value})


def test_case_axes_are_one_or_n_cases():
    law = empty_law(Dk=np.zeros((1, 4, 1, 2)))
    assert law.n_cases == 4
    with pytest.raises(ValueError, match=r"^u_ff: case axis must be 1 or n_cases = 4"):
        empty_law(Dk=np.zeros((1, 4, 1, 2)), u_ff=np.zeros((3, 3, 1)))


def test_arrays_are_frozen_copies():
    D = np.ones((1, 1, 1, 2))
    law = empty_law(Dk=D)
    D[:] = 7.0
    assert np.all(law.Dk == 1.0) and not law.Dk.flags.writeable


def test_reference_loop_is_the_stated_recursion(rng):
    """One state, A = a, B = 1, C = c, D = d, K0 = k0, per-case a and a time-varying d:
    ξ_k = a^k k0 e_0 + Σ_{j<k} a^{k-1-j} e_j (for k >= 1, e_0 entering both), written out."""
    n_t, nc = 40, 3
    a = np.array([0.5, -0.9, 0.99])
    d = rng.normal(size=n_t)
    law = LinearLaw(
        a[None, :, None, None],
        np.ones((1, 1, 1, 1)),
        np.full((1, 1, 1, 1), 2.0),
        d[:, None, None, None],
        rng.normal(size=(n_t, 1, 1)),
        rng.normal(size=(n_t, nc, 1)),
        np.full((1, 1, 1), 0.3),
        ("y",),
        ("u",),
        (1,),
        (1,),
    )
    Y = rng.normal(size=(n_t, nc, 1))
    U = run_linear_law(law, Y)
    e = (Y - law.y_ref)[..., 0]
    for k in range(n_t):
        terms = [a**k * 0.3 * e[0]] + [a ** (k - 1 - j) * e[j] for j in range(k)]
        xi = sum(terms)
        expect = law.u_ff[k, :, 0] + 2.0 * xi + d[k] * e[k]
        # each path rounds every summand and partial sum: a few ulps of Σ|terms| per step
        size = np.abs(law.u_ff[k, :, 0]) + 2 * sum(np.abs(t) for t in terms) + np.abs(d[k] * e[k])
        assert np.all(np.abs(U[k, :, 0] - expect) <= 4 * EPS * (k + 2) * size)


def test_affine_shift_reproduces_the_affine_recursion(rng):
    """x_{k+1} = A x + B e + F v_k, u = g_k + C x + D e, x_0 = s0: the shifted law gives the
    same commands (absorb_affine; the module docstring's algebra)."""
    n_t, nc, nk = 50, 2, 3
    A = 0.3 * rng.normal(size=(1, 1, nk, nk))
    B, C, D = (
        rng.normal(size=(1, 1, nk, 2)),
        rng.normal(size=(1, 1, 1, nk)),
        rng.normal(size=(1, 1, 1, 2)),
    )
    F, v = rng.normal(size=(nk, 2)), rng.normal(size=(n_t, nc, 2))
    f = v @ F.T
    g, s0 = rng.normal(size=(n_t, nc, 1)), rng.normal(size=(nc, nk))
    Y = rng.normal(size=(n_t, nc, 2))
    law = LinearLaw(
        A,
        B,
        C,
        D,
        np.zeros((n_t, 1, 2)),
        absorb_affine(A, C, g, F, v, s0),
        None,
        ("a", "b"),
        ("u",),
        (1, 1),
        (1,),
    )
    x, expect = s0.copy(), []
    for k in range(n_t):
        expect.append(g[k] + x @ C[0, 0].T + Y[k] @ D[0, 0].T)
        x = x @ A[0, 0].T + Y[k] @ B[0, 0].T + f[k]
    # the shift moves |s| (not |x|) into the rounding: bound with the larger of the two sizes
    size = np.abs(expect).max() + np.abs(law.u_ff).max()
    np.testing.assert_allclose(
        run_linear_law(law, Y), np.array(expect), rtol=0, atol=4 * EPS * n_t * size
    )


def test_user_law_has_no_linear_form():
    """A user-written law runs through Python: the base class answers None."""

    class Saturated(Controller):
        target = 0.0

        def __call__(self, t, y, state):
            return np.clip(-y["theta"], -1, 1), state

    assert Saturated().linear_form(DT, TIMES, NC) is None


# -- every linear law against itself called sample by sample --------------------------------------
def compare(law, rng, scale_y=1.0, n_cases=NC, state_law=False):
    form = law.linear_form(DT, TIMES, n_cases)
    assert form.reads == tuple(law.reads) and form.writes == tuple(law.writes)
    Y = scale_y * rng.normal(size=(NT, n_cases, form.p))
    fast, slow = run_linear_law(form, Y), run_controller(law, TIMES, Y)
    if state_law:
        rho = np.abs(np.linalg.eigvals(form.Ak[0, 0])).max()
        assert rho < 1  # the round-off is not amplified (module docstring)
        tol = 4 * EPS * NT * (np.abs(slow).max() + np.abs(form.u_ff).max())
    else:
        terms = np.abs(form.u_ff) + np.einsum(
            "tcij,tcj->tci", np.abs(form.Dk), np.abs(Y - form.y_ref)
        )
        tol = 4 * EPS * terms.max()
    err = np.abs(fast - slow).max()
    assert err <= tol, (err, tol)
    return form, err


def test_pd_per_case_gains_tracking_with_feedforward(rng, reference):
    law = PD(rng.uniform(1, 3, NC), rng.uniform(1, 3, NC), reference=reference)
    form, _ = compare(law, rng)
    assert law.reads == ("theta", "theta_dot") and law.writes == ("torque",)
    assert form.n_states == 0 and form.Dk.shape == (1, NC, 1, 2)
    np.testing.assert_array_equal(form.Dk[0, :, 0, 0], -law.kp)


def test_pd_step_and_no_feedforward(rng, reference):
    compare(PD(2.0, 3.0, target=np.linspace(0, 1, NC)), rng)
    form, _ = compare(PD(2.0, 3.0, reference=reference, feedforward=False), rng)
    assert np.all(form.u_ff == 0)


def test_lyapunov_laws(rng, reference):
    reg = LyapunovRegulator(rng.uniform(1, 3, NC), 2.0, rng.uniform(-1, 1, NC), target=0.3)
    assert reg.reads == ("theta", "theta_dot", "root_torque")
    compare(reg, rng)
    trk = LyapunovTracker(
        reference, 2.0, rng.uniform(1, 3, NC), 0.5, appendage_inertia=rng.uniform(0.5, 1, NC)
    )
    form, _ = compare(trk, rng)
    assert trk.reads == ("theta", "theta_dot", "root_torque")
    assert np.abs(form.u_ff).max() > 0  # the reference torque is fed forward


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(target=np.linspace(0.1, 0.5, NC)),
        dict(reference="slew"),
        dict(reference="slew", gains="discrete"),
        dict(target=0.3, initial_estimate="random"),
        dict(reference="slew", measurements=("theta", "rate")),
    ],
)
def test_lqg(rng, reference, plant, kwargs):
    A, B, C, Q = plant
    if kwargs.get("reference") == "slew":
        kwargs["reference"] = reference
    if kwargs.get("initial_estimate") == "random":
        kwargs["initial_estimate"] = 0.1 * rng.normal(size=(NC, 14))
    law = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=DT, **kwargs)
    form, _ = compare(law, rng, 0.1, state_law=True)
    assert law.reads == tuple(kwargs.get("measurements", ("theta", "theta_dot")))
    assert (form.K0 is None) == ("initial_estimate" in kwargs)


@pytest.mark.parametrize("order", [1, 2])
def test_frequency_shaped(rng, reference, plant, order):
    A, B, C, Q = plant
    design = frequency_shaped_lqr(A, B, Q, np.array([[7.0]]), 2.0, order=order, damping=0.7)
    L = kalman(A, B, C, 0.1, RN).gain
    compare(design.controller(C, L, DT, reference=reference), rng, 0.1, state_law=True)
    law = design.controller(
        C,
        L,
        DT,
        target=0.3,
        disturbance=1e-3 * rng.normal(size=14),
        initial_estimate=0.1 * rng.normal(size=14),
    )
    form, _ = compare(law, rng, 0.1, state_law=True)
    assert form.n_states == 14 + order


def test_estimator_law_refuses_another_period(plant):
    A, B, C, Q = plant
    law = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=DT)
    with pytest.raises(ValueError, match=r"^dt: the law was built for a sample period of 0.05"):
        law.linear_form(0.01, TIMES, 1)


def test_per_case_parameters_must_match_the_run():
    with pytest.raises(ValueError, match=r"^kp: has 3 cases, the run has n_cases = 5"):
        PD(np.ones(3), 1.0).linear_form(DT, TIMES, 5)


def test_run_controller_calls_a_frozen_law_without_a_reference_with_the_plants_widths():
    """An attitude law is a frozen dataclass without a reference: run_controller calls it as
    the engine does (no reference table written on it; found by flexsat.testing, where it
    raised FrozenInstanceError) with the channel widths given (attitude 4, rate 3, torque 3),
    and the commands are the law's own, sample by sample."""
    from flexsat.control.attitude_laws import QuaternionPD

    law = QuaternionPD(Kp=7.2, Kd=12.0)
    rng = np.random.default_rng(5)
    beta = rng.standard_normal((4, 2, 4))
    beta /= np.linalg.norm(beta, axis=-1, keepdims=True)
    rate = rng.standard_normal((4, 2, 3))
    U = run_controller(law, DT * np.arange(4), np.concatenate([beta, rate], -1), (4, 3), (3,))
    for k in range(4):
        u, _ = law(k * DT, {"attitude": beta[k], "rate": rate[k]}, {})
        np.testing.assert_array_equal(U[k], u)


@pytest.mark.parametrize("spec", [3, None, object()])
def test_channel_spec_refuses_what_is_no_channel_naming_the_field(spec):
    """One value that is neither a name, a Channel, a sequence nor a mapping is refused with the
    field's rule (it used to escape as ``TypeError: ... is not iterable``)."""
    from flexsat.control.linear_form import channel_spec

    with pytest.raises(ValueError, match=r"^measurements: give channel names or Channels, got "):
        channel_spec(spec, "measurements")
