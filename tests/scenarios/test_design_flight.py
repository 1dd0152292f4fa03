"""Flying a design study's nominal laws on dispersed truths (:mod:`flexsat.scenarios.
design_flight`): re-solved modes take the nominal signs without changing any physical output,
the inertia margins pick the cases a rule would refuse first, an unphysical truth is refused by
name before any case runs, and a case whose attitude leaves the perturbation law's hemisphere
is flown on the law itself. On the user-defined spacecraft of
``examples/own_spacecraft_design_study.yaml`` (a 9-node FE model: fast)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.control import PerturbationFeedback, QuaternionPD
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.scenarios.design_dispersions import case_builder
from flexsat.scenarios.design_flight import align_modes, dispersed_spacecraft, inertia_margins
from flexsat.scenarios.design_study import kept_modes, modal_model_of, stage_plan
from flexsat.scenarios.slew import TruthSpec, apply_truth
from flexsat.sim import SimConfig, SimulationDiverged, simulate

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "own_spacecraft_design_study.yaml"


def _data(tmp_path: Path) -> dict:
    data = yaml.safe_load(EXAMPLE.read_text(encoding="utf-8"))
    data["cache"] = str(tmp_path / "cache")
    data["simulation"]["duration"] = "6 s"
    return data


def _load(data: dict):
    return load_scenario(yaml.safe_dump(data, sort_keys=False))


@pytest.fixture(scope="module")
def nominal(tmp_path_factory):
    """The example's nominal study (no dispersions): its placement, laws and kept modes."""
    data = _data(tmp_path_factory.mktemp("own"))
    data.pop("dispersions")
    return run_scenario(_load(data)), data


def _case(data: dict, tip_masses: tuple[float, float]):
    case = dict(data)
    case["model"] = yaml.safe_load(yaml.safe_dump(data["model"]))
    case["model"]["fe"]["masses"][1]["mass"] = f"{tip_masses[0]} kg"
    case["model"]["fe"]["masses"][2]["mass"] = f"{tip_masses[1]} kg"
    return _load(case)


def test_a_re_solved_mode_takes_the_nominal_sign_and_no_output_changes(nominal):
    """Tip masses 0.9 and 1.1 kg: the solver returns the 32 Hz pair with the other sign (their
    shapes anti-parallel to the nominal's). Aligned, every elastic shape points as the
    nominal's; the spacecraft flown by a PD (which reads no modal coordinate) gives the same
    displacements and attitude either way: a mode's sign is a convention, not physics (the
    modal state flips with the shape; round-off of the flipped products only: 1e-12)."""
    result, data = nominal
    case = _case(data, (0.9, 1.1))
    raw = kept_modes(modal_model_of(case.model, case.folder), case.modes)
    aligned = align_modes(raw, result.modes)
    elastic = raw.frequencies > 1e-3
    dots = np.einsum("ijk,ijk->i", raw.shapes, result.modes.shapes)[elastic]
    assert (dots < 0).any()  # the solver's sign differs for some mode
    new = np.einsum("ijk,ijk->i", aligned.shapes, result.modes.shapes)[elastic]
    assert (new > 0).all()
    np.testing.assert_array_equal(aligned.frequencies, raw.frequencies)
    # a model of another size is returned as it is
    assert (
        align_modes(raw, kept_modes(result.modes, case.modes.model_copy(update={"n_modes": 3})))
        is raw
    )

    plants = [
        dispersed_spacecraft(case, result.placement, None, reference)
        for reference in (None, result.modes)
    ]
    arrays = result.laws["PD"].arrays
    config = SimConfig(duration=6.0, control_rate=20.0)
    runs = [
        simulate(
            p,
            QuaternionPD(Kp=arrays["Kp"], Kd=arrays["Kd"]),
            config,
            n_cases=1,
            initial_state=p.state_from(euler123=[0.1, 0.2, 0.5]),
        ).dataset
        for p in plants
    ]
    names = ["attitude", "rate"] + [str(n) for n in runs[0].data_vars if "displacement_" in str(n)]
    for name in names:
        a, b = runs[0][name].values, runs[1][name].values
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-12 * np.abs(a).max(), err_msg=name)


