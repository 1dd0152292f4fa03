"""The embedded default scenario (`flexsat run`) reproduces the TAMU experiment's claims
(Junkins, Pollock & Rahman 1990, Att. 3 §V, L1222-L1228)."""

from importlib import resources

import numpy as np
import pytest
import yaml

from flexsat.scenarios import DEFAULT_SCENARIO, load_scenario, run_scenario


@pytest.fixture(scope="module")
def runs():
    """The default scenario plus Law I with g2 = 0 (Att. 3 Fig. 9), same hardware and noise."""
    data = yaml.safe_load(resources.files("flexsat.cases").joinpath(DEFAULT_SCENARIO).read_text())
    data["runs"].append(
        {
            "label": "Law I, g2 = 0",
            "law": "lyapunov_regulator",
            "gains": {"g1": "600 ozf*in/rad", "g2": 0},
        }
    )
    result = run_scenario(load_scenario(yaml.safe_dump(data)))
    return {row["run"]: row for row in result.metrics_records()}


def test_default_scenario_is_the_published_experiment(runs):
    assert set(runs) == {"Law I", "Law II", "Law I, g2 = 0"}


def test_law_ii_settles_at_least_twice_as_fast_as_law_i(runs):
    """Law II settles in ≈ 6 s against > 12 s for Law I. Settling band 0.5°, friction and
    sensor noise on; a law not settled by the end of the 15 s run counts as 15 s."""
    t1 = runs["Law I"]["settling_time_s"]
    t1 = 15.0 if t1 is None else t1
    t2 = runs["Law II"]["settling_time_s"]
    assert t2 is not None and 2 * t2 <= t1
    assert 4.9 < t2 < 8.0  # it cannot settle before the 4.91 s reference ends; paper ≈ 6 s


def test_law_ii_overshoot_is_small_and_law_i_overshoot_is_not(runs):
    """Overshoot ≈ 1.5° for Law II against ≈ 10° for Law I (g2 = 800)."""
    assert runs["Law II"]["overshoot_deg"] < 3.0
    assert 6.0 < runs["Law I"]["overshoot_deg"] < 14.0


def test_law_i_without_rate_feedback_overshoots_strongly(runs):
    """Att. 3 Fig. 9: g2 = 0 overshoots by ≈ 34° (only passive dissipation)."""
    assert runs["Law I, g2 = 0"]["overshoot_deg"] > 25.0


def test_law_ii_leaves_less_vibration_than_law_i(runs):
    """Att. 3 L1222: "much lower peak vibration" under Law II."""
    assert runs["Law II"]["peak_tip_deflection_m"] < 0.8 * runs["Law I"]["peak_tip_deflection_m"]
    assert np.isfinite(runs["Law II"]["residual_energy_at_T_J"])
