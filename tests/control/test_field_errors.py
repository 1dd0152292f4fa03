"""The control laws refuse a bad input with a FieldError that carries the field as data
(``exc.field``), so that a scenario places it at the run's path without reading the message;
the message is unchanged, ``"field: rule"``."""

import numpy as np
import pytest

from flexsat.control import (
    PD,
    LQGController,
    MRPLaw,
    QuaternionPD,
    frequency_shaped_lqr,
    lqr,
)
from flexsat.control.ppf import PPFBank, PPFModel
from flexsat.input_checks import FieldError
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario

# double integrator θ'' = u: the smallest plant every law here accepts
A = np.array([[0.0, 1.0], [0.0, 0.0]])
B = np.array([[0.0], [1.0]])
LQG = {"A": A, "B": B, "C": np.eye(2), "K": [[1.0, 2.0]], "L": np.eye(2), "dt": 0.1}

CASES = [
    ("pd kp", lambda: PD(kp=-1.0, kd=1.0), "kp", "must be >= 0, got -1.0"),
    (
        "lqg gains",
        lambda: LQGController(**LQG, gains="zoh"),
        "gains",
        "must be 'continuous' or 'discrete', got 'zoh'",
    ),
    (
        "lqg B",
        lambda: LQGController(**{**LQG, "B": np.ones((2, 2))}),
        "B",
        "the controller interface commands one torque, so B must have one column, got 2",
    ),
    (
        "lqg measurements",
        lambda: LQGController(**LQG, measurements=("theta",)),
        "measurements",
        "give 2 measurement keys (one per row of C), got ('theta',)",
    ),
    (
        "lqr joint weight",
        lambda: lqr(A, B, np.eye(2), [[1.0]], N=[[10.0], [0.0]]),
        "N",
        "the joint weight [[Q, N], [Nᵀ, R]] must be positive semi-definite, but "
        "Q − N R⁻¹ Nᵀ has smallest eigenvalue -99",
    ),
    (
        "ppf sensor",
        lambda: PPFModel([1.0], 0.01, [[1.0]], [[0.0]]),
        "sensors[0]",
        "pair 1 has a zero sensor row (a_2 = 0)",
    ),
    (
        "ppf bank",
        lambda: PPFBank(np.ones((1, 1)), np.ones((2, 2))),
        "zeta_f",
        "must be a scalar or have the shape of omega_f (1, 1), got (2, 2)",
    ),
    (
        "frequency-shaped order",
        lambda: frequency_shaped_lqr(A, B, np.eye(2), [[1.0]], 1.0, order=3),
        "order",
        "must be 1 (control rate) or 2 (rate and acceleration), got 3",
    ),
    (
        "quaternion pd Kp",
        lambda: QuaternionPD(Kp=np.ones(2), Kd=1.0),
        "Kp",
        "per-axis gains must be a scalar or have last axis 3 (body axes 1, 2, 3; leading axes "
        "are cases), got shape (2,)",
    ),
    (
        "mrp P",
        lambda: MRPLaw(K=1.0, P=np.ones(2)),
        "P",
        "per-axis gains must be a scalar or have last axis 3 (body axes 1, 2, 3; leading axes "
        "are cases), got shape (2,)",
    ),
]


@pytest.mark.parametrize("build, field, rule", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_the_refusal_names_its_field_as_data(build, field, rule):
    with pytest.raises(FieldError) as info:
        build()
    assert info.value.field == field
    assert info.value.rule == rule
    assert str(info.value) == f"{field}: {rule}"  # the text callers and tests read, unchanged
    assert isinstance(info.value, ValueError)


SIMULATION = """
kind: simulation
name: test
case: eps
plant: {model: rigid}
initial: {euler123: ["10 deg", 0, 0]}
simulation: {duration: "2 s", control_rate: "10 Hz"}
runs:
  - {label: a, law: mrp_pd, gains: {K: "100 N*m", P: [1000, 1000]}}
"""


def test_a_scenario_places_the_law_refusal_at_the_gain():
    """MRPLaw refuses a two-axis P with FieldError("P", ...); the simulation scenario puts it
    under the run's gains (a plain ValueError carried no field, and the text fallback placed it
    at ``runs['a'].P``)."""
    with pytest.raises(ScenarioError) as info:
        run_scenario(load_scenario(SIMULATION))
    [problem] = info.value.problems
    assert problem.path == "runs['a'].gains.P"
    assert problem.rule.startswith("per-axis gains must be a scalar or have last axis 3")
