"""Any python-control system as a compensator between named channels: the law is the discrete
recursion of the system python-control itself computes (forced_response), a continuous system
is its zero-order-hold discretisation at the control period, the linear form is the law, and
bad systems, periods, channels and references are refused naming the field.

Tolerances: the law and python-control evaluate the same recursion x+ = Φx + Γe, u = Cx + De
with differently ordered sums: a few ulps per step of the largest summand, carried by the
system's own dynamics (|eig Φ| < 1 here), so 4 eps × n_t × max|u| × g with the gain scale
g = 1 + max|Φ| + max|Γ| + max|C| + max|D|. The continuous case compares two evaluations of one
matrix exponential (ours and scipy's in c2d), equal to ~10 eps |A dt|, which the response
carries with a factor 1 + max|A|.
"""

import numpy as np
import pytest

import control as ct
from flexsat.control import StateSpaceCompensator, run_linear_law
from flexsat.control.linear_form import run_controller
from flexsat.dynamics.plant import Channel

EPS = np.finfo(float).eps
DT, NT, NC = 0.02, 400, 4
TIMES = DT * np.arange(NT)


@pytest.fixture(scope="module")
def rng():
    return np.random.default_rng(10)


def stable_system(rng, n, p, m, dt=0):
    """A random stable system: continuous poles in [−3, −0.5] (or their ZOH images)."""
    V = rng.normal(size=(n, n))
    A = V @ np.diag(-rng.uniform(0.5, 3, n)) @ np.linalg.inv(V)
    sys = ct.ss(A, rng.normal(size=(n, p)), rng.normal(size=(m, n)), rng.normal(size=(m, p)))
    return sys if dt == 0 else ct.c2d(sys, dt, "zoh")


def gain_scale(sysd):
    return 1 + sum(np.abs(np.asarray(M)).max() for M in (sysd.A, sysd.B, sysd.C, sysd.D))


def test_discrete_mimo_system_is_its_recursion(rng):
    """Two measurement channels (θ and a 2-wide q) minus per-case references, two commands
    (a torque and a 2-wide force): the commands equal forced_response of the same discrete
    system driven by the errors, and the linear form equals the law."""
    sysd = stable_system(rng, 4, 3, 3, DT)
    law = StateSpaceCompensator(
        sysd,
        ["theta", ("q", 2)],
        ["torque", ("force", 2)],
        references={"theta": rng.normal(size=NC), "q": [0.1, -0.2]},
    )
    assert law.reads == ("theta", "q") and law.read_sizes == (1, 2)
    assert law.writes == ("torque", "force") and law.write_sizes == (1, 2)
    assert law.n_cases == NC
    Y = rng.normal(size=(NT, NC, 3))
    U = run_controller(law, TIMES, Y)
    E = Y - law.r
    expect = np.stack(
        [ct.forced_response(sysd, TIMES, E[:, c].T).outputs.T for c in range(NC)], axis=1
    )
    tol = 4 * EPS * NT * np.abs(expect).max() * gain_scale(sysd)
    assert np.abs(U - expect).max() <= tol
    form = law.linear_form(DT, TIMES, NC)
    assert np.abs(run_linear_law(form, Y) - U).max() <= tol


def test_continuous_system_is_discretised_by_zero_order_hold(rng):
    """The law equals c2d(sys, dt, 'zoh') run by forced_response; for a constant error (which
    the hold reproduces exactly) it equals the continuous system's own response at the
    samples."""
    sys = stable_system(rng, 3, 2, 1)
    law = StateSpaceCompensator(sys, ["theta", "theta_dot"], "torque", dt=DT)
    sysd = ct.c2d(sys, DT, "zoh")
    np.testing.assert_allclose(
        law.matrices[0], sysd.A, rtol=0, atol=10 * EPS * np.abs(sys.A * DT).max()
    )
    Y = rng.normal(size=(NT, 1, 2))
    U = run_controller(law, TIMES, Y)
    expect = ct.forced_response(sysd, TIMES, Y[:, 0].T).outputs[0]
    # the two exponentials differ by ~10 eps |A dt|, summed over n_t steps of the response
    tol = 4 * EPS * NT * np.abs(expect).max() * gain_scale(sysd) * (1 + np.abs(sys.A).max())
    assert np.abs(U[:, 0, 0] - expect).max() <= tol
    step = np.broadcast_to([0.3, -0.7], (NT, 1, 2))
    cont = ct.forced_response(sys, TIMES, step[:, 0].T).outputs[0]
    # python-control propagates the continuous system exactly for a constant input too
    np.testing.assert_allclose(
        run_controller(law, TIMES, step)[:, 0, 0],
        cont,
        rtol=0,
        atol=4 * EPS * NT * np.abs(cont).max() * gain_scale(sysd),
    )
    form = law.linear_form(DT, TIMES, 1)
    assert np.abs(run_linear_law(form, Y) - U).max() <= tol


