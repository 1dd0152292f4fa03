"""The NPS simulator slews of seed 001 as scenarios (`flexsat run examples/nps_pd_slews.yaml`)."""

from pathlib import Path

import numpy as np
import pytest

from flexsat.scenarios import load_scenario, prepare_scenario, run_scenario

EXAMPLE = Path(__file__).parents[1] / "examples" / "nps_pd_slews.yaml"


@pytest.fixture(scope="module")
def plan():
    return prepare_scenario(load_scenario(EXAMPLE))


def test_pd_gains_come_from_the_rigid_poles(plan):
    """Seed 001 L208-L220: ω_n = 0.06 Hz, ζ = 0.9 give k = 1.3985 N m/rad and
    kτ = 6.6773 N m s/rad (printed to 5 digits)."""
    for law in plan.controllers.values():
        assert float(law.kp) == pytest.approx(1.3985, rel=5e-5)
        assert float(law.kd) == pytest.approx(6.6773, rel=5e-5)


def test_sinusoidal_reference_amplitude(plan):
    """Seed 001 Eq. 36: A = 2π I Δθ / P² = 0.6475 N m for 60°, P = 10 s (notes V5)."""
    ref = plan.controllers["PD + sinusoid"].reference
    assert float(ref.u_max) == pytest.approx(0.6475, abs=1e-4)
    pseudo = plan.controllers["PD + pseudo-square"].reference
    assert float(pseudo.u_max) == pytest.approx(0.4823, abs=1e-4)  # notes V6


def test_every_slew_reaches_the_target(plan):
    result = run_scenario(plan.scenario)
    for label, res in zip(result.labels, result.results):
        theta = np.degrees(res.dataset.theta.values[0])
        assert abs(theta[-1] - 60.0) < 0.5, label
        assert np.isfinite(res.metrics["settling_time_s"][0]), label


LQG_EXAMPLE = Path(__file__).parents[1] / "examples" / "nps_lqg_30deg.yaml"


@pytest.fixture(scope="module")
def lqg_plan():
    return prepare_scenario(load_scenario(LQG_EXAMPLE))


def test_lqg_position_gain_is_the_integrator_value(lqg_plan):
    """With R_xx(θ) = 1 and R_uu = 7 the LQR position gain is √(1/7) = 0.378 whatever the modal
    data (the θ channel is a pure integrator)."""
    law = lqg_plan.controllers["LQG"]
    assert law.K[0, 0] == pytest.approx(np.sqrt(1 / 7), rel=1e-8)


def test_reduced_regulator_zeroes_the_gains_of_modes_3_to_6(lqg_plan):
    """Seed 001 Eq. 53: nonzero gains only for θ, q1, q2 and their rates; the refined filter
    then estimates modes 3-6 open loop (Kalman rows orders of magnitude below the kept ones)."""
    law = lqg_plan.controllers["LQG, reduced regulator (Eq. 53)"]
    n = law.K.shape[1] // 2
    dropped = np.r_[3:n, n + 3 : 2 * n]
    assert np.all(law.K[0, dropped] == 0) and np.all(law.K[0, [0, 1, 2, n, n + 1, n + 2]] != 0)
    rows = np.linalg.norm(law.L, axis=1)
    assert rows[dropped].max() < 1e-2 * rows[[0, n]].min()


def test_every_lqg_slew_reaches_30_degrees(lqg_plan):
    result = run_scenario(lqg_plan.scenario)
    for label, res in zip(result.labels, result.results):
        assert abs(np.degrees(res.dataset.theta.values[0, -1]) - 30.0) < 0.5, label


def test_lqg_section_is_required_by_the_law_and_only_by_it():
    from flexsat.scenarios import ScenarioError

    text = LQG_EXAMPLE.read_text().replace("law: lqg\n    lqg:", "law: pd\n    lqg:", 1)
    with pytest.raises(ScenarioError, match=r"lqg: required by law 'lqg' and only for it"):
        load_scenario(text)