def test_the_inertia_margins_are_those_of_the_built_truths(nominal):
    """Against each truth built (:func:`apply_truth`): the case of the least triangle margin
    of its principal moments and the case of the least eigenvalue of J − ΔᵀΔ."""
    result, data = nominal
    plant = dispersed_spacecraft(_load(data), result.placement, None)
    scales = np.random.default_rng(5).uniform(0.97, 1.03, (40, 3))  # its I1 + I2 - I3 is 11 %
    triangle, smallest = [], []
    for s in scales:
        truth = apply_truth(TruthSpec(inertia_scale=list(s)), plant)
        moments = np.linalg.eigvalsh(truth.inertia)
        triangle.append(min(moments.sum() - 2 * moments))
        smallest.append(np.linalg.eigvalsh(truth.inertia - truth.coupling.T @ truth.coupling)[0])
    assert inertia_margins(plant, scales) == [int(np.argmin(triangle)), int(np.argmin(smallest))]


def test_an_unphysical_truth_is_refused_by_name_before_any_case_runs(tmp_path, monkeypatch):
    """One principal moment up to 20 times: some case violates the triangle inequality; the
    stage names the parameter and the case, and no case is flown."""
    import flexsat.scenarios.design_dispersions as dispersions

    data = _data(tmp_path)
    data["truth"] = {"inertia_scale": [1.0, 1.0, 1.0]}
    data["dispersions"] = {
        "parameters": {"truth.inertia_scale[2]": {"distribution": "uniform", "low": 1, "high": 20}},
        "cases": 50,
    }

    def flown(*args, **kwargs):
        raise AssertionError("a case was flown")

    monkeypatch.setattr(dispersions, "fly_cases", flown)
    with pytest.raises(ScenarioError, match=r"truth\.inertia_scale\[2\].*case \d+.*triangle"):
        run_scenario(_load(data))


def test_a_case_out_of_the_law_s_hemisphere_flies_on_the_law_itself(tmp_path, monkeypatch):
    """A perturbation law on the own spacecraft, its truth dispersed (direct cases): a case
    whose error quaternion's scalar part is reported negative is flown again alone in the
    Python loop (the law itself); the others keep their compiled numbers. The compiled and
    the Python flight of a case agree to the closed loop's round-off (1e-9), and the case
    taken out is the Python loop's number exactly."""
    data = _data(tmp_path)
    data["laws"].append(
        {
            "label": "slew",
            "type": "perturbation",
            "maneuver": {
                "target": {"euler123": ["0.2 rad", 0, 0]},
                "duration": "4 s",
                "break_frequency": "2 rad/s",
            },
            "modes": 6,
            "linearization_points": 5,
            "break_frequency": "2 rad/s",
            "shaping_damping": 0.7,
            "weights": {"attitude": 1000, "rate": 1000, "modes": 1, "torque": 50, "force": 1e-2},
        }
    )
    data["runs"] = [{"label": "slew", "law": "slew"}]
    data["truth"] = {"inertia_scale": [1.0, 1.0, 1.0], "frequency_scale": 1.0}
    data["dispersions"] = {
        "parameters": {
            "truth.inertia_scale[0]": {"distribution": "uniform", "low": 0.95, "high": 1.05},
            "truth.frequency_scale": {"distribution": "uniform", "low": 0.9, "high": 1.1},
        },
        "cases": 3,
    }
    scenario = _load(data)
    nominal_data = dict(data)
    nominal_data.pop("dispersions")
    result = run_scenario(_load(nominal_data))
    build = case_builder(
        scenario, stage_plan(scenario)["dispersions"], result.placement, result.laws
    )
    values = [
        {"truth.inertia_scale[0]": v, "truth.frequency_scale": f}
        for v, f in ((0.97, 1.05), (1.03, 0.92), (1.0, 1.0))
    ]
    seeds = np.array([5, 6, 7])
    compiled = build.fly(values, seeds, 0)

    original = PerturbationFeedback.hemisphere

    def folded(self, times, attitude):
        out = original(self, times, attitude)
        if out.shape[0] == 3:
            out[1] = -1.0  # case 1 of the batch: as if its attitude had left the hemisphere
        return out

    monkeypatch.setattr(PerturbationFeedback, "hemisphere", folded)
    mixed = build.fly(values, seeds, 0)
    setup = build.setup(values[1], 6, 1)
    (law,) = build.controllers(setup.plant, setup.config.dt).values()
    python = simulate(
        setup.plant,
        law,
        setup.config,
        n_cases=1,
        seeds=[6],
        initial_state=setup.initial["slew"][None],
        compiled=False,
    )
    from flexsat.scenarios.design_study import batch_metrics

    expected = batch_metrics(python, np.asarray(build.laws["slew"]["beta_target"]))
    for name, values_ in mixed.items():
        assert values_[1] == expected[name][0], name
        np.testing.assert_array_equal(values_[[0, 2]], compiled[name][[0, 2]], err_msg=name)
        assert values_[1] == pytest.approx(compiled[name][1], rel=1e-9, abs=1e-15), name


