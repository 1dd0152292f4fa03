"""The NPS simulator slews of seed 001 as scenarios (`flexsat run examples/nps_pd_slews.yaml`)."""

from pathlib import Path

import numpy as np
import pytest

from flexsat.scenario import load_scenario, prepare_scenario, run_scenario

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
