"""The maneuver scenario schema (flexsat.scenarios.maneuver): quantities in SI, and one
``field.path: rule`` message per bad input."""

from __future__ import annotations

import math

import pytest
import yaml

from flexsat.scenarios import ScenarioError, default_scenario, load_scenario, prepare_scenario
from flexsat.units import to_si

OZ_IN = to_si("1 ozf*in", "N*m")


def small_data() -> dict:
    """The default scenario as a dict, with a 3-mode model and a 2 s run (fast)."""
    data = yaml.safe_load(default_scenario().yaml_text)
    data["model"]["n_modes"] = 3
    data["simulation"]["duration"] = "2 s"
    return data


def problems_of(mutate) -> str:
    """The ScenarioError message of the small scenario changed by ``mutate(data)``."""
    data = small_data()
    mutate(data)
    with pytest.raises(ScenarioError) as info:
        prepare_scenario(load_scenario(yaml.safe_dump(data)))
    return str(info.value)


# -- the default ---------------------------------------------------------------------------------
def test_default_scenario_loads_in_si():
    s = default_scenario()
    assert s.name == "TAMU 40 deg slew, Law I vs Law II"
    assert s.case == "tamu"
    assert [r.label for r in s.runs] == ["Law I", "Law II"]
    assert s.maneuver.angle == pytest.approx(math.radians(40))
    assert s.actuator.saturation == pytest.approx(400 * OZ_IN)
    assert s.runs[0].gains.g1 == pytest.approx(600 * OZ_IN)
    assert s.runs[1].reference.shape == "smooth_bang_bang"
    config = s.sim_config()
    assert config.control_rate == 75.0
    assert config.substeps == 4  # ceil(13.33 ms / 3.34 ms)
    assert config.friction.coulomb == pytest.approx(20 * OZ_IN)
    assert config.sensors.rate == "ls_filter"


def test_dump_round_trips_and_bare_numbers_are_si():
    s = default_scenario()
    again = load_scenario(yaml.safe_dump(s.model_dump()))
    assert again.model_dump() == s.model_dump()
    data = small_data()
    data["maneuver"]["angle"] = math.radians(40)
    data["actuator"]["saturation"] = "2.824620725690418"
    bare = load_scenario(yaml.safe_dump(data))
    assert bare.maneuver.angle == pytest.approx(s.maneuver.angle)
    assert bare.actuator.saturation == pytest.approx(s.actuator.saturation)


@pytest.mark.parametrize(
    "section, key, text, expected",
    [
        ("maneuver", "angle", "0.5 turn", math.pi),
        ("simulation", "integration_step", "1 ms", 1e-3),
        ("simulation", "control_rate", "0.1 kHz", 100.0),
        ("actuator", "saturation", "1 N*m", 1.0),
        ("sensors", "encoder_resolution", "1 arcmin", math.radians(1 / 60)),
    ],
)
def test_quantities_convert_to_si(section, key, text, expected):
    data = small_data()
    data[section][key] = text
    assert getattr(getattr(load_scenario(yaml.safe_dump(data)), section), key) == pytest.approx(
        expected
    )


# -- one test per bad-input rule -----------------------------------------------------------------
def test_unknown_key_is_named_with_its_path():
    message = problems_of(lambda d: d["sensors"].update(rate_windw=3))
    assert (
        "sensors.rate_windw: unknown key (allowed: encoder_resolution, rate, rate_window" in message
    )


def test_unknown_keys_at_top_level_and_in_a_run():
    message = problems_of(
        lambda d: (d.update(colour=1, size=2), d["runs"][1]["reference"].update(beta=1))
    )
    assert "colour: unknown key (allowed: kind, name, case, case_overrides, model" in message
    assert "size: unknown key" in message
    assert "runs['Law II'].reference.beta: unknown key (allowed: shape, u_max" in message
    assert "invalid scenario (3 problems)" in message


@pytest.mark.parametrize(
    "mutate, expected",
    [
        (
            lambda d: d["simulation"].update(duration="nan"),
            "simulation.duration: must be a finite number, got 'nan'",
        ),
        (
            lambda d: d["simulation"].update(duration=float("inf")),
            "simulation.duration: must be a finite number, got inf",
        ),
        (
            lambda d: d["runs"][0]["gains"].update(g2="inf ozf*in*s/rad"),
            "runs['Law I'].gains.g2: must be a finite number",
        ),
        (
            lambda d: d["case_overrides"].update(n_modes="nan"),
            "case_overrides.n_modes: must be a finite number, got 'nan'",
        ),
    ],
    ids=["nan-string", "inf-number", "inf-quantity", "nan-override"],
)
def test_non_finite_numbers(mutate, expected):
    assert expected in problems_of(mutate)


