"""Claims of a dispersed batch: case i of the batch is plant i run alone; plants that do not
share their channels and state are refused, naming the field."""

import numpy as np
import pytest

from flexsat.control import PD
from flexsat.dynamics.dispersion import stack_plants
from flexsat.dynamics.hub_appendage import HubAppendage
from flexsat.dynamics.plant import Channel, Plant
from flexsat.sim import BearingFriction, RandomTorque, SimConfig, simulate
from flexsat.units import to_si


def _plants(tamu_case, n_modes=4):
    base = tamu_case.model()
    p = base.params
    out = []
    for hub, zeta in ((1.0, 0.005), (1.3, 0.01), (0.8, 0.02)):
        params = p.__class__(**{**p.__dict__, "hub_inertia": hub * p.hub_inertia, "damping": zeta})
        out.append(HubAppendage(params, n_modes=n_modes))
    return out


def test_case_i_of_a_dispersed_batch_is_plant_i_run_alone(tamu_case):
    """Hub inertia and damping dispersed over 3 cases, with bearing friction and a random
    torque on (seed i for case i): every history equals the single run of plant i to 1e-12
    relative (the batched products round differently from the single ones, ~1e-16 per step,
    and the closed loop is stable, so the differences stay at round-off). 8 substeps are more
    than any case needs for the friction, so the batch and the singles take the same steps
    (a batch takes the largest number any of its cases needs)."""
    plants = _plants(tamu_case)
    friction = BearingFriction(to_si("20 ozf*in", "N*m"), to_si("0.001 ozf*in*s/rad", "N*m*s/rad"))
    cfg = SimConfig(duration=3.0, friction=friction, random_torque=RandomTorque(0.01), substeps=8)
    law = PD(5.0, 20.0, target=[0.3, 0.4, 0.5])
    batch = simulate(stack_plants(plants), law, cfg).dataset
    assert batch.attrs["substeps"] == 8
    for i, plant in enumerate(plants):
        one = simulate(plant, PD(5.0, 20.0, target=law.target[i]), cfg, seeds=[i]).dataset
        for var in (
            "theta",
            "theta_dot",
            "torque",
            "friction_torque",
            "root_torque",
            "tip_deflection",
            "energy",
            "vibration_energy",
        ):
            a, b = batch[var].values[i], one[var].values[0]
            assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max(), (i, var)
        assert batch.settling_time_s.values[i] == pytest.approx(
            one.settling_time_s.values[0], rel=1e-12, nan_ok=True
        )


def test_the_batch_size_must_be_the_number_of_plants(tamu_case):
    with pytest.raises(
        ValueError,
        match=r"^n_cases: the dispersed plant carries 3 cases, the "
        r"batch has 2",
    ):
        simulate(stack_plants(_plants(tamu_case)), PD(1.0, 1.0), SimConfig(duration=0.1), n_cases=2)


def test_mismatched_plants_are_refused_naming_the_field(tamu_case):
    four, ten = _plants(tamu_case, 4)[0], tamu_case.model()
    with pytest.raises(
        ValueError,
        match=r"^nx: plants\[1\] has nx 22, plants\[0\] has 10; a "
        r"dispersed batch needs the same channels",
    ):
        stack_plants([four, ten])
    from flexsat.cases import nps

    with pytest.raises(
        ValueError,
        match=r"^outputs: plants\[1\] has outputs \(theta, "
        r"theta_dot, root_torque, tip_deflection\)",
    ):
        stack_plants([four, nps().model()])


class _Oscillator(Plant):
    """x'' = −k x + u: a minimal linear plant for the protocol tests."""

    inputs = (Channel("force", "N"),)
    outputs = (Channel("position", "m"),)

    def __init__(self, k):
        self.k = k

    @property
    def nx(self):
        return 2

    def linear_part(self):
        return np.array([[0.0, 1.0], [-self.k, 0.0]]), np.array([[0.0], [1.0]])

    def output_matrices(self, name):
        return np.array([[1.0, 0.0]]), np.zeros((1, 1)), np.zeros((1, 1))


def test_non_finite_dispersed_parameters_are_refused():
    with pytest.raises(ValueError, match=r"^A: plants\[1\] has a non-finite entry"):
        stack_plants([_Oscillator(1.0), _Oscillator(float("nan"))])


def test_structural_plants_with_no_feedthrough_disperse():
    """A structure's outputs have no D_f (``output_matrices`` gives None for it): stacked, the
    outputs still carry their per-case matrices (D_f stays None) and case i of the batch is
    plant i run alone (found by flexsat.testing's dispersion check; the stacked None used to
    become an object array and the run failed to start)."""
    from flexsat.cases.agrawal_bang import agrawal_bang
    from flexsat.sim import ChannelDisturbance
    from flexsat.testing.checks import HoldLaw

    plants = [agrawal_bang(tip_mass=m).plant(3) for m in (0.0, 0.01, 0.02)]
    stacked = stack_plants(plants)
    assert stacked.output_matrices("y1")[2] is None
    assert stacked.output_matrices("y1")[0].shape == (3, 1, plants[0].nx)
    cfg = SimConfig(duration=0.5, channel_disturbances={"u1": ChannelDisturbance(random=0.1)})
    x0 = 1e-3 * np.random.default_rng(1).standard_normal((3, plants[0].nx))
    u = {"u1": np.full(3, 0.2), "u2": np.zeros(3), "u3": np.full(3, -0.1)}
    batch = simulate(stacked, HoldLaw(u), cfg, initial_state=x0).dataset
    for i, plant in enumerate(plants):
        one_law = HoldLaw({k: v[i : i + 1] for k, v in u.items()})
        one = simulate(plant, one_law, cfg, seeds=[i], initial_state=x0[i], n_cases=1).dataset
        for var in ("y1", "y2", "y3", "u1", "energy"):
            a, b = batch[var].values[i], one[var].values[0]
            # batched products round differently: 2 n_x ε per step over 38 steps
            assert np.abs(a - b).max() <= 2 * plants[0].nx * 38 * 2.2e-16 * np.abs(b).max(), var


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_a_dispersed_batch_of_one_is_its_plant_run_alone(compiled):
    """A DispersedPlant of a single flexible spacecraft (per-case matrices with a case axis of
    length one) runs on both loops and equals the spacecraft run alone: before, the Python loop
    treated it as a shared plant and broadcast its (1, n, n) matrices into a misshapen
    measurement. Tolerance 1e-12 relative: the per-case products round differently from the
    shared ones (~1e-16 per step) on a stable 0.5 s slew."""
    import sys
    from pathlib import Path

    from flexsat.control.attitude_laws import MRPLaw
    from flexsat.dynamics.dispersion import DispersedPlant

    sys.path.insert(0, str(Path(__file__).parents[1] / "testing"))
    from test_conformance import _flexible

    plant = _flexible()
    target = [np.cos(0.3), 0.6 * np.sin(0.3), 0.8 * np.sin(0.3), 0.0]
    law = MRPLaw(K=10.0, P=[50.0, 60.0, 70.0], beta_target=target)
    cfg = SimConfig(duration=0.5)
    one = simulate(DispersedPlant([plant]), law, cfg, seeds=[0], compiled=compiled).dataset
    alone = simulate(plant, law, cfg, seeds=[0], compiled=compiled).dataset
    assert set(one.data_vars) == set(alone.data_vars)
    for var in alone.data_vars:
        a, b = one[var].values, alone[var].values
        assert a.shape == b.shape, var
        if np.issubdtype(b.dtype, np.floating):  # NaN: a metric with no value in both
            scale = np.nanmax(np.abs(b), initial=0.0)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * scale, err_msg=var)