def test_transfer_function_and_unit_references(rng):
    """A lead compensator given as a transfer function; a Channel's reference in its unit."""
    lead = ct.tf([2.0, 1.0], [0.1, 1.0])
    ch = Channel("theta", "rad")
    law = StateSpaceCompensator(lead, [ch], "torque", dt=DT, references={"theta": "10 deg"})
    assert law.r[0, 0] == pytest.approx(np.deg2rad(10.0), rel=1e-15)
    Y = rng.normal(size=(NT, 2, 1))
    same = StateSpaceCompensator(
        ct.ss(lead), ["theta"], "torque", dt=DT, references={"theta": np.deg2rad(10.0)}
    )
    np.testing.assert_array_equal(run_controller(law, TIMES, Y), run_controller(same, TIMES, Y))


def test_unspecified_discrete_period_takes_dt(rng):
    sysd = stable_system(rng, 2, 1, 1, DT)
    free = ct.ss(sysd.A, sysd.B, sysd.C, sysd.D, True)
    law = StateSpaceCompensator(free, "theta", "torque", dt=DT)
    assert law.dt == DT


@pytest.mark.parametrize(
    "kwargs,field,rule",
    [
        (dict(dt=0.01), "system.dt", "samples every 0.02 s, the control period dt is 0.01"),
        (dict(measurements=["theta"]), "measurements", "sum to 1, the system has 2 inputs"),
        (dict(commands=["torque", "force"]), "commands", "sum to 2, the system has 1 outputs"),
        (dict(references={"rate": 1.0}), "references", "'rate' is not a measurement channel"),
        (
            dict(references={"theta": np.ones(3), "theta_dot": np.ones(2)}),
            "references.theta_dot",
            "has 2 cases, another reference 3",
        ),
        (dict(references={"theta": "1 N*m"}), "references.theta", "must be a number in SI units"),
    ],
)
def test_bad_input_names_the_field(rng, kwargs, field, rule):
    sysd = stable_system(rng, 2, 2, 1, DT)
    args = dict(measurements=["theta", "theta_dot"], commands="torque") | kwargs
    with pytest.raises(ValueError, match=rf"^{field}: .*{rule}"):
        StateSpaceCompensator(sysd, **args)


def test_refusals_of_period_and_system(rng):
    with pytest.raises(ValueError, match=r"^dt: a continuous system needs the control period"):
        StateSpaceCompensator(stable_system(rng, 2, 1, 1), "theta", "torque")
    with pytest.raises(ValueError, match=r"^system: must be a python-control StateSpace"):
        StateSpaceCompensator(np.eye(2), "theta", "torque", dt=DT)
    with pytest.raises(ValueError, match=r"^references.theta: incompatible units"):
        StateSpaceCompensator(
            stable_system(rng, 2, 1, 1),
            [Channel("theta", "rad")],
            "torque",
            dt=DT,
            references={"theta": "1 m"},
        )
    law = StateSpaceCompensator(stable_system(rng, 2, 1, 1), "theta", "torque", dt=DT)
    with pytest.raises(ValueError, match=r"^dt: the compensator runs at a period of 0.02 s"):
        law.linear_form(0.01, TIMES, 1)
    state = law.initial_state(1)
    _, state = law(0.0, {"theta": np.zeros(1)}, state)
    with pytest.raises(
        ValueError,
        match=r"^dt: the compensator runs at a period of 0.02 s but "
        r"was called 0.05 s after",
    ):
        law(0.05, {"theta": np.zeros(1)}, state)