def test_an_lqr_meets_the_motion_it_was_designed_for_once_the_signs_are_aligned(tmp_path):
    """The nominal modes with the first pair's signs reversed (what a re-solve may return):
    the same spacecraft, but an LQR designed on the nominal feeds those modal coordinates back
    reversed (here it diverges); with the signs aligned to the nominal it flies the nominal run
    (the same arithmetic on the same numbers: bit for bit)."""
    from dataclasses import replace

    from flexsat.scenarios.design_laws import LawSpec, law_controller
    from flexsat.scenarios.design_placement import spacecraft

    data = _data(tmp_path)
    data.pop("dispersions")
    data["laws"] = [
        {
            "label": "LQR",
            "type": "lqr",
            "modes": 2,  # the 2.5 Hz pair, well inside the 50 Hz sampling
            "weights": {"attitude": 10, "rate": 10, "modes": 1e3, "torque": 1, "force": 1},
        }
    ]
    data["runs"] = [{"label": "r", "law": "LQR", "initial": {"euler123": [0.1, 0.1, 0.1]}}]
    data["simulation"]["control_rate"] = "50 Hz"
    result = run_scenario(_load(data))
    scenario = result.scenario
    modes = result.modes
    sign = np.ones(modes.n_modes)
    sign[np.flatnonzero(modes.frequencies > 1e-3)[:2]] = -1.0  # the 2.5 Hz pair
    flipped = replace(
        modes,
        shapes=modes.shapes * sign[:, None, None],
        participation=modes.participation * sign[:, None],
    )
    config = SimConfig(duration=6.0, control_rate=50.0)
    law = LawSpec.model_validate(data["laws"][0])

    def flown(kept):
        plant = spacecraft(kept, scenario.placement, result.placement)
        controller = law_controller(law, result.laws["LQR"].arrays, plant, config.dt)
        x0 = plant.state_from(euler123=[0.1, 0.1, 0.1])
        return simulate(plant, controller, config, n_cases=1, initial_state=x0).dataset

    nominal, aligned = (flown(m) for m in (modes, align_modes(flipped, modes)))
    # reversed, the modal feedback of the pair is positive: this LQR destabilises the spacecraft
    with pytest.raises(SimulationDiverged):
        flown(flipped)
    displacement = [str(n) for n in nominal.data_vars if "displacement_" in str(n)]
    for name in ["attitude", "torque", *displacement]:
        np.testing.assert_array_equal(aligned[name].values, nominal[name].values, err_msg=name)