def test_integration_step_must_be_below_the_control_period():
    message = problems_of(lambda d: d["simulation"].update(integration_step="20 ms"))
    assert (
        "simulation.integration_step: must be smaller than the control period "
        "1/control_rate = 13.33 ms, got 20 ms"
    ) in message


def test_incompatible_units():
    message = problems_of(lambda d: d["maneuver"].update(angle="40 kg"))
    assert "maneuver.angle: incompatible units (kilogram given, rad expected)" in message


def test_positive_simulation_settings_come_from_the_runtime():
    message = problems_of(lambda d: d["simulation"].update(control_rate=-3))
    assert "simulation.control_rate: must be > 0" in message


def test_disturbance_rules():
    message = problems_of(lambda d: d["disturbances"].update(random_torque="-5 ozf*in"))
    assert "disturbances.random_torque: must be >= 0" in message


@pytest.mark.parametrize(
    "mutate, expected",
    [
        (
            lambda d: d["runs"][0]["gains"].update(kp=1),
            "runs['Law I'].gains.kp: not a gain of law 'lyapunov_regulator' "
            "(its gains: g1, g2, g3)",
        ),
        (
            lambda d: d["runs"][1].pop("reference"),
            "runs['Law II'].reference: required by law 'lyapunov_tracker'",
        ),
        (
            lambda d: d["runs"][0].update(reference={"shape": "bang_bang", "u_max": 1}),
            "runs['Law I'].reference: law 'lyapunov_regulator' tracks no reference",
        ),
        (
            lambda d: d["runs"][1]["reference"].update(shape="bang_bang"),
            "runs['Law II'].reference.alpha: not a parameter of shape 'bang_bang'",
        ),
        (
            lambda d: d["runs"][1]["reference"].update(duration="3 s"),
            "runs['Law II'].reference: give exactly 2 of {u_max, duration, alpha}",
        ),
        (
            lambda d: d["runs"][1].update(law="unknown"),
            "runs['Law II'].law: Input should be 'lyapunov_regulator', 'lyapunov_tracker', "
            "'pd' or 'lqg'",
        ),
        (
            lambda d: d["runs"].append({"label": "PD", "law": "pd"}),
            "runs['PD'].gains.kp: required by law 'pd' (or give poles)",
        ),
        (
            lambda d: d["runs"].append(
                {
                    "label": "PD",
                    "law": "pd",
                    "poles": {"natural_frequency": "0.4 kg", "damping_ratio": 0.9},
                }
            ),
            "runs['PD'].poles.natural_frequency: incompatible units",
        ),
        (
            lambda d: d["runs"].append(
                {
                    "label": "PD",
                    "law": "pd",
                    "poles": {"natural_frequency": "0.06 Hz", "damping_ratio": -0.9},
                }
            ),
            "runs['PD'].poles.damping_ratio: must be >= 0",
        ),
        (lambda d: d["runs"].append(dict(d["runs"][0])), "runs: duplicate label 'Law I'"),
    ],
    ids=[
        "foreign-gain",
        "missing-reference",
        "extra-reference",
        "shape-parameter",
        "overdetermined-shape",
        "unknown-law",
        "pd-without-gains",
        "poles-in-kg",
        "negative-damping",
        "duplicate-label",
    ],
)
def test_run_rules(mutate, expected):
    assert expected in problems_of(mutate)


def test_unknown_case():
    message = problems_of(lambda d: d.update(case="nope"))
    assert "case: unknown case 'nope'; known: [" in message and "'tamu'" in message


def test_model_option_given_twice():
    assert "model.n_modes: also given in case_overrides" in problems_of(
        lambda d: d["case_overrides"].update(n_modes=3)
    )


# -- scenario files (flexsat.scenarios.quantity goes through flexsat.units.to_si) ------------------
def test_scenario_refuses_a_dimensionless_unit_where_a_dimension_is_due():
    assert "simulation.duration: incompatible units (degree given, s expected)" in problems_of(
        lambda d: d["simulation"].update(duration="15 deg")
    )
    pd_run = {
        "label": "PD",
        "law": "pd",
        "poles": {"natural_frequency": "100 percent", "damping_ratio": 0.9},
        "reference": {"shape": "sinusoidal", "duration": "10 s"},
    }
    assert (
        "runs['PD'].poles.natural_frequency: incompatible units (percent given, rad/s expected)"
    ) in problems_of(lambda d: d["runs"].append(pd_run))


@pytest.mark.parametrize("text", ["1/0", "(1", "10.0**400", "10**10**10 s"])
def test_scenario_reports_unreadable_expressions_as_problems(text):
    assert f"simulation.duration: cannot read {text!r} as a quantity" in problems_of(
        lambda d: d["simulation"].update(duration=text)
    )
